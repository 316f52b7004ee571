//! The NAO (`robots::nao`): the hand-written DH tables against the URDF (two independent
//! derivations), hand-checkable facts at q = 0, and the change of support foot.

use crate::common;

use nalgebra::{IsometryMatrix3, Rotation3, Translation3, Vector3};
use proptest::prelude::*;
use taskstack::human::Side;
use taskstack::model::Model;
use taskstack::robots::nao;

const URDF: &str = include_str!("../data/nao.urdf");
const TOL: f64 = 1e-9;

/// NAOqi's StandInit posture (radians), other variables 0.
const STAND_INIT: [(&str, f64); 16] = [
    ("LShoulderPitch", 1.4),
    ("LShoulderRoll", 0.3),
    ("LElbowYaw", -1.39),
    ("LElbowRoll", -1.0),
    ("LHipPitch", -0.35),
    ("LKneePitch", 0.7),
    ("LAnklePitch", -0.35),
    ("RHipPitch", -0.35),
    ("RKneePitch", 0.7),
    ("RAnklePitch", -0.35),
    ("RShoulderPitch", 1.4),
    ("RShoulderRoll", -0.3),
    ("RElbowYaw", 1.39),
    ("RElbowRoll", 1.0),
    ("HeadYaw", 0.0),
    ("HeadPitch", 0.0),
];

fn stand_init(model: &Model) -> Vec<f64> {
    let mut q = vec![0.0; model.nv()];
    for (name, value) in STAND_INIT {
        q[model.variable_index(name).unwrap()] = value;
    }
    q
}

/// Largest position (m), orientation (rad) and CoM (m) differences between two models over all
/// NAO named frames.
fn compare(a: &Model, b: &Model, q: &[f64]) -> (f64, f64, f64) {
    let (mut da, mut db) = (a.new_data(), b.new_data());
    a.forward_kinematics(&mut da, q).unwrap();
    b.forward_kinematics(&mut db, q).unwrap();
    let (mut pos, mut rot): (f64, f64) = (0.0, 0.0);
    for (name, _, _) in nao::FRAMES {
        let pa = da.frame_placement(a.frame_id(name).unwrap());
        let pb = db.frame_placement(b.frame_id(name).unwrap());
        pos = pos.max((pa.translation.vector - pb.translation.vector).norm());
        rot = rot.max(common::rotation_error(&pa.rotation, &pb.rotation));
    }
    let com = (a.com(&da).unwrap() - b.com(&db).unwrap()).norm();
    (pos, rot, com)
}

fn pairs() -> Vec<(&'static str, Model, Model)> {
    vec![
        (
            "r_sole",
            nao::rfoot(),
            nao::from_urdf_str(URDF, Some("r_sole")).unwrap(),
        ),
        (
            "l_sole",
            nao::lfoot(),
            nao::from_urdf_str(URDF, Some("l_sole")).unwrap(),
        ),
        (
            "torso",
            nao::torso(),
            nao::from_urdf_str(URDF, Some("torso")).unwrap(),
        ),
        // The URDF's own root is `base_link`, coincident with `torso` (fixed joint, identity).
        (
            "urdf root",
            nao::torso(),
            nao::from_urdf_str(URDF, None).unwrap(),
        ),
    ]
}

#[test]
fn variables_frames_and_mass_follow_the_contract() {
    for (_, dh, urdf) in pairs() {
        for model in [&dh, &urdf] {
            let names: Vec<&str> = model.variables().iter().map(|v| v.name.as_str()).collect();
            assert_eq!(names, nao::VARIABLES);
            assert_eq!(model.frames().len(), nao::FRAMES.len());
            // Sum of all URDF <mass> values (python over nao.urdf: 5.305402000100008).
            assert!(
                (model.total_mass() - 5.3054020001).abs() < 1e-12,
                "{}",
                model.total_mass()
            );
        }
        for (vd, vu) in dh.variables().iter().zip(urdf.variables()) {
            assert_eq!(
                (vd.lower, vd.upper, vd.velocity),
                (vu.lower, vu.upper, vu.velocity)
            );
        }
    }
}

#[test]
fn dh_and_urdf_agree_at_stand_init_and_zero() {
    for (root, dh, urdf) in pairs() {
        for q in [stand_init(&dh), vec![0.0; 23]] {
            let (pos, rot, com) = compare(&dh, &urdf, &q);
            assert!(
                pos < TOL && rot < TOL && com < TOL,
                "{root}: {pos:e} m, {rot:e} rad, com {com:e} m"
            );
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]
    #[test]
    fn dh_and_urdf_agree_at_random_q(u in proptest::collection::vec(0.0..1.0f64, 23)) {
        for (root, dh, urdf) in pairs() {
            let q = common::q_from_unit(&dh, &u);
            let (pos, rot, com) = compare(&dh, &urdf, &q);
            prop_assert!(pos < TOL && rot < TOL && com < TOL, "{}: {:e} m, {:e} rad, com {:e} m", root, pos, rot, com);
        }
    }

    #[test]
    fn rfoot_and_lfoot_give_the_same_relative_placements(u in proptest::collection::vec(0.0..1.0f64, 23)) {
        let (r, l) = (nao::rfoot(), nao::lfoot());
        let q = common::q_from_unit(&r, &u);
        let (mut dr, mut dl) = (r.new_data(), l.new_data());
        r.forward_kinematics(&mut dr, &q).unwrap();
        l.forward_kinematics(&mut dl, &q).unwrap();
        for (a, _, _) in nao::FRAMES {
            for (b, _, _) in nao::FRAMES {
                let rel = |m: &Model, d: &taskstack::model::ModelData| {
                    d.frame_placement(m.frame_id(a).unwrap()).inverse() * d.frame_placement(m.frame_id(b).unwrap())
                };
                let (x, y) = (rel(&r, &dr), rel(&l, &dl));
                prop_assert!((x.translation.vector - y.translation.vector).norm() < TOL, "{} → {}", a, b);
                prop_assert!(common::rotation_error(&x.rotation, &y.rotation) < TOL, "{} → {}", a, b);
            }
        }
    }

    #[test]
    fn switching_support_keeps_every_frame_in_place(
        u in proptest::collection::vec(0.0..1.0f64, 23),
        x in -1.0..1.0f64, y in -1.0..1.0f64, yaw in -3.0..3.0f64,
    ) {
        let (r, l) = (nao::rfoot(), nao::lfoot());
        let q = common::q_from_unit(&r, &u);
        let world_t_rsole = IsometryMatrix3::from_parts(
            Translation3::new(x, y, 0.0),
            Rotation3::from_axis_angle(&Vector3::z_axis(), yaw),
        );
        let (mut dr, mut dl) = (r.new_data(), l.new_data());
        r.forward_kinematics(&mut dr, &q).unwrap();
        l.forward_kinematics(&mut dl, &q).unwrap();
        let world_t_lsole = nao::switch_support(&r, &dr, &world_t_rsole, Side::Left).unwrap();
        // And back: the right sole lands where it started.
        let back = nao::switch_support(&l, &dl, &world_t_lsole, Side::Right).unwrap();
        prop_assert!((back.translation.vector - world_t_rsole.translation.vector).norm() < TOL);
        for (name, _, _) in nao::FRAMES {
            let a = r.placement_in_world(&dr, &world_t_rsole, r.frame_id(name).unwrap()).unwrap();
            let b = l.placement_in_world(&dl, &world_t_lsole, l.frame_id(name).unwrap()).unwrap();
            prop_assert!((a.translation.vector - b.translation.vector).norm() < TOL, "{}", name);
            prop_assert!(common::rotation_error(&a.rotation, &b.rotation) < TOL, "{}", name);
        }
    }
}

#[test]
fn hand_checkable_positions_at_zero_in_the_right_sole_frame() {
    let model = nao::rfoot();
    let mut data = model.new_data();
    model.forward_kinematics(&mut data, &[0.0; 23]).unwrap();
    let at = |name: &str| {
        data.frame_placement(model.frame_id(name).unwrap())
            .translation
            .vector
    };
    // Torso: HipOffsetY sideways; FootHeight + TibiaLength + ThighLength + HipOffsetZ up
    // = 0.04511 + 0.1029 + 0.100 + 0.085 = 0.33301.
    let torso = Vector3::new(0.0, 0.05, 0.33301);
    let expected = [
        ("r_sole", Vector3::zeros()),
        ("l_sole", Vector3::new(0.0, 0.1, 0.0)), // 2 × HipOffsetY
        ("r_ankle", Vector3::new(0.0, 0.0, 0.04511)),
        ("r_knee", Vector3::new(0.0, 0.0, 0.04511 + 0.1029)),
        ("r_hip", Vector3::new(0.0, 0.0, 0.24801)),
        ("l_hip", Vector3::new(0.0, 0.1, 0.24801)),
        ("r_toe", Vector3::new(0.05, 0.0, 0.0)),
        ("l_heel", Vector3::new(-0.05, 0.1, 0.0)),
        ("torso", torso),
        // NeckOffsetZ 0.1265 above the torso; gaze + (0.05871, 0, 0.06364).
        ("head", torso + Vector3::new(0.0, 0.0, 0.1265)),
        ("gaze", torso + Vector3::new(0.05871, 0.0, 0.1265 + 0.06364)),
        // Shoulder (0, ±ShoulderOffsetY 0.098, ShoulderOffsetZ 0.100) from the torso; arms straight
        // forward at q = 0: elbow + (UpperArmLength 0.105, ±ElbowOffsetY 0.015, 0), wrist
        // + LowerArmLength 0.05595, hand + (HandOffsetX 0.05775, 0, −HandOffsetZ 0.01231):
        // hand x = 0.105 + 0.05595 + 0.05775 = 0.2187, y = 0.05 ± (0.098 + 0.015) = 0.163 / −0.063,
        // z = 0.33301 + 0.100 − 0.01231 = 0.4207.
        ("l_shoulder", torso + Vector3::new(0.0, 0.098, 0.1)),
        ("l_elbow", torso + Vector3::new(0.105, 0.113, 0.1)),
        ("l_wrist", torso + Vector3::new(0.16095, 0.113, 0.1)),
        ("l_hand", Vector3::new(0.2187, 0.163, 0.4207)),
        ("r_hand", Vector3::new(0.2187, -0.063, 0.4207)),
    ];
    for (name, want) in expected {
        assert!(
            (at(name) - want).norm() < 1e-12,
            "{name}: {} vs {want}",
            at(name)
        );
    }
    // Every frame is axis-aligned at q = 0.
    for p in data.frame_placements() {
        assert!(common::rotation_error(&p.rotation, &Rotation3::identity()) < 1e-12);
    }
}

#[test]
fn hip_yaw_pitch_is_one_variable_driving_both_legs() {
    let model = nao::rfoot();
    let k = model.variable_index("LHipYawPitch").unwrap();
    let driven: Vec<&str> = model
        .joints()
        .iter()
        .filter(|j| j.variable == Some(k))
        .map(|j| j.name.as_str())
        .collect();
    assert_eq!(driven.len(), 2, "{driven:?}");
    assert!(model.variable_index("RHipYawPitch").is_err());
}

/// The stance point by hand: the left FSR rectangle spans x −30.25 … 70.25 mm and y −23.1 …
/// 29.9 mm, so its centre is (20.0, 3.4) mm; 15 mm from the inner edge (y = −23.1 mm) is
/// y = −8.1 mm; a margin past the centre gives the centre. The right foot is the mirror image.
#[test]
fn stance_point_keeps_the_margin_from_the_inner_edge() {
    let close =
        |a: [f64; 2], b: [f64; 2]| (a[0] - b[0]).abs() < 1e-12 && (a[1] - b[1]).abs() < 1e-12;
    assert!(close(
        nao::profile().sole_centre(Side::Left),
        [0.020, 0.0034]
    ));
    assert!(close(
        nao::profile().sole_centre(Side::Right),
        [0.020, -0.0034]
    ));
    assert!(close(
        nao::profile().stance_point(Side::Left, 0.015),
        [0.020, -0.0081]
    ));
    assert!(close(
        nao::profile().stance_point(Side::Right, 0.015),
        [0.020, 0.0081]
    ));
    assert!(close(
        nao::profile().stance_point(Side::Left, 0.04),
        [0.020, 0.0034]
    ));
    assert!(close(
        nao::profile().stance_point(Side::Right, 0.04),
        [0.020, -0.0034]
    ));
}
