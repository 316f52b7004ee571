//! A robot with a waist ([`BipedProfile::chest`], the G1's `torso_link` above its three waist
//! joints): the hands turn its upper body at the waist's yaw, with the chest upright on the
//! hips and the hips facing midway between the feet (Poubel et al.'s tables), or with the waist
//! out of the hands' IK (Koenemann et al.'s method). Checked on the postures the imitator
//! outputs, with the model's own forward kinematics.

use nalgebra::{Rotation3, Vector3};
use taskstack::human::HumanFrame;
use taskstack::imitation::config::ImitationMethod;
use taskstack::imitation::koenemann::KoenemannConfig;
use taskstack::imitation::phase::tables::{OrientationTarget, Task, TaskTables};
use taskstack::imitation::phase::{PhaseConfig, SupportPhase};
use taskstack::imitation::reference::support::SupportConfig;
use taskstack::imitation::{Imitator, ImitatorConfig};
use taskstack::io::clip::Clip;
use taskstack::robots::{BipedProfile, g1, nao};

/// CMU 05_12: a slow dance with the arms high and single supports.
const CLIP: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/tests/data/mocap/cmu_05_12_slow_dance_tendu_arms_high.bvh"
);

/// The orientation tasks of `profile`'s executable posture level in `phase`.
fn posture_orientations(profile: &BipedProfile, phase: SupportPhase) -> Vec<(String, String)> {
    let tables = TaskTables::executable(&PhaseConfig::default(), profile);
    let posture = (tables.table(phase).levels.iter())
        .find(|l| l.name == "posture")
        .expect("every executable table has a posture level");
    (posture.tasks.iter())
        .filter_map(|task| match task {
            Task::Orientation { frame, target } => {
                let kind = match target {
                    OrientationTarget::Facing { .. } => "facing",
                    OrientationTarget::Upright { .. } => "upright",
                    _ => "other",
                };
                Some((frame.clone(), kind.to_owned()))
            }
            _ => None,
        })
        .collect()
}

#[test]
fn the_g1s_tables_hold_its_chest_upright_and_its_hips_facing_between_its_feet() {
    let pair = |frame: &str, kind: &str| (frame.to_owned(), kind.to_owned());
    for phase in SupportPhase::ALL {
        assert_eq!(
            posture_orientations(&g1::profile(), phase),
            vec![pair("pelvis", "facing"), pair("torso_link", "upright")],
            "{phase}"
        );
        // The NAO's torso is rigid with its hips: its heading stays free.
        assert_eq!(
            posture_orientations(&nao::profile(), phase),
            vec![pair("torso", "upright")],
            "{phase}"
        );
    }
}

/// Over the clip imitated by `profile` with `method`, per frame: the angle (rad) between the
/// chest's and the pelvis's z axes, the pelvis heading's distance (rad) from midway between the
/// soles' headings, and the largest distance (rad) of a waist joint from the standing posture.
fn waist_motion(profile: BipedProfile, method: ImitationMethod) -> Vec<[f64; 3]> {
    let mut clip = Clip::open(CLIP).unwrap();
    let config = ImitatorConfig {
        support: SupportConfig::for_capture(clip.capture()),
        method,
        ..ImitatorConfig::default()
    };
    let stand = profile.stand.clone();
    let mut imitator = Imitator::new(profile.clone(), config).unwrap();
    let waist: Vec<usize> = (imitator.variable_names().enumerate())
        .filter(|(_, name)| name.starts_with("waist_"))
        .map(|(i, _)| i)
        .collect();
    assert_eq!(waist.len(), 3);
    let mut frame = HumanFrame::new(0.0);
    let mut out = Vec::new();
    while clip.read_frame(&mut frame).unwrap() {
        let robot = imitator.step(&frame).unwrap();
        let model = profile.model(robot.root);
        let mut data = model.new_data();
        model.forward_kinematics(&mut data, &robot.q).unwrap();
        let rotation = |name: &str| data.frame_placement(model.frame_id(name).unwrap()).rotation;
        let heading = |r: Rotation3<f64>| {
            let x = r * Vector3::x();
            x.y.atan2(x.x)
        };
        let [pelvis, chest] = [rotation("pelvis"), rotation("torso_link")];
        let tilt = (chest * Vector3::z()).angle(&(pelvis * Vector3::z()));
        let middle = 0.5 * (heading(rotation("left_sole")) + heading(rotation("right_sole")));
        let turn = (heading(pelvis) - middle).abs();
        let waist_moved = (waist.iter())
            .map(|&i| (robot.q[i] - stand[i]).abs())
            .fold(0.0, f64::max);
        out.push([tilt, turn, waist_moved]);
    }
    out
}

/// The largest value of column `k` over the frames.
fn largest(frames: &[[f64; 3]], k: usize) -> f64 {
    frames.iter().map(|f| f[k]).fold(0.0, f64::max)
}

#[test]
fn poubels_tables_turn_the_g1s_upper_body_at_its_waist_only() {
    let held = waist_motion(g1::profile(), ImitationMethod::default());
    let (tilt, turn) = (largest(&held, 0), largest(&held, 1));
    // The upright task trails the waist's fast yaw by a few frames (its step is bounded).
    assert!(tilt < 0.08, "the chest leaned {tilt} rad off the hips");
    assert!(
        turn < 0.001,
        "the hips turned {turn} rad off the feet's middle"
    );
    // The waist still turns the upper body about the vertical.
    assert!(largest(&held, 2) > 0.1, "the waist never turned");

    // Without a chest the hand tasks swing the waist and turn the hips on the legs.
    let free = BipedProfile {
        chest: None,
        ..g1::profile()
    };
    let swung = waist_motion(free, ImitationMethod::default());
    assert!(largest(&swung, 0) > 0.2, "{}", largest(&swung, 0));
    assert!(largest(&swung, 1) > 0.1, "{}", largest(&swung, 1));
}

#[test]
fn koenemanns_method_keeps_the_g1s_waist_out_of_the_hands_ik() {
    let koenemann = || ImitationMethod::Koenemann(KoenemannConfig::default());
    let held = waist_motion(g1::profile(), koenemann());
    assert!(largest(&held, 2) < 1e-12, "{}", largest(&held, 2));

    let free = BipedProfile {
        chest: None,
        ..g1::profile()
    };
    let swung = waist_motion(free, koenemann());
    assert!(largest(&swung, 2) > 0.05, "{}", largest(&swung, 2));
}
