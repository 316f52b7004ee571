//! Forward kinematics, Jacobians and CoM of `model`: finite differences, a hand-checked planar
//! arm, re-rooting consistency, and the typed errors of the algorithms.

use crate::common;

use faer::Mat;
use nalgebra::Vector3;
use proptest::prelude::*;
use taskstack::model::{FrameId, Model, ModelError, UrdfOptions};
use taskstack::robots::nao;

const TREE: &str = include_str!("../data/tree.urdf");
const PLANAR: &str = include_str!("../data/planar3r.toml");
/// Jacobians vs central differences (step 1e-6).
const FD_TOL: f64 = 1e-6;

fn tree(root: Option<&str>) -> Model {
    let options = UrdfOptions {
        root_link: root.map(str::to_owned),
        ..UrdfOptions::default()
    };
    Model::from_urdf_str(TREE, &options).unwrap()
}

fn all_frames_error(model: &Model, q: &[f64]) -> f64 {
    let offset = Vector3::new(0.03, -0.02, 0.05);
    let mut worst: f64 = 0.0;
    for f in 0..model.frames().len() {
        let id = model.frame_id(&model.frames()[f].name).unwrap();
        worst = worst.max(common::frame_jacobian_error(model, q, id, &offset));
    }
    worst.max(common::com_jacobian_error(model, q))
}

/// Largest difference (kg·m²/s) between `A_O v` and the momentum by differences, over a few
/// velocities of unit entries' scale.
fn momentum_jacobian_error(model: &Model, q: &[f64]) -> f64 {
    let mut data = model.new_data();
    model.forward_kinematics(&mut data, q).unwrap();
    let mut a = Mat::<f64>::zeros(3, model.nv());
    model.angular_momentum_jacobian(&data, a.as_mut()).unwrap();
    let mut worst: f64 = 0.0;
    for k in 0..3 {
        let v: Vec<f64> = (0..model.nv())
            .map(|j| ((j * 7 + k * 3) % 5) as f64 * 0.4 - 0.8)
            .collect();
        let expected = common::momentum_by_differences(model, q, &v);
        for r in 0..3 {
            let got: f64 = (0..model.nv()).map(|j| a[(r, j)] * v[j]).sum();
            worst = worst.max((got - expected[r]).abs());
        }
    }
    worst
}

#[test]
fn angular_momentum_jacobian_matches_the_links_motion() {
    // The tree has inertias, a prismatic joint, mimics and a fixed tool; the G1's URDF its
    // real inertias; the NAO's DH model point masses.
    let models = [tree(None), taskstack::robots::g1::left_sole(), nao::rfoot()];
    for model in models {
        assert!(model.links().iter().any(|l| l.mass > 0.0));
        for u in [0.2, 0.5, 0.8] {
            let q = common::q_from_unit(&model, &vec![u; model.nv()]);
            let error = momentum_jacobian_error(&model, &q);
            assert!(error < 1e-6, "momentum Jacobian off by {error} kg·m²/s");
        }
    }
}

/// Per variable of `model`: `Σ |μ| ℓ` over its joints' levers to a point within `extent` of
/// `frame` (m per rad or per m): what bounds the point's speed per unit of the variable.
fn variable_levers(model: &Model, frame: FrameId, extent: f64) -> Vec<f64> {
    let mut out = vec![0.0; model.nv()];
    let levers = model.levers(frame, extent).unwrap();
    for (joint, lever) in model.joints().iter().zip(levers) {
        if let (Some(v), Some(l)) = (joint.variable, lever) {
            out[v] += joint.multiplier.abs() * l;
        }
    }
    out
}

#[test]
fn planar_arm_levers_by_hand() {
    let model = Model::from_dh_str(PLANAR, "planar3r.toml").unwrap();
    let tip = model.frame_id("tip").unwrap();
    // Below joint 3 the last link (0.1 m), below joint 2 also the middle one (0.2 m), below
    // joint 1 the whole arm (0.6 m); a point within 0.05 m of the tip adds 0.05.
    let levers = model.levers(tip, 0.05).unwrap();
    let expected = [0.65, 0.35, 0.15];
    for (got, want) in levers.iter().zip(expected) {
        assert!((got.unwrap() - want).abs() < 1e-15, "{levers:?}");
    }
    // Stretched (q = 0), the tip moves at the whole arm's length per radian of joint 1: the
    // bound is reached.
    let mut data = model.new_data();
    model.forward_kinematics(&mut data, &[0.0; 3]).unwrap();
    let mut j = Mat::<f64>::zeros(3, 3);
    (model.point_jacobian(&data, tip, &Vector3::zeros(), j.as_mut())).unwrap();
    let speed = (j[(0, 0)].powi(2) + j[(1, 0)].powi(2)).sqrt();
    assert!((speed - 0.6).abs() < 1e-15);
    // A frame of another model is refused.
    let foreign = nao::rfoot().frame_id("l_sole").unwrap();
    assert!(matches!(
        model.levers(foreign, 0.0),
        Err(ModelError::FrameOutOfRange(_))
    ));
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(16))]
    #[test]
    fn levers_bound_every_points_speed(
        u in proptest::collection::vec(0.0..1.0f64, 29),
        offset in proptest::collection::vec(-1.0..1.0f64, 3),
    ) {
        // A prismatic joint, mimics and a fixed tool (the tree, also re-rooted at a leaf), the
        // NAO's coupled hips, the G1's URDF.
        let models = [tree(None), tree(Some("hand2")), nao::rfoot(), taskstack::robots::g1::left_sole()];
        let extent = 0.05;
        let offset = Vector3::new(offset[0], offset[1], offset[2]) * (extent / 3f64.sqrt());
        for model in models {
            let q = common::q_from_unit(&model, &u[..model.nv()]);
            let mut data = model.new_data();
            model.forward_kinematics(&mut data, &q).unwrap();
            let mut j = Mat::<f64>::zeros(3, model.nv());
            for f in model.frames() {
                let id = model.frame_id(&f.name).unwrap();
                model.point_jacobian(&data, id, &offset, j.as_mut()).unwrap();
                let bound = variable_levers(&model, id, extent);
                for (v, b) in bound.iter().enumerate() {
                    let speed = (0..3).map(|r| j[(r, v)].powi(2)).sum::<f64>().sqrt();
                    prop_assert!(speed <= b + 1e-12, "{} {} variable {v}: {speed} > {b}", model.name(), f.name);
                }
            }
        }
    }

    #[test]
    fn nao_jacobians_match_finite_differences(u in proptest::collection::vec(0.0..1.0f64, 23)) {
        for model in [nao::rfoot(), nao::lfoot()] {
            let q = common::q_from_unit(&model, &u);
            let err = all_frames_error(&model, &q);
            prop_assert!(err < FD_TOL, "{}: {:e}", model.name(), err);
        }
    }

    #[test]
    fn tree_jacobians_match_finite_differences(u in proptest::collection::vec(0.0..1.0f64, 4)) {
        // Rooted at its URDF root, at the leaf behind the fixed joint, and at the other leaf.
        for root in [None, Some("tool"), Some("hand2")] {
            let model = tree(root);
            let q = common::q_from_unit(&model, &u);
            let err = all_frames_error(&model, &q);
            prop_assert!(err < FD_TOL, "{:?}: {:e}", root, err);
        }
    }

    #[test]
    fn rerooted_tree_keeps_relative_placements_and_com(u in proptest::collection::vec(0.0..1.0f64, 4)) {
        let original = tree(None);
        let q = common::q_from_unit(&original, &u);
        let mut d0 = original.new_data();
        original.forward_kinematics(&mut d0, &q).unwrap();
        for root in ["tool", "hand2", "link2"] {
            let model = tree(Some(root));
            let mut d = model.new_data();
            model.forward_kinematics(&mut d, &q).unwrap();
            // The new root's placement in the original base frame maps every frame and the CoM.
            let base_t_root = d0.frame_placement(original.frame_id(root).unwrap());
            for f in original.frames() {
                let a = d0.frame_placement(original.frame_id(&f.name).unwrap());
                let b = base_t_root * d.frame_placement(model.frame_id(&f.name).unwrap());
                prop_assert!((a.translation.vector - b.translation.vector).norm() < 1e-12, "{} {}", root, f.name);
                prop_assert!(common::rotation_error(&a.rotation, &b.rotation) < 1e-12, "{} {}", root, f.name);
            }
            let com0 = original.com(&d0).unwrap();
            let com = base_t_root.transform_point(&model.com(&d).unwrap().into()).coords;
            prop_assert!((com0 - com).norm() < 1e-12, "{}", root);
        }
    }
}

#[test]
fn tree_structure_mimic_prismatic_fixed() {
    let model = tree(None);
    let names: Vec<&str> = model.variables().iter().map(|v| v.name.as_str()).collect();
    assert_eq!(names, ["j1", "slide", "j3", "j5"]);
    // `tool` (fixed) is folded into `link4`: 8 URDF links, 7 bodies.
    assert_eq!(model.links().len(), 7);
    let link4 = &model.links()[model.link_index("link4").unwrap()];
    assert!((link4.mass - 0.35).abs() < 1e-15);
    // m4 = −0.5·j1 + 0.1; m6 = 2·j3 − 0.2.
    let m4 = model.joints().iter().find(|j| j.name == "m4").unwrap();
    assert_eq!(
        (m4.variable, m4.multiplier, m4.offset),
        (Some(0), -0.5, 0.1)
    );
    let m6 = model.joints().iter().find(|j| j.name == "m6").unwrap();
    assert_eq!(
        (m6.variable, m6.multiplier, m6.offset),
        (Some(2), 2.0, -0.2)
    );
    // The continuous joint has no limits.
    assert_eq!(model.variables()[3].lower, f64::NEG_INFINITY);
    // Re-rooted at `tool`: the path joints are reversed (multiplier and offset negated).
    let rerooted = tree(Some("tool"));
    let m4 = rerooted.joints().iter().find(|j| j.name == "m4").unwrap();
    assert_eq!((m4.multiplier, m4.offset), (0.5, -0.1));
    assert_eq!(rerooted.links()[0].name, "tool");
    assert!((rerooted.total_mass() - model.total_mass()).abs() < 1e-15);
}

#[test]
fn planar_arm_matches_hand_calculation() {
    let model = Model::from_dh_str(PLANAR, "planar3r.toml").unwrap();
    let q = [0.3, -0.7, 1.1];
    let mut data = model.new_data();
    model.forward_kinematics(&mut data, &q).unwrap();
    let (a1, a12, a123) = (q[0], q[0] + q[1], q[0] + q[1] + q[2]);
    // tip = 0.3·(c1, s1) + 0.2·(c12, s12) + 0.1·(c123, s123)
    let tip = Vector3::new(
        0.3 * a1.cos() + 0.2 * a12.cos() + 0.1 * a123.cos(),
        0.3 * a1.sin() + 0.2 * a12.sin() + 0.1 * a123.sin(),
        0.0,
    );
    let got = data.frame_placement(model.frame_id("tip").unwrap());
    assert!((got.translation.vector - tip).norm() < 1e-15);
    assert!((got.rotation.angle() - a123).abs() < 1e-12);
    // CoM: masses 1, 2, 1 kg at mid-links: (1·0.15·u1 + 2·(0.3·u1 + 0.1·u12) + 1·(0.3·u1 + 0.2·u12 + 0.05·u123)) / 4
    let u = |a: f64| Vector3::new(a.cos(), a.sin(), 0.0);
    let com = (u(a1) * (0.15 + 0.6 + 0.3) + u(a12) * (0.2 + 0.2) + u(a123) * 0.05) / 4.0;
    assert!((model.com(&data).unwrap() - com).norm() < 1e-15);
    // Jacobian of the tip, column 3: z × (tip − joint 3) = 0.1·(−s123, c123, 0).
    let mut j = Mat::<f64>::zeros(3, 3);
    let id = model.frame_id("tip").unwrap();
    model
        .point_jacobian(&data, id, &Vector3::zeros(), j.as_mut())
        .unwrap();
    assert!((j[(0, 2)] + 0.1 * a123.sin()).abs() < 1e-15);
    assert!((j[(1, 2)] - 0.1 * a123.cos()).abs() < 1e-15);
}

#[test]
fn algorithm_errors_are_typed() {
    let model = nao::rfoot();
    let mut data = model.new_data();
    let hand = model.frame_id("l_hand").unwrap();
    let zero = Vector3::zeros();
    let mut j = Mat::<f64>::zeros(3, 23);
    assert_eq!(
        model.point_jacobian(&data, hand, &zero, j.as_mut()),
        Err(ModelError::KinematicsNotComputed)
    );
    assert!(matches!(
        model.forward_kinematics(&mut data, &[0.0; 22]),
        Err(ModelError::WrongQLength {
            expected: 23,
            got: 22
        })
    ));
    let mut q = [0.0; 23];
    q[4] = f64::NAN;
    assert!(matches!(
        model.forward_kinematics(&mut data, &q),
        Err(ModelError::NonFiniteQ { index: 4, ref variable, .. }) if variable == "LElbowYaw"
    ));
    model.forward_kinematics(&mut data, &[0.0; 23]).unwrap();
    let mut wrong = Mat::<f64>::zeros(3, 22);
    assert!(matches!(
        model.point_jacobian(&data, hand, &zero, wrong.as_mut()),
        Err(ModelError::OutputShape {
            expected_rows: 3,
            expected_cols: 23,
            rows: 3,
            cols: 22
        })
    ));
    assert!(matches!(
        model.com_jacobian_rows(&data, 2, j.as_mut()),
        Err(ModelError::OutputShape {
            expected_rows: 2,
            ..
        })
    ));
    assert_eq!(
        model.frame_id("l_foot_typo"),
        Err(ModelError::UnknownFrame("l_foot_typo".into()))
    );
    assert_eq!(
        model.variable_index("RHipYawPitch"),
        Err(ModelError::UnknownVariable("RHipYawPitch".into()))
    );
    assert!(matches!(
        model.point_jacobian(
            &data,
            hand,
            &Vector3::new(f64::INFINITY, 0.0, 0.0),
            j.as_mut()
        ),
        Err(ModelError::NonFiniteOffset(_))
    ));
    let other = Model::from_dh_str(PLANAR, "planar3r.toml").unwrap();
    assert_eq!(other.com(&data), Err(ModelError::ForeignData));
    let massless = tree_without_mass();
    let mut d = massless.new_data();
    massless.forward_kinematics(&mut d, &[0.0; 1]).unwrap();
    assert_eq!(massless.com(&d), Err(ModelError::NoMass));
}

fn tree_without_mass() -> Model {
    let urdf = r#"<robot name="m"><link name="a"/><link name="b"/>
        <joint name="j" type="revolute"><parent link="a"/><child link="b"/><axis xyz="0 0 1"/>
        <limit lower="-1" upper="1" effort="1" velocity="1"/></joint></robot>"#;
    Model::from_urdf_str(urdf, &UrdfOptions::default()).unwrap()
}

#[test]
fn model_is_shareable_between_threads() {
    fn shareable<T: Send + Sync>(_: &T) -> bool {
        true
    }
    let model = nao::rfoot();
    assert!(shareable(&model) && shareable(&model.new_data()));
    // And actually used from two threads at once.
    let heights: Vec<f64> = std::thread::scope(|s| {
        let handles: Vec<_> = [0.0, 0.5]
            .map(|knee| {
                let model = &model;
                s.spawn(move || {
                    let mut data = model.new_data();
                    let mut q = vec![0.0; 23];
                    q[model.variable_index("RKneePitch").unwrap()] = knee;
                    model.forward_kinematics(&mut data, &q).unwrap();
                    data.frame_placement(model.frame_id("torso").unwrap())
                        .translation
                        .z
                })
            })
            .into();
        handles.into_iter().map(|h| h.join().unwrap()).collect()
    });
    // A bent knee lowers the torso.
    assert!((heights[0] - 0.33301).abs() < 1e-12 && heights[1] < heights[0]);
}
