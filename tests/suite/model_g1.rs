//! The Unitree G1 from its URDF (`robots::g1`): forward kinematics against the URDF chain composed
//! by hand in the test, Jacobians against finite differences, mass against the URDF's links.

use faer::Mat;
use nalgebra::{IsometryMatrix3, Rotation3, Translation3, Unit, Vector3};
use taskstack::model::{Model, UrdfError};
use taskstack::robots::g1;

/// `ᵖT_c(q)` of one URDF joint: origin, then rotation by `q` about the axis (all G1 joints are
/// revolute or fixed).
fn joint_transform(robot: &urdf_rs::Robot, name: &str, q: f64) -> IsometryMatrix3<f64> {
    let j = robot.joints.iter().find(|j| j.name == name).unwrap();
    let [x, y, z] = j.origin.xyz.0;
    let [r, p, w] = j.origin.rpy.0;
    let origin = IsometryMatrix3::from_parts(
        Translation3::new(x, y, z),
        Rotation3::from_euler_angles(r, p, w),
    );
    let axis = Unit::new_normalize(Vector3::from(j.axis.xyz.0));
    origin
        * IsometryMatrix3::from_parts(
            Translation3::identity(),
            Rotation3::from_axis_angle(&axis, q),
        )
}

/// `ᵖᵉˡᵛⁱˢT_x(q)` along a chain of joints from the pelvis, `q` indexed as [`g1::VARIABLES`]
/// (fixed joints at 0).
fn chain(robot: &urdf_rs::Robot, joints: &[&str], q: &[f64]) -> IsometryMatrix3<f64> {
    joints.iter().fold(IsometryMatrix3::identity(), |t, name| {
        let value = g1::VARIABLES
            .iter()
            .position(|v| v == name)
            .map_or(0.0, |k| q[k]);
        t * joint_transform(robot, name, value)
    })
}

fn as_str(names: &[String]) -> Vec<&str> {
    names.iter().map(String::as_str).collect()
}

fn leg(side: &str) -> Vec<String> {
    [
        "hip_pitch",
        "hip_roll",
        "hip_yaw",
        "knee",
        "ankle_pitch",
        "ankle_roll",
    ]
    .iter()
    .map(|j| format!("{side}_{j}_joint"))
    .collect()
}

/// A few postures: zero, and deterministic pseudo-random ones inside the limits.
fn postures(model: &Model) -> Vec<Vec<f64>> {
    let mut out = vec![vec![0.0; model.nv()]];
    for seed in 1..4 {
        out.push(
            model
                .variables()
                .iter()
                .enumerate()
                .map(|(k, v)| {
                    let s = ((seed * 7919 + k * 104_729) % 1000) as f64 / 1000.0;
                    let (lo, hi) = (v.lower.max(-1.0), v.upper.min(1.0));
                    lo + s * (hi - lo)
                })
                .collect(),
        );
    }
    out
}

#[test]
fn the_left_sole_and_hand_match_the_urdf_chain_composed_by_hand() {
    let robot = urdf_rs::read_from_string(g1::URDF).unwrap();
    let model = g1::right_sole();
    assert_eq!(model.nv(), 29);
    let mut data = model.new_data();
    let sole = IsometryMatrix3::translation(0.0, 0.0, -g1::SOLE_DEPTH);
    let (left, right) = (leg("left"), leg("right"));
    let hand: Vec<&str> = [
        "waist_yaw_joint",
        "waist_roll_joint",
        "waist_pitch_joint",
        "right_shoulder_pitch_joint",
        "right_shoulder_roll_joint",
        "right_shoulder_yaw_joint",
        "right_elbow_joint",
        "right_wrist_roll_joint",
        "right_wrist_pitch_joint",
        "right_wrist_yaw_joint",
        "right_hand_palm_joint",
    ]
    .to_vec();
    for q in postures(&model) {
        model.forward_kinematics(&mut data, &q).unwrap();
        let pelvis_t_right = chain(&robot, &as_str(&right), &q) * sole;
        let right_t_pelvis = pelvis_t_right.inverse();
        let expected = [
            (
                "left_sole",
                right_t_pelvis * chain(&robot, &as_str(&left), &q) * sole,
            ),
            (
                "right_rubber_hand",
                right_t_pelvis * chain(&robot, &hand, &q),
            ),
        ];
        for (frame, want) in expected {
            let got = data.frame_placement(model.frame_id(frame).unwrap());
            assert!(
                (got.translation.vector - want.translation.vector).norm() < 1e-12,
                "{frame} at {q:?}: {got} vs {want}"
            );
            assert!((got.rotation.matrix() - want.rotation.matrix()).norm() < 1e-12);
        }
    }
}

#[test]
fn rooted_at_either_sole_the_other_mirrors_at_zero() {
    let at_zero = |model: &Model, frame: &str| {
        let mut data = model.new_data();
        model
            .forward_kinematics(&mut data, &vec![0.0; model.nv()])
            .unwrap();
        data.frame_placement(model.frame_id(frame).unwrap())
            .translation
            .vector
    };
    let left_in_right = at_zero(&g1::right_sole(), "left_sole");
    let right_in_left = at_zero(&g1::left_sole(), "right_sole");
    // The lateral offsets of one leg's joint origins, summed by hand (the pitch rotations of
    // the hip roll and knee origins do not move y): hip pitch 0.064452 + hip roll 0.052 + knee
    // 0.0021489 − ankle pitch 0.000094445 = 0.118506455 m; the feet are twice that apart.
    assert!(
        (left_in_right.y - 2.0 * 0.118506455).abs() < 1e-9,
        "{left_in_right}"
    );
    assert!(left_in_right.z.abs() < 1e-12 && left_in_right.x.abs() < 1e-9);
    assert!((right_in_left + left_in_right).norm() < 1e-12);
}

#[test]
fn mass_is_the_urdf_links_mass() {
    let robot = urdf_rs::read_from_string(g1::URDF).unwrap();
    let sum: f64 = robot.links.iter().map(|l| l.inertial.mass.value).sum();
    for model in [g1::left_sole(), g1::right_sole(), g1::pelvis()] {
        assert!((model.total_mass() - sum).abs() < 1e-9);
    }
}

/// Central differences of `f` at `q` along each variable.
fn finite_difference(
    model: &Model,
    q: &[f64],
    f: impl Fn(&taskstack::model::ModelData) -> Vector3<f64>,
) -> Mat<f64> {
    let h = 1e-6;
    let mut data = model.new_data();
    let mut out = Mat::<f64>::zeros(3, model.nv());
    for k in 0..model.nv() {
        let mut qk = q.to_vec();
        qk[k] += h;
        model.forward_kinematics(&mut data, &qk).unwrap();
        let plus = f(&data);
        qk[k] -= 2.0 * h;
        model.forward_kinematics(&mut data, &qk).unwrap();
        let minus = f(&data);
        for r in 0..3 {
            out[(r, k)] = (plus[r] - minus[r]) / (2.0 * h);
        }
    }
    out
}

#[test]
fn hand_and_com_jacobians_match_finite_differences() {
    for model in [g1::left_sole(), g1::right_sole()] {
        let hand = model.frame_id("left_rubber_hand").unwrap();
        let offset = Vector3::new(0.05, 0.0, 0.0);
        for q in postures(&model) {
            let mut data = model.new_data();
            model.forward_kinematics(&mut data, &q).unwrap();
            let mut jacobian = Mat::<f64>::zeros(3, model.nv());
            model
                .point_jacobian(&data, hand, &offset, jacobian.as_mut())
                .unwrap();
            let fd = finite_difference(&model, &q, |d| {
                model.point_position(d, hand, &offset).unwrap()
            });
            assert!((&jacobian - &fd).norm_max() < 1e-7);
            model.com_jacobian(&data, jacobian.as_mut()).unwrap();
            let fd = finite_difference(&model, &q, |d| model.com(d).unwrap());
            assert!((&jacobian - &fd).norm_max() < 1e-7);
        }
    }
}

#[test]
fn a_published_free_base_loads_and_bad_text_is_refused() {
    let with_free_base = g1::URDF
        .replace(
            "<!-- <link name=\"world\"></link>",
            "<link name=\"world\"></link>",
        )
        .replace("</joint> -->", "</joint>");
    assert_ne!(with_free_base, g1::URDF);
    let model = g1::from_urdf_str(&with_free_base, Some("right_sole")).unwrap();
    assert_eq!(model, g1::right_sole());
    assert!(matches!(
        g1::from_urdf_str("<robot name=\"g1\">", None),
        Err(UrdfError::Xml(_))
    ));
    let no_knee = g1::URDF.replace("left_knee_joint", "left_knee_renamed");
    assert_eq!(
        g1::from_urdf_str(&no_knee, None).unwrap_err(),
        UrdfError::UnknownVariable("left_knee_joint".into())
    );
}
