//! Servo targets (`robots::servo`, `RobotFrame::servo_targets`): the planned posture plus the
//! static sag of the profile's position servos. On one foot the expected sag is computed here from forward
//! kinematics alone: the gradient of the potential energy `M g z_c` by central differences,
//! divided by each servo's stiffness `effort / servo_saturation`.

use taskstack::human::HumanFrame;
use taskstack::imitation::reference::support::SupportConfig;
use taskstack::imitation::{Imitator, ImitatorConfig};
use taskstack::io::clip::Clip;
use taskstack::robots::{BipedProfile, g1, nao};

fn imitator_on(name: &str, profile: BipedProfile) -> (Clip, Imitator) {
    let path = format!("{}/tests/data/mocap/{name}", env!("CARGO_MANIFEST_DIR"));
    let clip = Clip::open(path).unwrap();
    let config = ImitatorConfig {
        support: SupportConfig::for_capture(clip.capture()),
        ..ImitatorConfig::default()
    };
    (clip, Imitator::new(profile, config).unwrap())
}

const CLIP: &str = "cmu_05_12_slow_dance_tendu_arms_high.bvh";

#[test]
fn a_robot_without_servo_stiffness_commands_its_postures() {
    assert_eq!(nao::profile().servo_saturation, None);
    let (mut clip, mut imitator) = imitator_on(CLIP, nao::profile());
    let mut frame = HumanFrame::new(0.0);
    while clip.read_frame(&mut frame).unwrap() {
        let r = imitator.step(&frame).unwrap();
        assert_eq!(r.servo_targets, r.q, "t = {}", r.time);
    }
}

#[test]
fn on_one_foot_the_g1_commands_each_posture_plus_its_servos_sag() {
    // Without the sway shaper, whose delay `tests/robots_sway.rs` checks.
    let profile = BipedProfile {
        sway_period: None,
        ..g1::profile()
    };
    let saturation = profile.servo_saturation.expect("the G1 states its servos");
    let variables = profile
        .model(taskstack::human::Side::Right)
        .variables()
        .to_vec();
    let (mut clip, mut imitator) = imitator_on(CLIP, profile.clone());
    let mut frame = HumanFrame::new(0.0);
    let (mut one_foot, mut largest_sag) = (0, 0.0_f64);
    while clip.read_frame(&mut frame).unwrap() {
        let r = imitator.step(&frame).unwrap();
        for ((target, q), v) in r.servo_targets.iter().zip(&r.q).zip(&variables) {
            assert!(target.is_finite() && *target >= v.lower && *target <= v.upper);
            assert!(
                (target - q).abs() < 0.05,
                "{}: sag {} rad",
                v.name,
                target - q
            );
            largest_sag = largest_sag.max((target - q).abs());
        }
        if r.phase.airborne_foot() != Some(r.root.other()) {
            continue;
        }
        one_foot += 1;
        let model = profile.model(r.root);
        let mut data = model.new_data();
        let mut potential = |q: &[f64]| {
            model.forward_kinematics(&mut data, q).unwrap();
            model.total_mass() * 9.81 * model.com(&data).unwrap().z
        };
        let h = 1e-6;
        for (k, v) in variables.iter().enumerate() {
            let mut q = r.q.clone();
            q[k] += h;
            let plus = potential(&q);
            q[k] -= 2.0 * h;
            let torque = (plus - potential(&q)) / (2.0 * h);
            let expected = (r.q[k] + torque * saturation / v.effort).clamp(v.lower, v.upper);
            assert!(
                (r.servo_targets[k] - expected).abs() < 1e-6,
                "t = {}, {}: {} vs {expected}",
                r.time,
                v.name,
                r.servo_targets[k]
            );
        }
    }
    assert!(
        one_foot > 100,
        "the clip stands on one foot: {one_foot} frames"
    );
    // The stance leg's servos hold the whole weight: their sag is several mrad.
    assert!(largest_sag > 0.005, "{largest_sag}");
}

#[test]
fn a_servo_saturation_that_is_not_a_positive_angle_is_refused() {
    let mut profile = g1::profile();
    for bad in [0.0, -0.01, f64::NAN, f64::INFINITY] {
        profile.servo_saturation = Some(bad);
        let err = profile.validate().unwrap_err();
        assert!(err.to_string().contains("servo_saturation"), "{err}");
    }
}

#[test]
fn targets_of_the_wrong_length_are_refused() {
    use taskstack::model::ModelError;
    use taskstack::robots::servo::ServoSag;
    let profile = g1::profile();
    let model = profile.model(taskstack::human::Side::Right);
    let mut data = model.new_data();
    model.forward_kinematics(&mut data, &profile.stand).unwrap();
    let mut servo = ServoSag::new(&profile).unwrap();
    let mut out = vec![0.0; model.nv() - 1];
    let short = servo.targets(model, &data, &[], &profile.stand, &mut out);
    assert!(matches!(short, Err(ModelError::WrongQLength { .. })));
    assert!(ServoSag::new(&nao::profile()).is_none());
}
