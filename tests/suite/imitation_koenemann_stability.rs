//! Koenemann et al.'s stabilized postures are statically stable by construction: over random
//! human motion (a real clip's frames with random arm, pelvis and foot displacements, feet
//! lifted at random so the support changes), the CoM's ground projection is inside the support
//! polygon of the support the method reports at every frame, and no joint leaves its limits.
//!
//! The polygon is built here from the profile's sole outlines and the frame's sole placements:
//! one sole in single support and while the other foot is coming down, the convex hull of both
//! otherwise.

use nalgebra::{Point3, Vector2, Vector3};
use proptest::prelude::*;
use taskstack::human::Side;
use taskstack::human::{HumanFrame, HumanJoint};
use taskstack::imitation::config::ImitationMethod;
use taskstack::imitation::koenemann::KoenemannConfig;
use taskstack::imitation::output::RobotFrame;
use taskstack::imitation::phase::SupportPhase;
use taskstack::imitation::reference::support::SupportConfig;
use taskstack::imitation::{Imitator, ImitatorConfig};
use taskstack::io::clip::Clip;
use taskstack::robots::{BipedProfile, nao};

/// Frames of a clip with both single and double support.
fn clip_frames() -> (Vec<HumanFrame>, SupportConfig) {
    let path = format!(
        "{}/tests/data/mocap/cmu_05_02_stand_arm_gestures_turn_single_leg.bvh",
        env!("CARGO_MANIFEST_DIR")
    );
    let mut clip = Clip::open(path).unwrap();
    let support = SupportConfig::for_capture(clip.capture());
    let mut frames = Vec::new();
    let mut frame = HumanFrame::new(0.0);
    while clip.read_frame(&mut frame).unwrap() {
        frames.push(frame);
    }
    (frames, support)
}

/// The soles the method stands on in `phase`.
fn support_soles(phase: SupportPhase) -> &'static [Side] {
    match phase {
        SupportPhase::Left | SupportPhase::LeftToDouble(_) => &[Side::Left],
        SupportPhase::Right | SupportPhase::RightToDouble(_) => &[Side::Right],
        SupportPhase::Double | SupportPhase::DoubleToLeft(_) | SupportPhase::DoubleToRight(_) => {
            &[Side::Left, Side::Right]
        }
    }
}

/// Signed distance (m, > 0 inside) of `p` to the convex hull of `points` (Andrew's monotone
/// chain, then the smallest distance to an edge line).
fn hull_margin(mut points: Vec<Vector2<f64>>, p: Vector2<f64>) -> f64 {
    points.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    let cross = |o: Vector2<f64>, a: Vector2<f64>, b: Vector2<f64>| (a - o).perp(&(b - o));
    let mut hull: Vec<Vector2<f64>> = Vec::new();
    for pass in 0..2 {
        let start = hull.len();
        let ordered: Vec<_> = if pass == 0 {
            points.clone()
        } else {
            points.iter().rev().copied().collect()
        };
        for q in ordered {
            while hull.len() >= start + 2
                && cross(hull[hull.len() - 2], hull[hull.len() - 1], q) <= 0.0
            {
                hull.pop();
            }
            hull.push(q);
        }
        hull.pop();
    }
    (0..hull.len())
        .map(|i| {
            let (a, b) = (hull[i], hull[(i + 1) % hull.len()]);
            (b - a).perp(&(p - a)) / (b - a).norm()
        })
        .fold(f64::INFINITY, f64::min)
}

fn com_margin(profile: &BipedProfile, r: &RobotFrame) -> f64 {
    let mut points = Vec::new();
    for &side in support_soles(r.phase) {
        let sole = match side {
            Side::Left => &r.left_sole,
            Side::Right => &r.right_sole,
        };
        for &[x, y] in &profile.foot(side).outline {
            points.push(sole.transform_point(&Point3::new(x, y, 0.0)).xy().coords);
        }
    }
    hull_margin(points, r.com.xy())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 12, ..ProptestConfig::default() })]

    #[test]
    fn the_com_is_over_the_support_the_method_reports(
        start in 0usize..700,
        moves in prop::collection::vec(
            (prop::array::uniform3(-0.15f64..0.15), prop::array::uniform2(-0.05f64..0.05), 0usize..4),
            12,
        ),
    ) {
        let (frames, support) = clip_frames();
        let profile = nao::profile();
        let config = ImitatorConfig {
            support,
            method: ImitationMethod::Koenemann(KoenemannConfig::default()),
            ..ImitatorConfig::default()
        };
        let mut imitator = Imitator::new(profile.clone(), config).unwrap();
        let bounds = imitator.bounds().clone();
        // 12 segments of a quarter second: the hands moved, the pelvis shifted, a foot lifted
        // (1: left, 2: right) or not.
        for k in 0..12 * 30 {
            let (hands, pelvis, lift) = moves[k / 30];
            let mut frame = frames[(start + k).min(frames.len() - 1)];
            frame.time = k as f64 / 120.0;
            let shift = Vector3::new(pelvis[0], pelvis[1], 0.0);
            for (joint, p) in frame.joints().collect::<Vec<_>>() {
                let Some(mut p) = p else { continue };
                use HumanJoint as J;
                if matches!(joint, J::LHand | J::RHand | J::LWrist | J::RWrist) {
                    p += Vector3::from(hands);
                }
                let foot = matches!(joint, J::LAnkle | J::LToe | J::RAnkle | J::RToe);
                if !foot {
                    p += shift;
                }
                let lifted = match lift {
                    1 => matches!(joint, J::LAnkle | J::LToe),
                    2 => matches!(joint, J::RAnkle | J::RToe),
                    _ => false,
                };
                if lifted {
                    p.z += 0.15;
                }
                frame.set(joint, Some(p));
            }
            let r = imitator.step(&frame).unwrap();
            let margin = com_margin(&profile, r);
            prop_assert!(margin >= -1e-4, "t = {}: {:?}, CoM margin {margin} m", r.time, r.phase);
            for (i, &q) in r.q.iter().enumerate() {
                prop_assert!(q >= bounds.lower()[i] && q <= bounds.upper()[i], "joint {i} at {q}");
            }
        }
    }
}

/// A human who stops moving: after the Kinect gesture clip, its last frame held for 2 s (what
/// the CLI's hold does). The hands reach their targets and their speed falls to zero; every
/// frame must still give a finite posture (a zero step over a zero distance once gave the arms'
/// IK a NaN target).
#[test]
fn a_human_who_stops_moving_leaves_the_robot_standing_still() {
    let path = format!(
        "{}/tests/data/mocap/kinect2_labanotation_ges02_balancinghands.csv",
        env!("CARGO_MANIFEST_DIR")
    );
    let mut clip = Clip::open(path).unwrap();
    let config = ImitatorConfig {
        method: ImitationMethod::Koenemann(KoenemannConfig::default()),
        support: SupportConfig::for_capture(clip.capture()),
        ..ImitatorConfig::default()
    };
    let mut imitator = Imitator::new(nao::profile(), config).unwrap();
    let mut frame = HumanFrame::new(0.0);
    while clip.read_frame(&mut frame).unwrap() {
        imitator.step(&frame).unwrap();
    }
    let end = frame.time;
    let mut last = Vec::new();
    for k in 1..=240 {
        frame.time = end + k as f64 / 120.0;
        let q = &imitator.step(&frame).unwrap().q;
        assert!(q.iter().all(|x| x.is_finite()), "frame {k}");
        if k == 120 {
            last = q.clone();
        }
    }
    let q = &imitator.step(&frame).unwrap().q;
    let moved = q
        .iter()
        .zip(&last)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(
        moved < 0.05,
        "still moving {moved} rad in the second second"
    );
}
