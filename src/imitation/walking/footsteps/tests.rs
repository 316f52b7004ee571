use super::*;
use crate::human::HumanJoint;
use nalgebra::Vector2;

/// A step envelope 5 cm forward, 4 cm back, 9.5–12 cm to the side, ±0.15 rad.
const AREA: FootArea = FootArea {
    x_min: -0.04,
    x_max: 0.05,
    lateral_min: 0.095,
    lateral_max: 0.12,
    yaw_max: 0.15,
};

fn pose(x: f64, y: f64, yaw: f64) -> GroundPose {
    GroundPose {
        xy: Vector2::new(x, y),
        yaw,
    }
}

/// A human frame standing with the ankles at `r` and `l` (x, y), feet pointing +x.
pub(crate) fn human(r: [f64; 2], l: [f64; 2]) -> HumanFrame {
    let mut frame = HumanFrame::new(0.0);
    let v = |x: f64, y: f64, z: f64| nalgebra::Vector3::new(x, y, z);
    frame.set(HumanJoint::RAnkle, Some(v(r[0], r[1], 0.08)));
    frame.set(HumanJoint::LAnkle, Some(v(l[0], l[1], 0.08)));
    frame.set(HumanJoint::RToe, Some(v(r[0] + 0.15, r[1], 0.02)));
    frame.set(HumanJoint::LToe, Some(v(l[0] + 0.15, l[1], 0.02)));
    frame.set(HumanJoint::RHip, Some(v(0.0, -0.1, 0.9)));
    frame.set(HumanJoint::LHip, Some(v(0.0, 0.1, 0.9)));
    frame
}

fn walking() -> FootstepConfig {
    FootstepConfig {
        follow: true,
        ..FootstepConfig::default()
    }
}

const FEET: [GroundPose; 2] = [
    GroundPose {
        xy: Vector2::new(0.0, 0.1),
        yaw: 0.0,
    },
    GroundPose {
        xy: Vector2::new(0.0, 0.0),
        yaw: 0.0,
    },
];

#[test]
fn a_human_step_forward_becomes_a_clipped_robot_step() {
    let mut planner = FootstepPlanner::new(walking(), AREA);
    let double = SupportPhase::Double;
    let dt = 0.01;
    // Standing 0.25 s (the footprints settle): no step.
    let start = human([0.0, -0.1], [0.0, 0.1]);
    let s = planner
        .update(&start, HumanSupport::Double, 0.25, FEET, double, 0.25)
        .support;
    assert_eq!(s, HumanSupport::Double);
    assert_eq!(planner.steps_pending(), 0);
    // The left foot lands 0.4 m ahead: 0.1 m for the robot at ratio 0.25, clipped to the
    // envelope's 0.05 m ahead of the right foot.
    let moved = human([0.0, -0.1], [0.4, 0.1]);
    let s = planner
        .update(&moved, HumanSupport::Double, 0.25, FEET, double, dt)
        .support;
    assert_eq!(
        s,
        HumanSupport::Right,
        "stand on the right foot to move the left"
    );
    let (foot, target) = planner.target().unwrap();
    assert_eq!(foot, Side::Left);
    assert!(
        (target.xy - Vector2::new(0.05, 0.1)).norm() < 1e-12,
        "{target:?}"
    );
    assert!(target.yaw.abs() < 1e-12);
    assert_eq!(planner.steps_pending(), 1);
    // Once the robot stands on the right foot with the left on its target, it lands.
    let feet = [pose(0.05, 0.1, 0.0), FEET[1]];
    let s = planner
        .update(
            &moved,
            HumanSupport::Double,
            0.25,
            feet,
            SupportPhase::Right,
            dt,
        )
        .support;
    assert_eq!(s, HumanSupport::Double);
    assert_eq!(planner.target(), None);
    // The right foot, 1 cm behind its clipped target (0.04 m behind the left foot at most),
    // is close enough: no step.
    let s = planner
        .update(&moved, HumanSupport::Double, 0.25, feet, double, dt)
        .support;
    assert_eq!(s, HumanSupport::Double);
    assert_eq!(planner.steps_pending(), 0);
    // The human brings the right foot up: the robot's right foot goes 0.1 m forward, which
    // is 0.05 m ahead of the left foot and within the envelope.
    let together = human([0.4, -0.1], [0.4, 0.1]);
    let s = planner
        .update(&together, HumanSupport::Double, 0.25, feet, double, dt)
        .support;
    assert_eq!(s, HumanSupport::Left);
    let (foot, target) = planner.target().unwrap();
    assert_eq!(foot, Side::Right);
    assert!(
        (target.xy - Vector2::new(0.1, 0.0)).norm() < 1e-12,
        "{target:?}"
    );
}

/// The human's toe-out is not copied: a foot that keeps its heading keeps the robot's.
#[test]
fn headings_are_relative_to_the_start() {
    let mut planner = FootstepPlanner::new(walking(), AREA);
    let mut frame = human([0.0, -0.1], [0.0, 0.1]);
    // Toes out by 0.3 rad on both feet.
    let v = |x: f64, y: f64| nalgebra::Vector3::new(x, y, 0.02);
    frame.set(
        HumanJoint::RToe,
        Some(v(0.15 * 0.3f64.cos(), -0.1 - 0.15 * 0.3f64.sin())),
    );
    frame.set(
        HumanJoint::LToe,
        Some(v(0.15 * 0.3f64.cos(), 0.1 + 0.15 * 0.3f64.sin())),
    );
    let s = planner
        .update(
            &frame,
            HumanSupport::Double,
            0.25,
            FEET,
            SupportPhase::Double,
            0.25,
        )
        .support;
    assert!(planner.origin.is_some(), "the footprints settled");
    assert_eq!(s, HumanSupport::Double);
    assert_eq!(planner.steps_pending(), 0);
}

/// A standing human with the right toe turned by `yaw` (rad) from +x.
fn right_toe_turned(yaw: f64) -> HumanFrame {
    let mut frame = human([0.0, -0.1], [0.0, 0.1]);
    let toe = nalgebra::Vector3::new(0.15 * yaw.cos(), -0.1 + 0.15 * yaw.sin(), 0.02);
    frame.set(HumanJoint::RToe, Some(toe));
    frame
}

/// A foot on the ground whose heading jitters within `pivot` (12° here, against the 5°
/// step threshold) is no step; one that turns past it is followed to its full heading.
#[test]
fn a_foot_on_the_ground_is_turned_only_by_a_pivot() {
    let mut planner = FootstepPlanner::new(walking(), AREA);
    let mut update = |yaw: f64| {
        let frame = right_toe_turned(yaw);
        let double = SupportPhase::Double;
        planner.update(&frame, HumanSupport::Double, 0.25, FEET, double, 0.01);
        (planner.steps_pending(), planner.target())
    };
    // The footprint settles over the first 0.2 s on the ground.
    for _ in 0..30 {
        assert_eq!(update(0.0), (0, None));
    }
    for k in 0..100 {
        let jitter = 0.21 * (0.3 * f64::from(k)).sin();
        assert_eq!(
            update(jitter),
            (0, None),
            "frame {k}: jitter {jitter:.3} rad"
        );
    }
    // 0.3 rad is past the 0.26 rad pivot: the right foot is stepped, to the envelope's
    // 0.15 rad (the left foot, its reference, stands at 0).
    let (pending, target) = update(-0.3);
    assert_eq!(pending, 1);
    let (foot, target) = target.expect("a step");
    assert_eq!(foot, Side::Right);
    assert!((target.yaw + 0.15).abs() < 1e-12, "{target:?}");
    // Once pivoted, the foot's heading is followed back within the pivot too.
    let (_, target) = update(-0.1);
    assert!((target.expect("the step").1.yaw + 0.1).abs() < 1e-12);
}

/// A foot on the ground whose ankle wanders within `slide` (4 cm here, against the 2 cm step
/// threshold at ratio 1) is no step; one that slides past it is followed.
#[test]
fn a_foot_on_the_ground_is_moved_only_by_a_slide() {
    let mut planner = FootstepPlanner::new(walking(), AREA);
    let mut update = |x: f64| {
        let frame = human([x, -0.1], [0.0, 0.1]);
        let double = SupportPhase::Double;
        planner.update(&frame, HumanSupport::Double, 1.0, FEET, double, 0.01);
        (planner.steps_pending(), planner.target())
    };
    for _ in 0..30 {
        assert_eq!(update(0.0), (0, None));
    }
    for k in 0..100 {
        let x = 0.04 * (0.3 * f64::from(k)).sin();
        assert_eq!(update(x), (0, None), "frame {k}: x {x:.3} m");
    }
    // 6 cm forward is past the 5 cm slide: a step, clipped to the envelope's 5 cm.
    let (pending, target) = update(0.06);
    assert_eq!(pending, 1);
    let (foot, target) = target.expect("a step");
    assert_eq!(foot, Side::Right);
    assert!((target.xy.x - 0.05).abs() < 1e-12, "{target:?}");
}

#[test]
fn a_human_on_one_leg_is_followed_after_the_stance_time() {
    // Without walking: the foot is lifted in place.
    let mut planner = FootstepPlanner::new(FootstepConfig::default(), AREA);
    let frame = human([0.0, -0.1], [0.0, 0.1]);
    let mut step = |human, phase, dt| planner.update(&frame, human, 0.25, FEET, phase, dt).support;
    step(HumanSupport::Double, SupportPhase::Double, 0.01);
    let mut support = HumanSupport::Double;
    for _ in 0..29 {
        support = step(HumanSupport::Right, SupportPhase::Double, 0.01);
    }
    assert_eq!(support, HumanSupport::Double, "0.29 s is not yet a stance");
    let support = step(HumanSupport::Right, SupportPhase::Double, 0.02);
    assert_eq!(support, HumanSupport::Right);
    // In single support with the foot on its target, it stays up while the human's is.
    let support = step(HumanSupport::Right, SupportPhase::Right, 0.01);
    assert_eq!(support, HumanSupport::Right);
    let support = step(HumanSupport::Double, SupportPhase::Right, 0.01);
    assert_eq!(support, HumanSupport::Double);
}

/// Looking ahead at the left foot lifted from 1 s to `end`, landing 0.4 m ahead of where
/// it stood (human world); lift lead 0.5 s, landing lead 0.4 s.
fn looking_ahead(config: FootstepConfig, end: f64) -> FootstepPlanner {
    let lift = FootLift {
        foot: Side::Left,
        start: 1.0,
        end,
        landing: Some(pose(0.4, 0.1, 0.0)),
    };
    let schedule =
        crate::imitation::walking::look_ahead::FootSchedule::from_lifts(&[lift]).unwrap();
    FootstepPlanner::new(config, AREA).with_look_ahead(FootLookAhead {
        schedule,
        lift_lead: 0.5,
        landing_lead: 0.4,
    })
}

/// One update at human time `t` (standing frame) with `human`'s support and the robot in
/// `phase`.
fn at(
    planner: &mut FootstepPlanner,
    t: f64,
    human: HumanSupport,
    phase: SupportPhase,
) -> StepRequest {
    let mut frame = super::tests::human([0.0, -0.1], [0.0, 0.1]);
    frame.time = t;
    planner.update(&frame, human, 0.25, FEET, phase, 0.01)
}

#[test]
fn looking_ahead_the_weight_shifts_before_the_lift_and_the_foot_lowers_before_the_landing() {
    use crate::imitation::phase::TakeOff;
    let (h, p) = (HumanSupport::Double, SupportPhase::Double);
    let shift = SupportPhase::DoubleToRight(TakeOff::ComToFoot);
    let mut planner = looking_ahead(FootstepConfig::default(), 3.0);
    let request = |support, lift| StepRequest { support, lift };
    assert_eq!(
        at(&mut planner, 0.4, h, p),
        request(h, true),
        "not within the lead"
    );
    let hold = request(HumanSupport::Right, false);
    assert_eq!(at(&mut planner, 0.6, h, p), hold, "shift, foot down");
    assert_eq!(at(&mut planner, 0.9, h, shift), hold);
    let (right, up) = (HumanSupport::Right, SupportPhase::Right);
    assert_eq!(at(&mut planner, 1.0, right, shift), request(right, true));
    assert_eq!(at(&mut planner, 2.0, right, up), request(right, true));
    // Landing at 3 s, within 0.4 s of 2.7 s: lowered now.
    assert_eq!(at(&mut planner, 2.7, right, up), request(h, true));
    // Back in double support while the human's foot is still up: not followed again.
    assert_eq!(at(&mut planner, 2.8, right, p), request(h, true));
}

#[test]
fn looking_ahead_a_stance_ended_before_the_robot_lifts_is_given_up() {
    use crate::imitation::phase::TakeOff;
    let shift = SupportPhase::DoubleToRight(TakeOff::ComToFoot);
    let (h, right) = (HumanSupport::Double, HumanSupport::Right);
    let mut planner = looking_ahead(FootstepConfig::default(), 1.5);
    assert_eq!(
        at(&mut planner, 0.6, h, SupportPhase::Double).support,
        right
    );
    assert_eq!(at(&mut planner, 1.2, right, shift).support, right);
    assert_eq!(at(&mut planner, 1.5, h, shift).support, h);
    // A stance shorter than the stance time is not followed at all.
    let mut planner = looking_ahead(FootstepConfig::default(), 1.25);
    for t in [0.6, 0.8, 1.0, 1.2] {
        assert_eq!(at(&mut planner, t, h, SupportPhase::Double).support, h);
    }
}

#[test]
fn looking_ahead_a_walking_foot_aims_where_the_human_foot_lands() {
    let (h, p) = (HumanSupport::Double, SupportPhase::Double);
    let mut planner = looking_ahead(walking(), 1.5);
    // Standing 0.25 s: the footprints settle.
    for k in 0..25 {
        at(&mut planner, 0.01 * f64::from(k), h, p);
    }
    // 0.4 m ahead, 0.1 m at ratio 0.25, clipped to the envelope's 0.05 m: a step before
    // the human lifts, the foot waiting for the human's.
    let request = at(&mut planner, 0.6, h, p);
    assert_eq!(request.support, HumanSupport::Right);
    assert!(!request.lift);
    let (foot, target) = planner.target().unwrap();
    assert_eq!(foot, Side::Left);
    assert!(
        (target.xy - Vector2::new(0.05, 0.1)).norm() < 1e-12,
        "{target:?}"
    );
}

/// A foot's heading is its toe's direction while the foot is near flat, the pelvis' while
/// it stands on its toes. The relevé is CMU 05_02's first frame: the left toe 5.7 cm
/// behind, 2.5 cm left of and 11.5 cm below the ankle, whose direction, atan2(0.025,
/// −0.057) = 2.73 rad, is no heading of that foot.
#[test]
fn a_foot_on_its_toes_takes_the_pelvis_heading() {
    let v = |x: f64, y: f64, z: f64| Some(nalgebra::Vector3::new(x, y, z));
    let mut frame = human([0.0, 0.0], [0.0, 0.1]);
    // The pelvis faces 0.3 rad: left hip − right hip = 0.2·(−sin 0.3, cos 0.3).
    let (s, c) = 0.3f64.sin_cos();
    frame.set(HumanJoint::RHip, v(0.1 * s, -0.1 * c, 0.9));
    frame.set(HumanJoint::LHip, v(-0.1 * s, 0.1 * c, 0.9));
    // The right foot flat (toe 6 cm below the ankle, 15 cm ahead), turned out 0.2 rad.
    let (s, c) = (-0.2f64).sin_cos();
    frame.set(HumanJoint::RToe, v(0.15 * c, 0.15 * s, 0.02));
    frame.set(HumanJoint::LToe, v(-0.057, 0.125, 0.08 - 0.115));
    let heading = |frame: &HumanFrame, foot| footprint(frame, foot).unwrap().yaw;
    assert!((heading(&frame, Side::Right) + 0.2).abs() < 1e-12);
    assert!((heading(&frame, Side::Left) - 0.3).abs() < 1e-12);
    // The toe 8 cm ahead: 40° below the ankle's level (6.7 cm down), its own heading 0;
    // 50° (9.5 cm down), the pelvis'.
    let below = |deg: f64| 0.08 * deg.to_radians().tan();
    frame.set(HumanJoint::LToe, v(0.08, 0.1, 0.08 - below(40.0)));
    assert!(heading(&frame, Side::Left).abs() < 1e-12);
    frame.set(HumanJoint::LToe, v(0.08, 0.1, 0.08 - below(50.0)));
    assert!((heading(&frame, Side::Left) - 0.3).abs() < 1e-12);
}
