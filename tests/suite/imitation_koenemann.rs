//! Koenemann et al.'s pieces against their equations, with hand-computed values.

use nalgebra::Vector3;
use taskstack::human::{HumanFrame, HumanJoint as J, centre_of_mass};
use taskstack::imitation::koenemann::mapping::{Calibration, Limbs, Posture, PostureMapping};
use taskstack::imitation::koenemann::offset::{OffsetSpeed, offset};
use taskstack::imitation::koenemann::retarget::{FootRetargeting, retarget_double, support_normal};
use taskstack::imitation::koenemann::support_mode::{SupportMode, target_offset};
use taskstack::imitation::reference::support::HumanSupport as H;

fn v(x: f64, y: f64, z: f64) -> Vector3<f64> {
    Vector3::new(x, y, z)
}

#[test]
fn eq6_offset_of_a_drawn_example() {
    // Feet at (0, 0.1) and (0, −0.1); CoM at (0.05, 0.04, 0.3): the projection on the line is
    // 0.06 from the left foot along 0.2, o = 0.3.
    let o = offset(&v(0.05, 0.04, 0.3), &v(0.0, 0.1, 0.0), &v(0.0, -0.1, 0.0)).unwrap();
    assert!((o - 0.3).abs() < 1e-12, "{o}");
    // Beyond the right foot: > 1; coincident feet: none.
    let o = offset(&v(0.0, -0.15, 0.3), &v(0.0, 0.1, 0.0), &v(0.0, -0.1, 0.0)).unwrap();
    assert!((o - 1.25).abs() < 1e-12);
    assert!(offset(&v(0.0, 0.0, 0.3), &v(0.0, 0.1, 0.0), &v(0.0, 0.1, 0.0)).is_none());
}

#[test]
fn the_offset_speed_is_largest_at_the_middle_and_small_at_the_feet() {
    let speed = OffsetSpeed {
        max: 2.0,
        border: 0.1,
        acceleration: f64::INFINITY,
    };
    assert_eq!(speed.at(0.5), 2.0);
    assert!((speed.at(0.0) - 0.2).abs() < 1e-12);
    assert!((speed.at(1.0) - 0.2).abs() < 1e-12);
    // v(0.25) = 2 (0.1 + 0.9 · 4 · 0.25 · 0.75) = 2 · 0.775.
    assert!((speed.at(0.25) - 1.55).abs() < 1e-12);
    // A step never passes its target, and stops there.
    assert_eq!(speed.step(0.5, 0.0, 0.52, 0.1), (0.52, 0.0));
    let (o, rate) = speed.step(0.5, 0.0, 0.0, 0.1);
    assert!((o - 0.3).abs() < 1e-12 && rate == -2.0, "{o} {rate}");
}

#[test]
fn the_offset_rate_changes_by_at_most_the_acceleration_and_brakes_before_its_target() {
    let speed = OffsetSpeed {
        max: 2.0,
        border: 0.1,
        acceleration: 6.0,
    };
    // From rest at 0.5 toward 1: the rate may reach v(0.5) = 2 but gains only 6 · 0.1 = 0.6.
    let (o, rate) = speed.step(0.5, 0.0, 1.0, 0.1);
    assert!(
        (rate - 0.6).abs() < 1e-12 && (o - 0.56).abs() < 1e-12,
        "{o} {rate}"
    );
    // At 2 /s, 0.1 short of the target: the stopping speed √(2 · 6 · 0.1) ≈ 1.095 < 2, so the
    // rate drops, by 6 · 0.01 = 0.06 in 10 ms.
    let (o, rate) = speed.step(0.5, 2.0, 0.6, 0.01);
    assert!(
        (rate - 1.94).abs() < 1e-12 && (o - 0.5194).abs() < 1e-12,
        "{o} {rate}"
    );
}

#[test]
fn fig4_single_support_only_with_the_human_on_that_foot_and_the_offset_there() {
    let tol = 0.05;
    assert_eq!(
        SupportMode::Double.next(H::Left, 0.3, tol),
        SupportMode::Double
    );
    assert_eq!(
        SupportMode::Double.next(H::Left, 0.04, tol),
        SupportMode::Left
    );
    assert_eq!(
        SupportMode::Double.next(H::Right, 0.04, tol),
        SupportMode::Double
    );
    assert_eq!(
        SupportMode::Double.next(H::Right, 0.96, tol),
        SupportMode::Right
    );
    assert_eq!(
        SupportMode::Double.next(H::Double, 0.0, tol),
        SupportMode::Double
    );
    assert_eq!(SupportMode::Left.next(H::Left, 0.5, tol), SupportMode::Left);
    assert_eq!(
        SupportMode::Left.next(H::Double, 0.0, tol),
        SupportMode::Double
    );
    // Straight from one foot to the other goes through double support.
    assert_eq!(
        SupportMode::Left.next(H::Right, 0.0, tol),
        SupportMode::Double
    );
    assert_eq!(
        SupportMode::Right.next(H::Airborne, 1.0, tol),
        SupportMode::Right
    );
    assert_eq!(target_offset(H::Left, 0.7, 0.5), 0.0);
    assert_eq!(target_offset(H::Right, 0.7, 0.5), 1.0);
    assert_eq!(target_offset(H::Double, 1.3, 0.5), 1.0);
    assert_eq!(target_offset(H::Airborne, 0.7, 0.4), 0.4);
}

#[test]
fn eq7_normal_points_from_the_offset_point_to_the_com() {
    // Feet at y = ±0.1 (left +), o' = 0.25: the point is (0, 0.05, 0); CoM (0.03, 0.05, 0.4).
    let n = support_normal(
        &v(0.03, 0.05, 0.4),
        &v(0.0, 0.1, 0.0),
        &v(0.0, -0.1, 0.0),
        0.25,
    )
    .unwrap();
    let expected = v(0.03, 0.0, 0.4).normalize();
    assert!((n - expected).norm() < 1e-12, "{n}");
}

#[test]
fn double_support_retargeting_meets_the_desired_offset() {
    let com = v(0.0, 0.0, 0.3);
    let feet = [v(0.0, 0.1, -0.3), v(0.0, -0.1, -0.3)];
    // Shifting both feet keeps their distance.
    let [l, r] = retarget_double(FootRetargeting::ShiftBothFeet, &com, feet, 0.2);
    assert!((offset(&com, &l, &r).unwrap() - 0.2).abs() < 1e-12);
    assert!(((l - r).norm() - 0.2).abs() < 1e-12);
    // The paper's rule moves the left foot toward the CoM when o' < o; the right stays.
    let [l, r] = retarget_double(FootRetargeting::MoveOneFoot, &com, feet, 0.2);
    assert!((offset(&com, &l, &r).unwrap() - 0.2).abs() < 1e-9);
    assert_eq!(r, feet[1]);
    assert!(l.y < 0.1 && l.y > 0.0);
    let [l, r] = retarget_double(FootRetargeting::MoveOneFoot, &com, feet, 0.8);
    assert!((offset(&com, &l, &r).unwrap() - 0.8).abs() < 1e-9);
    assert_eq!(l, feet[0]);
}

fn skeleton(arms_out: bool) -> HumanFrame {
    let mut f = HumanFrame::new(0.0);
    let hand_y = if arms_out { 0.75 } else { 0.2 };
    let hand_z = if arms_out { 1.4 } else { 0.85 };
    let elbow = |y: f64| {
        if arms_out {
            v(0.0, y * 0.45 / 0.2, 1.4)
        } else {
            v(0.0, y, 1.12)
        }
    };
    for (j, p) in [
        (J::MidHip, v(0.0, 0.0, 0.9)),
        (J::LHip, v(0.0, 0.1, 0.9)),
        (J::RHip, v(0.0, -0.1, 0.9)),
        (J::LKnee, v(0.0, 0.1, 0.5)),
        (J::RKnee, v(0.0, -0.1, 0.5)),
        (J::LAnkle, v(0.0, 0.1, 0.1)),
        (J::RAnkle, v(0.0, -0.1, 0.1)),
        (J::LToe, v(0.15, 0.1, 0.0)),
        (J::RToe, v(0.15, -0.1, 0.0)),
        (J::MidShoulder, v(0.0, 0.0, 1.4)),
        (J::Head, v(0.0, 0.0, 1.6)),
        (J::LShoulder, v(0.0, 0.2, 1.4)),
        (J::RShoulder, v(0.0, -0.2, 1.4)),
        (J::LElbow, elbow(0.2)),
        (J::RElbow, elbow(-0.2)),
        (J::LWrist, v(0.0, hand_y, hand_z)),
        (J::RWrist, v(0.0, -hand_y, hand_z)),
    ] {
        f.set(j, Some(p));
    }
    f
}

#[test]
fn a_t_pose_calibrates_and_the_ratios_scale_the_deviation() {
    let t = skeleton(true);
    let posture = Posture::of_human(&t).unwrap();
    assert!(posture.is_t_pose());
    // Hand relative to shoulder in chest axes: (0, 0.55, 0); ankle to hip: (0, 0, −0.8).
    assert!((posture.hands[0] - v(0.0, 0.55, 0.0)).norm() < 1e-12);
    assert!((posture.feet[1] - v(0.0, 0.0, -0.8)).norm() < 1e-12);
    let robot = Limbs {
        arms: [0.22, 0.22],
        legs: [0.2, 0.2],
    };
    let feet = [v(0.0, 0.0, -0.19), v(0.0, 0.0, -0.19)];
    let mapping = PostureMapping::calibrate(&t, &robot, feet, Calibration::Auto).unwrap();
    assert!(mapping.calibrated_on_first_frame());
    // m = 0.22 / 0.55 for the arms, 0.2 / 0.8 for the legs (eq. 4).
    assert!((mapping.ratios().arms[0] - 0.4).abs() < 1e-12);
    assert!((mapping.ratios().legs[0] - 0.25).abs() < 1e-12);
    // Arms down: hand − shoulder = (0, 0, −0.55) in chest axes; f_R = (0, 0.22, 0) + 0.4 ·
    // ((0, 0, −0.55) − (0, 0.55, 0)) = (0, 0, −0.22).
    let mut down = t;
    down.set(J::LElbow, Some(v(0.0, 0.2, 1.12)));
    down.set(J::LWrist, Some(v(0.0, 0.2, 0.85)));
    let mapped = mapping.map(&Posture::of_human(&down).unwrap());
    assert!(
        (mapped.hands[0] - v(0.0, 0.0, -0.22)).norm() < 1e-12,
        "{}",
        mapped.hands[0]
    );
    // The unchanged legs map to the robot's standing feet.
    assert!((mapped.feet[0] - feet[0]).norm() < 1e-12);
    // Arms down at the start: not a T-pose, the ideal reference is used.
    let ideal =
        PostureMapping::calibrate(&skeleton(false), &robot, feet, Calibration::Auto).unwrap();
    assert!(!ideal.calibrated_on_first_frame());
}

#[test]
fn the_human_com_is_de_levas_weighted_sum() {
    let f = skeleton(true);
    let com = centre_of_mass(&f).unwrap();
    // Symmetric about the sagittal plane.
    assert!(com.y.abs() < 1e-12);
    // Heights by hand: head 1.6; trunk 1.4 − 0.4486 · 0.5; upper arm and forearm and hand at 1.4;
    // thigh 0.9 − 0.4095 · 0.4; shank 0.5 − 0.4459 · 0.4; foot 0.1 − 0.4415 · 0.1.
    let z = 0.0694 * 1.6
        + 0.4346 * (1.4 - 0.4486 * 0.5)
        + 2.0 * (0.0271 + 0.0162 + 0.0061) * 1.4
        + 2.0 * 0.1416 * (0.9 - 0.4095 * 0.4)
        + 2.0 * 0.0433 * (0.5 - 0.4459 * 0.4)
        + 2.0 * 0.0137 * (0.1 - 0.4415 * 0.1);
    assert!((com.z - z).abs() < 1e-12, "{} vs {z}", com.z);
}
