//! Segment-by-segment scaler (Poubel eq. 1) and the NAO human joint angles.
//!
//! Expected values come from the NAO's published dimensions (FootHeight 0.04511 m, thigh and
//! tibia 0.100 / 0.1029 m, upper arm (0.105, ±0.015, 0) m), from hand-built human poses and from
//! the robot's own forward kinematics used as a "human".

use nalgebra::{Rotation3, Vector3};
use proptest::prelude::*;
use taskstack::human::Side;
use taskstack::human::{HumanFrame, HumanJoint as J};
use taskstack::imitation::reference::scaler::{
    RobotSkeleton, ScaleConfig, ScaleError, ScaledSkeleton, Scaler, Stance,
};
use taskstack::imitation::reference::support::{HumanSupport, SupportConfig, SupportDetector};
use taskstack::io::bvh::{BvhConfig, BvhReader};
use taskstack::robots::nao;
use taskstack::robots::{HumanJointAngles, RobotPoint};

const DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/mocap/");
/// NAOqi FootHeight: ankle above sole.
const FOOT_HEIGHT: f64 = 0.04511;

/// A 1.8 m-ish human standing in a T-pose facing +x, feet pointing +x.
fn standing() -> HumanFrame {
    let mut f = HumanFrame::new(0.0);
    let mut put = |j, x, y, z| f.set(j, Some(Vector3::new(x, y, z)));
    put(J::Pelvis, 0.0, 0.0, 1.0);
    put(J::MidHip, 0.0, 0.0, 0.95);
    put(J::LHip, 0.0, 0.09, 0.95);
    put(J::RHip, 0.0, -0.09, 0.95);
    put(J::LKnee, 0.0, 0.09, 0.5);
    put(J::RKnee, 0.0, -0.09, 0.5);
    put(J::LAnkle, 0.0, 0.09, 0.08);
    put(J::RAnkle, 0.0, -0.09, 0.08);
    put(J::LToe, 0.14, 0.09, 0.02);
    put(J::RToe, 0.14, -0.09, 0.02);
    put(J::MidShoulder, 0.0, 0.0, 1.45);
    put(J::Neck, 0.0, 0.0, 1.55);
    put(J::Head, 0.02, 0.0, 1.65);
    put(J::LShoulder, 0.0, 0.18, 1.45);
    put(J::RShoulder, 0.0, -0.18, 1.45);
    put(J::LElbow, 0.0, 0.46, 1.45);
    put(J::RElbow, 0.0, -0.46, 1.45);
    put(J::LWrist, 0.0, 0.72, 1.45);
    put(J::RWrist, 0.0, -0.72, 1.45);
    put(J::LHand, 0.0, 0.8, 1.45);
    put(J::RHand, 0.0, -0.8, 1.45);
    f
}

fn scaler() -> Scaler {
    Scaler::new(
        RobotSkeleton::of(&nao::profile()).unwrap(),
        ScaleConfig::new(nao::STEP_ENVELOPE),
    )
    .unwrap()
}

fn is_pair(j: J) -> bool {
    matches!(j, J::LHip | J::RHip | J::LShoulder | J::RShoulder)
}

/// Segments whose direction is not the human's by design: toes of feet on the ground (flat), and
/// in double support the shanks (they close the leg loop).
fn exempt(j: J, scaled: &ScaledSkeleton) -> bool {
    let grounded_toe = |side, toe| j == toe && scaled.sole(side).is_some();
    grounded_toe(Side::Left, J::LToe)
        || grounded_toe(Side::Right, J::RToe)
        || (scaled.stance == Stance::Double && matches!(j, J::LAnkle | J::RAnkle))
}

/// The human direction of the segment ending at `j`, in the output frame: rotated by minus the
/// heading of the base foot's ankle→toe projection.
fn human_direction(frame: &HumanFrame, sk: &RobotSkeleton, j: J, base: Side) -> Vector3<f64> {
    let (ankle, toe) = match base {
        Side::Left => (J::LAnkle, J::LToe),
        Side::Right => (J::RAnkle, J::RToe),
    };
    let foot = frame.get(toe).unwrap() - frame.get(ankle).unwrap();
    let r = Rotation3::from_axis_angle(&Vector3::z_axis(), -foot.y.atan2(foot.x));
    let v = if is_pair(j) {
        let (l, rr) = if j.name().starts_with('L') {
            (j, j.mirror())
        } else {
            (j.mirror(), j)
        };
        let sign = if j == l { 1.0 } else { -1.0 };
        sign * (frame.get(l).unwrap() - frame.get(rr).unwrap())
    } else {
        frame.get(j).unwrap() - frame.get(sk.antecedent(j).unwrap()).unwrap()
    };
    r * v.normalize()
}

/// Every non-exempt segment has the robot's length; with `frame` complete, the human direction.
fn check_segments(scaled: &ScaledSkeleton, sk: &RobotSkeleton, frame: Option<&HumanFrame>) {
    for &j in sk.joints() {
        let Some(a) = sk.antecedent(j) else { continue };
        let seg = scaled.get(j).unwrap() - scaled.get(a).unwrap();
        assert!(seg.iter().all(|c| c.is_finite()), "{j:?} not finite");
        if exempt(j, scaled) {
            continue;
        }
        let length = sk.length(j).unwrap();
        assert!(
            (seg.norm() - length).abs() < 1e-9,
            "{j:?}: {} vs robot {length} ({:?})",
            seg.norm(),
            scaled.stance
        );
        if let Some(frame) = frame {
            let expected = human_direction(frame, sk, j, scaled.base());
            assert!(
                (seg / length - expected).norm() < 1e-9,
                "{j:?} direction {:?} vs {expected:?}",
                seg / length
            );
        }
    }
}

#[test]
fn nao_segment_lengths_come_from_the_model() {
    let sk = RobotSkeleton::of(&nao::profile()).unwrap();
    // NAO dimensions: thigh 0.100, tibia 0.1029, hip offset 0.050, upper arm √(0.105² + 0.015²),
    // MidHip→MidShoulder = 0.085 (torso above hips) + 0.100 (shoulders above torso).
    assert!((sk.length(J::LKnee).unwrap() - 0.100).abs() < 1e-12);
    assert!((sk.length(J::RAnkle).unwrap() - 0.1029).abs() < 1e-12);
    assert!((sk.length(J::LHip).unwrap() - 0.050).abs() < 1e-12);
    assert!((sk.length(J::LElbow).unwrap() - 0.105f64.hypot(0.015)).abs() < 1e-12);
    assert!((sk.length(J::MidShoulder).unwrap() - 0.185).abs() < 1e-12);
    assert!((sk.ankle_height(Side::Left) - FOOT_HEIGHT).abs() < 1e-12);
    assert!((sk.ankle_height(Side::Right) - FOOT_HEIGHT).abs() < 1e-12);
    // Leg loop: mid-ankle to mid-hip = 0.1029 + 0.100 straight up.
    assert!((sk.loop_length() - 0.2029).abs() < 1e-12);
    assert!(!sk.has(J::Pelvis));
}

#[test]
fn mapping_errors_name_the_problem() {
    let model = nao::rfoot();
    let soles = ["l_sole", "r_sole"];
    let zero = vec![0.0; model.nv()];
    let skeleton = |points: &[(J, RobotPoint)]| RobotSkeleton::new(&model, points, soles, &zero);
    assert_eq!(
        skeleton(&nao::points()[..3]).unwrap_err(),
        ScaleError::MissingJoint("LKnee")
    );
    let frame = |name: &str| RobotPoint::Frame(name.to_owned());
    let points = [(J::MidHip, frame("l_hip")), (J::MidHip, frame("r_hip"))];
    assert_eq!(
        skeleton(&points).unwrap_err(),
        ScaleError::DuplicateJoint("MidHip")
    );
    let err = skeleton(&[(J::MidHip, frame("pelvis_nowhere"))]).unwrap_err();
    assert!(err.to_string().contains("pelvis_nowhere"), "{err}");
    let mut bad = ScaleConfig::new(nao::STEP_ENVELOPE);
    bad.area.x_min = 1.0;
    assert!(matches!(
        Scaler::new(RobotSkeleton::of(&nao::profile()).unwrap(), bad),
        Err(ScaleError::BadConfig(_))
    ));
    let mut s = scaler();
    assert!(matches!(
        s.scale(&HumanFrame::new(f64::NAN), HumanSupport::Double),
        Err(ScaleError::NonFiniteTime(_))
    ));
}

#[test]
fn single_support_lengths_directions_and_origin() {
    let sk = RobotSkeleton::of(&nao::profile()).unwrap();
    // A pose with bent limbs, turned 0.4 rad, standing on the right foot.
    let mut frame = standing();
    frame.set(J::LKnee, Some(Vector3::new(0.3, 0.1, 0.75)));
    frame.set(J::LAnkle, Some(Vector3::new(0.2, 0.12, 0.4)));
    frame.set(J::LElbow, Some(Vector3::new(0.2, 0.3, 1.3)));
    frame.set(J::LWrist, Some(Vector3::new(0.4, 0.2, 1.4)));
    let turn = Rotation3::from_axis_angle(&Vector3::z_axis(), 0.4);
    let mut turned = HumanFrame::new(0.0);
    for (j, p) in frame.joints() {
        turned.set(j, p.map(|p| turn * p + Vector3::new(1.0, -2.0, 0.0)));
    }
    for support in [HumanSupport::Right, HumanSupport::Left] {
        let mut s = scaler();
        let scaled = s.scale(&turned, support).unwrap();
        check_segments(scaled, &sk, Some(&turned));
        let base = scaled.base();
        let ankle = if base == Side::Right {
            J::RAnkle
        } else {
            J::LAnkle
        };
        assert!((scaled.get(ankle).unwrap() - Vector3::new(0.0, 0.0, FOOT_HEIGHT)).norm() < 1e-12);
        assert!(scaled.sole(base.other_side()).is_none());
    }
}

trait OtherSide {
    fn other_side(self) -> Side;
}
impl OtherSide for Side {
    fn other_side(self) -> Side {
        match self {
            Side::Left => Side::Right,
            Side::Right => Side::Left,
        }
    }
}

#[test]
fn double_support_puts_both_soles_on_the_ground() {
    let sk = RobotSkeleton::of(&nao::profile()).unwrap();
    let mut frame = standing();
    // Human feet 1.0 m apart, knees at ±0.45 m: legs (hip→knee→ankle) 0.87 (right) and
    // |(0, .36, −.45)| + |(0, .35, −.42)| = 0.5763 + 0.5467 (left), mean 0.9965; robot leg
    // 0.2029 → ratio 0.2036, lateral 0.89 · 0.2036 = 0.181, clipped to the NAO area's largest
    // lateral offset.
    frame.set(J::LKnee, Some(Vector3::new(0.0, 0.45, 0.5)));
    frame.set(J::LAnkle, Some(Vector3::new(0.0, 0.8, 0.08)));
    frame.set(J::LToe, Some(Vector3::new(0.14, 0.8, 0.02)));
    let mut s = scaler();
    let scaled = *s.scale(&frame, HumanSupport::Double).unwrap();
    check_segments(&scaled, &sk, Some(&frame));
    assert_eq!(scaled.stance, Stance::Double);
    assert!((scaled.get(J::RAnkle).unwrap() - Vector3::new(0.0, 0.0, FOOT_HEIGHT)).norm() < 1e-12);
    assert!((scaled.get(J::LAnkle).unwrap().z - FOOT_HEIGHT).abs() < 1e-12);
    // Toes at the sole level (z = 0), 0.05 m ahead of the ankle (NAO toe frame).
    for toe in [J::LToe, J::RToe] {
        assert!(scaled.get(toe).unwrap().z.abs() < 1e-12);
    }
    let left = scaled.sole(Side::Left).unwrap();
    assert!(
        (left.xy.y - nao::STEP_ENVELOPE.lateral_max).abs() < 1e-12,
        "{left:?}"
    );
    assert!(left.xy.x.abs() < 1e-12 && left.yaw.abs() < 1e-12);
    // Leg loop: MidHip at loop length from the mid-ankle point.
    let mid_ankle = (scaled.get(J::LAnkle).unwrap() + scaled.get(J::RAnkle).unwrap()) / 2.0;
    assert!(((scaled.get(J::MidHip).unwrap() - mid_ankle).norm() - sk.loop_length()).abs() < 1e-12);

    // Proportional placement inside the area: feet and knees at ±0.25 m, hips at ±0.09 m: legs
    // |(0, .16, −.45)| + 0.42 = 0.8976, ratio 0.2029/0.8976, lateral 0.5 · ratio = 0.1130.
    let mut frame = standing();
    for (j, y) in [(J::LKnee, 0.25), (J::RKnee, -0.25)] {
        frame.set(j, Some(Vector3::new(0.0, y, 0.5)));
    }
    for (a, t, y) in [(J::LAnkle, J::LToe, 0.25), (J::RAnkle, J::RToe, -0.25)] {
        frame.set(a, Some(Vector3::new(0.0, y, 0.08)));
        frame.set(t, Some(Vector3::new(0.14, y, 0.02)));
    }
    let mut s = scaler();
    let scaled = s.scale(&frame, HumanSupport::Double).unwrap();
    let ratio = 0.2029 / (0.16f64.hypot(0.45) + 0.42);
    let left = scaled.sole(Side::Left).unwrap();
    assert!((left.xy.y - 0.5 * ratio).abs() < 1e-12, "{left:?}");
}

#[test]
fn a_foot_put_down_stays_until_double_support_ends() {
    let mut s = scaler();
    let mut frame = standing();
    s.scale(&frame, HumanSupport::Right).unwrap();
    frame.set(J::LAnkle, Some(Vector3::new(0.2, 0.2, 0.08)));
    frame.set(J::LToe, Some(Vector3::new(0.34, 0.2, 0.02)));
    let landed = s
        .scale(&frame, HumanSupport::Double)
        .unwrap()
        .sole(Side::Left);
    // The human slides the foot while in DS: the robot foot does not move.
    frame.set(J::LAnkle, Some(Vector3::new(0.1, 0.3, 0.08)));
    frame.set(J::LToe, Some(Vector3::new(0.24, 0.3, 0.02)));
    let later = s.scale(&frame, HumanSupport::Airborne).unwrap();
    assert_eq!(later.stance, Stance::Double);
    assert_eq!(later.sole(Side::Left), landed);
    // Legs 0.87 (right) and 0.45 + |(.2, .11, −.42)| = 0.45 + 0.4781 (left): ratio 0.2029/0.8991.
    // x: 0.2 · ratio = 0.0451 (inside [−0.06, 0.08]); lateral 0.29 · ratio = 0.065 → 0.095.
    let landed = landed.unwrap();
    let ratio = 0.2029 / ((0.87 + 0.45 + (0.2f64 * 0.2 + 0.11 * 0.11 + 0.42 * 0.42).sqrt()) / 2.0);
    assert!((landed.xy.x - 0.2 * ratio).abs() < 1e-12, "{landed:?}");
    assert!((landed.xy.y - 0.095).abs() < 1e-12);

    // Landing the right foot after left support: in the right sole frame, the left foot is at
    // minus the right foot's placement relative to the left.
    let mut s = scaler();
    let frame = standing();
    s.scale(&frame, HumanSupport::Left).unwrap();
    let scaled = s.scale(&frame, HumanSupport::Double).unwrap();
    // 0.18 · 0.2029/0.87 = 0.042, under the 0.095 minimum; mirrored twice.
    let left = scaled.sole(Side::Left).unwrap();
    assert!((left.xy.y - 0.095).abs() < 1e-12, "{left:?}");
}

#[test]
fn missing_and_coincident_joints_reuse_the_previous_direction() {
    let mut s = scaler();
    let mut frame = standing();
    frame.set(J::LElbow, Some(Vector3::new(0.3, 0.18, 1.45)));
    let first = *s.scale(&frame, HumanSupport::Right).unwrap();
    let mut broken = frame;
    broken.set(J::LElbow, None);
    broken.set(J::LHand, broken.get(J::LWrist));
    let second = s.scale(&broken, HumanSupport::Right).unwrap();
    // Elbow missing: shoulder→elbow and elbow→wrist keep the previous frame's directions; the
    // hand on the wrist (zero-length segment) too.
    for j in [J::LElbow, J::LWrist, J::LHand] {
        assert!(
            (first.get(j).unwrap() - second.get(j).unwrap()).norm() < 1e-12,
            "{j:?}"
        );
    }
    // First frame with nothing at all: the robot's reference posture (arms forward at q = 0).
    let mut s = scaler();
    let empty = s.scale(&HumanFrame::new(0.0), HumanSupport::Right).unwrap();
    let sk = RobotSkeleton::of(&nao::profile()).unwrap();
    let r = sk.reference(J::RAnkle).unwrap() - Vector3::new(0.0, 0.0, FOOT_HEIGHT);
    for (j, p) in empty.points() {
        if let Some(p) = p {
            assert!((p - (sk.reference(j).unwrap() - r)).norm() < 1e-12, "{j:?}");
        }
    }
}

fn frames_equal(a: &ScaledSkeleton, b: &ScaledSkeleton, tol: f64) -> bool {
    a.points()
        .zip(b.points())
        .all(|((_, p), (_, q))| match (p, q) {
            (Some(p), Some(q)) => (p - q).norm() < tol,
            (None, None) => true,
            _ => false,
        })
}

fn joint_strategy() -> impl Strategy<Value = (u8, [f64; 3])> {
    (0u8..10, prop::array::uniform3(-0.3f64..0.3))
}

/// Random frames: standing pose, each joint perturbed, and if `degenerate` missing (10 %) or on
/// its antecedent (10 %), times a size 10^`log_size`.
fn frame_strategy(
    degenerate: bool,
    log_size: std::ops::Range<f64>,
) -> impl Strategy<Value = HumanFrame> {
    (prop::array::uniform21(joint_strategy()), log_size).prop_map(move |(joints, log_size)| {
        let size = 10f64.powf(log_size);
        let base = standing();
        let mut f = HumanFrame::new(0.0);
        for (j, (kind, d)) in J::ALL.into_iter().zip(joints) {
            let p = base.get(j).unwrap() + Vector3::from(d);
            f.set(j, Some(p * size));
            match kind {
                _ if !degenerate => {}
                0 => f.set(j, None),
                1 => f.set(j, j.antecedent().and_then(|a| f.get(a))),
                _ => {}
            }
        }
        f
    })
}

fn support_strategy() -> impl Strategy<Value = HumanSupport> {
    prop::sample::select(vec![
        HumanSupport::Double,
        HumanSupport::Right,
        HumanSupport::Left,
        HumanSupport::Airborne,
    ])
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    #[test]
    fn random_frames_never_give_nan_and_keep_lengths(
        frames in prop::collection::vec((frame_strategy(true, -6.0..3.0), support_strategy()), 1..6)
    ) {
        let sk = RobotSkeleton::of(&nao::profile()).unwrap();
        let mut s = scaler();
        let angles_model = nao::rfoot();
        let mut angles = nao::JointAngles::new(&angles_model).unwrap();
        let mut q = vec![0.0; angles_model.nv()];
        for (frame, support) in &frames {
            let scaled = s.scale(frame, *support).unwrap();
            check_segments(scaled, &sk, None);
            let ankle = if scaled.base() == Side::Right { J::RAnkle } else { J::LAnkle };
            prop_assert!((scaled.get(ankle).unwrap() - Vector3::new(0.0, 0.0, FOOT_HEIGHT)).norm() < 1e-12);
            angles.compute(scaled.directions(), &mut q).unwrap();
            for (v, var) in q.iter().zip(angles_model.variables()) {
                prop_assert!(v.is_finite() && *v >= var.lower && *v <= var.upper, "{} = {v}", var.name);
            }
        }
    }

    #[test]
    fn scaling_is_invariant_to_size_and_rigid_motion(
        frame in frame_strategy(false, -1.0..1.0),
        support in support_strategy(),
        size in 0.01f64..100.0,
        yaw in -3.1f64..3.1,
        shift in prop::array::uniform3(-5.0f64..5.0),
    ) {
        // Complete frames only: a direction missing at the first frame takes the robot's
        // reference direction, which does not turn with the human.
        let r = Rotation3::from_axis_angle(&Vector3::z_axis(), yaw);
        let mut moved = HumanFrame::new(0.0);
        for (j, p) in frame.joints() {
            moved.set(j, p.map(|p| r * (p * size) + Vector3::from(shift)));
        }
        let a = *scaler().scale(&frame, support).unwrap();
        let b = *scaler().scale(&moved, support).unwrap();
        prop_assert!(frames_equal(&a, &b, 1e-9), "{a:?}\n{b:?}");
    }
}

#[test]
fn real_clip_keeps_robot_lengths_on_every_frame() {
    let sk = RobotSkeleton::of(&nao::profile()).unwrap();
    let mut s = scaler();
    let mut detector = SupportDetector::new(SupportConfig::optical()).unwrap();
    let mut reader = BvhReader::open(
        format!("{DATA}cmu_05_02_stand_arm_gestures_turn_single_leg.bvh"),
        BvhConfig::cmu(),
    )
    .unwrap();
    let mut frame = HumanFrame::new(0.0);
    let mut n = 0;
    let mut stances = [0usize; 3];
    while reader.read_frame(&mut frame).unwrap() {
        let support = detector.update(&frame);
        let scaled = s.scale(&frame, support).unwrap();
        check_segments(scaled, &sk, Some(&frame));
        stances[scaled.stance as usize] += 1;
        n += 1;
    }
    assert!(n > 1000, "{n} frames");
    // The clip has a ~1.8 s right-leg stance (120 fps) and long double support.
    assert!(stances[Stance::Right as usize] > 150, "{stances:?}");
    assert!(stances[Stance::Double as usize] > 500, "{stances:?}");
}

/// The human frame made of the NAO's own named frames at `q` (robot as human), and the model.
fn robot_as_human(q: &[f64]) -> HumanFrame {
    let model = nao::rfoot();
    let mut data = model.new_data();
    model.forward_kinematics(&mut data, q).unwrap();
    let p = |name: &str| {
        data.frame_placement(model.frame_id(name).unwrap())
            .translation
            .vector
    };
    let mut f = HumanFrame::new(0.0);
    for (j, point) in nao::points() {
        f.set(
            j,
            Some(match &point {
                RobotPoint::Frame(a) => p(a),
                RobotPoint::Midpoint(a, b) => (p(a) + p(b)) / 2.0,
            }),
        );
    }
    f
}

fn angles_of(frame: &HumanFrame) -> Vec<f64> {
    let model = nao::rfoot();
    let mut s = scaler();
    let scaled = s.scale(frame, HumanSupport::Right).unwrap();
    let mut q = vec![0.0; model.nv()];
    nao::JointAngles::new(&model)
        .unwrap()
        .compute(scaled.directions(), &mut q)
        .unwrap();
    q
}

fn var(name: &str) -> usize {
    nao::VARIABLES.iter().position(|v| *v == name).unwrap()
}

#[test]
fn hand_computed_arm_and_leg_angles() {
    // Standing straight: legs vertical, so hip roll/pitch, knee and ankles are 0.
    let q = angles_of(&standing());
    for name in [
        "LHipRoll",
        "LHipPitch",
        "LKneePitch",
        "LAnklePitch",
        "LAnkleRoll",
        "RHipRoll",
        "RKneePitch",
    ] {
        assert!(q[var(name)].abs() < 1e-12, "{name} = {}", q[var(name)]);
    }
    // T-pose: arm sideways → roll π/2 − δ (δ = atan2(0.015, 0.105)) = 1.4289, beyond the
    // 1.3265 limit → clipped; right arm mirrored.
    assert!((q[var("LShoulderRoll")] - 1.3265).abs() < 1e-4);
    assert!((q[var("RShoulderRoll")] + 1.3265).abs() < 1e-4);

    let delta = 0.015f64.atan2(0.105);
    let mut f = standing();
    // Left arm straight forward: pitch 0, roll −δ.
    f.set(J::LElbow, Some(Vector3::new(0.28, 0.18, 1.45)));
    f.set(J::LWrist, Some(Vector3::new(0.54, 0.18, 1.45)));
    // Right arm hanging down: pitch π/2 (limit 2.0857); elbow straight: NAO's forearm is parallel
    // to shoulder→elbow at RElbowRoll = δ (its elbow is 15 mm outward of the roll axis).
    f.set(J::RElbow, Some(Vector3::new(0.0, -0.18, 1.17)));
    f.set(J::RWrist, Some(Vector3::new(0.0, -0.18, 0.91)));
    let q = angles_of(&f);
    assert!(q[var("LShoulderPitch")].abs() < 1e-12);
    assert!((q[var("LShoulderRoll")] + delta).abs() < 1e-12);
    assert!((q[var("RShoulderPitch")] - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
    assert!((q[var("RElbowRoll")] - delta).abs() < 1e-12);

    // Left elbow bent 90° inwards (forearm towards −y): LElbowRoll −(π/2 − δ), LElbowYaw 0.
    f.set(J::LWrist, Some(Vector3::new(0.28, -0.08, 1.45)));
    // Right elbow bent 90° inwards with the upper arm forward: RElbowRoll +(π/2 − δ).
    f.set(J::RElbow, Some(Vector3::new(0.28, -0.18, 1.45)));
    f.set(J::RWrist, Some(Vector3::new(0.28, 0.08, 1.45)));
    let q = angles_of(&f);
    let bent = std::f64::consts::FRAC_PI_2 - delta;
    assert!((q[var("LElbowRoll")] + bent).abs() < 1e-12);
    assert!(q[var("LElbowYaw")].abs() < 1e-12);
    assert!((q[var("RElbowRoll")] - bent).abs() < 1e-12);
    assert!(q[var("RElbowYaw")].abs() < 1e-12);

    // Squat: thigh 45° forward, shank vertical → HipPitch −π/4, knee +π/4, ankle 0
    // (sole level with a vertical shank).
    let mut f = standing();
    let s = 0.45 / 2f64.sqrt();
    f.set(J::LKnee, Some(Vector3::new(s, 0.09, 0.95 - s)));
    f.set(J::LAnkle, Some(Vector3::new(s, 0.09, 0.95 - s - 0.42)));
    let q = angles_of(&f);
    let quarter = std::f64::consts::FRAC_PI_4;
    assert!((q[var("LHipPitch")] + quarter).abs() < 1e-12);
    assert!((q[var("LKneePitch")] - quarter).abs() < 1e-12);
    assert!(q[var("LAnklePitch")].abs() < 1e-12);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(100))]

    /// The NAO as its own human: angles observable from positions come back to 1e−6.
    #[test]
    fn robot_as_human_reproduces_its_angles(
        unit_q in prop::collection::vec(0.0f64..1.0, 23),
        hip_yaw_pitch_zero in any::<bool>(),
    ) {
        let model = nao::rfoot();
        let mut q: Vec<f64> = model
            .variables()
            .iter()
            .zip(&unit_q)
            .map(|(v, u)| v.lower + u * (v.upper - v.lower))
            .collect();
        if hip_yaw_pitch_zero {
            q[var("LHipYawPitch")] = 0.0;
        }
        let angles = angles_of(&robot_as_human(&q));
        let mut observable = vec![
            "LShoulderPitch", "LShoulderRoll", "LElbowRoll", "LKneePitch",
            "RShoulderPitch", "RShoulderRoll", "RElbowRoll", "RKneePitch",
        ];
        if hip_yaw_pitch_zero {
            observable.extend(["LHipRoll", "LHipPitch", "RHipRoll", "RHipPitch"]);
        }
        for side in ["L", "R"] {
            // Elbow yaw is defined when the elbow is bent.
            if q[var(&format!("{side}ElbowRoll"))].abs() > 0.2 {
                observable.push(if side == "L" { "LElbowYaw" } else { "RElbowYaw" });
            }
        }
        for name in observable {
            let k = var(name);
            prop_assert!((angles[k] - q[k]).abs() < 1e-6, "{name}: {} vs {}", angles[k], q[k]);
        }
    }
}
