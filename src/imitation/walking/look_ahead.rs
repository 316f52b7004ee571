//! Look-ahead for the feet (Di Fava et al. §III.C, applied to the feet): with the whole
//! recording at hand, the robot knows when the human will lift each foot, for how long, and where
//! it will put it down, before it happens.
//!
//! # The schedule
//!
//! [`FootSchedule::of_clip`] runs the online [`SupportDetector`] over the clip once (so the
//! offline and the online imitation see the same supports; these are also the feet's floor
//! contacts of [`crate::imitation::reference::contact_events`]) and keeps, per foot, the intervals `[start, end)` of the
//! human's clock (s) during which the foot is off the ground (the other foot alone supports the
//! body; an airborne frame keeps the last support, as the phase machine does), with the
//! footprint it lands on (human world frame: ankle ground point and heading, as
//! [`crate::imitation::walking::footsteps`] reads it).
//!
//! # What the robot does with it
//!
//! The [`FootstepPlanner`](crate::imitation::walking::footsteps::FootstepPlanner) looks ahead on the human's clock
//! by how long the robot's own motions take ([`MotionTimes`]): its weight shift (the *lift
//! lead*) for lift-offs, its lowering (the *landing lead*) for landings; first guesses
//! [`FootLookAhead::lift_lead`] and [`FootLookAhead::landing_lead`], then the robot's last timed
//! ones, so that no setting ties the look-ahead to one robot or one speed:
//!
//! * **Weight shift before the lift-off.** A lift of the human's foot that starts within the
//!   lift lead starts the robot's step now: the CoM moves over the other foot while the human
//!   still stands on both. The robot's foot leaves the ground only once the human's has
//!   ([`StepRequest::lift`]), so the robot lifts with the human instead of a weight shift later.
//!   Without walking, a lift is followed only if the robot, ready at the lift-off or a lift lead
//!   from now (whichever is later), can stand on one leg for at least
//!   [`FootstepConfig::stance_time`] of it; and not if the other foot has a longer such lift
//!   starting before the robot could be ready again (a lift lead and a landing lead after this
//!   one ends): a slow robot imitates the human's real one-leg stance, not the shuffle before
//!   it. A followed stance that the human ends before the robot's foot is off the ground is
//!   given up.
//! * **Lowering before the landing.** A lifted foot is lowered once the human's foot will be down
//!   within the landing lead, so it lands about when the human's does.
//! * **Walking toward the next footprint.** With walking on, a foot's target is the footprint
//!   where the human's foot will land as soon as its lift is within the lift lead, not the one
//!   it left: the step is planned a swing earlier, and its foot waits for the human's to lift.
//!
//! Units: seconds, metres, radians. The schedule is built once (it allocates); looking ahead
//! while stepping does not.
//!
//! [`FootstepConfig::stance_time`]: crate::imitation::walking::footsteps::FootstepConfig::stance_time
//! [`StepRequest::lift`]: crate::imitation::walking::footsteps::StepRequest::lift

use thiserror::Error;

use crate::human::{HumanFrame, Side};
use crate::imitation::phase::{Landing, SupportPhase, TakeOff};
use crate::imitation::reference::support::{
    HumanSupport, SupportConfig, SupportDetector, SupportError,
};
use crate::locomotion::GroundPose;

/// One lift of a human foot: off the ground from `start` to `end` (human clock, s).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FootLift {
    /// The lifted foot.
    pub foot: Side,
    /// Time of the first frame with the foot off the ground (s).
    pub start: f64,
    /// Time of the first frame with the foot back on the ground (s); infinite if the clip ends
    /// with it lifted.
    pub end: f64,
    /// Where it lands (human world frame, m and rad); `None` if it does not land, or the
    /// landing frame lacks the foot's joints.
    pub landing: Option<GroundPose>,
}

impl FootLift {
    /// How long the foot is off the ground (s).
    pub fn duration(&self) -> f64 {
        self.end - self.start
    }
}

/// Errors building a [`FootSchedule`].
#[derive(Debug, Error, PartialEq)]
pub enum LookAheadError {
    /// The support detector's settings are invalid.
    #[error(transparent)]
    Support(#[from] SupportError),
    /// A given lift is not a finite interval, or overlaps or precedes the foot's previous one.
    #[error(
        "lift {index} ({start} s to {end} s) must start after the foot's previous lift ends and end after it starts"
    )]
    LiftOrder {
        /// Index of the lift in the list given.
        index: usize,
        /// Its start (s).
        start: f64,
        /// Its end (s).
        end: f64,
    },
    /// A frame time is not finite or does not increase.
    #[error("frame {index} has time {time} s, not after the previous frame's {previous} s")]
    TimeOrder {
        /// Index of the frame in the clip.
        index: usize,
        /// Its time (s).
        time: f64,
        /// The previous frame's time (s).
        previous: f64,
    },
}

/// Every lift of each of the human's feet in a recording, in time order (see the module docs).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FootSchedule {
    /// Per foot ([`Side::index`]), the lifts in time order.
    lifts: [Vec<FootLift>; 2],
}

impl FootSchedule {
    /// The lifts of `frames` as the support detector with `support` sees them.
    ///
    /// # Errors
    /// [`LookAheadError::Support`] for invalid thresholds, [`LookAheadError::TimeOrder`] when a
    /// frame time is not finite or not after the previous one.
    pub fn of_clip(frames: &[HumanFrame], support: SupportConfig) -> Result<Self, LookAheadError> {
        let mut detector = SupportDetector::new(support)?;
        let mut schedule = Self::default();
        let mut up = [false; 2];
        let mut previous = f64::NEG_INFINITY;
        for (index, frame) in frames.iter().enumerate() {
            let time = frame.time;
            if !(time.is_finite() && time > previous) {
                return Err(LookAheadError::TimeOrder {
                    index,
                    time,
                    previous,
                });
            }
            previous = time;
            let now_up = match detector.update(frame) {
                HumanSupport::Airborne => up,
                support => support.feet().map(|down| !down),
            };
            for foot in Side::BOTH {
                let lifts = &mut schedule.lifts[foot.index()];
                match (up[foot.index()], now_up[foot.index()]) {
                    (false, true) => lifts.push(FootLift {
                        foot,
                        start: time,
                        end: f64::INFINITY,
                        landing: None,
                    }),
                    (true, false) => {
                        if let Some(lift) = lifts.last_mut() {
                            lift.end = time;
                            lift.landing = footprint(frame, foot);
                        }
                    }
                    _ => {}
                }
            }
            up = now_up;
        }
        Ok(schedule)
    }

    /// A schedule of given lifts (from another detector, or edited): per foot in time order,
    /// each with a finite start before its end (which may be infinite), not overlapping the
    /// foot's previous lift.
    ///
    /// # Errors
    /// [`LookAheadError::LiftOrder`] names the first lift that breaks the order.
    pub fn from_lifts(lifts: &[FootLift]) -> Result<Self, LookAheadError> {
        let mut schedule = Self::default();
        for (index, lift) in lifts.iter().enumerate() {
            let foot = &mut schedule.lifts[lift.foot.index()];
            let after = foot.last().map_or(f64::NEG_INFINITY, |l| l.end);
            if !(lift.start.is_finite() && lift.start >= after && lift.end > lift.start) {
                return Err(LookAheadError::LiftOrder {
                    index,
                    start: lift.start,
                    end: lift.end,
                });
            }
            foot.push(*lift);
        }
        Ok(schedule)
    }

    /// The lifts of `foot`, in time order.
    pub fn lifts(&self, foot: Side) -> &[FootLift] {
        &self.lifts[foot.index()]
    }

    /// The lifts of `foot` that end after `now` (s): the one under way, if any, and those to
    /// come, in time order.
    pub fn lifts_after(&self, foot: Side, now: f64) -> &[FootLift] {
        let lifts = &self.lifts[foot.index()];
        &lifts[lifts.partition_point(|l| l.end <= now)..]
    }

    /// The lift of `foot` under way at `now` or starting within `lead` after it (s), if any.
    pub fn lift_within(&self, foot: Side, now: f64, lead: f64) -> Option<&FootLift> {
        (self.lifts_after(foot, now).first()).filter(|l| l.start <= now + lead)
    }
}

/// The feet's look-ahead of the offline mode: the recording's schedule and how far ahead the
/// robot acts. The leads are durations of the robot's own motions, not of the human's, so they
/// are learnt as the robot moves ([`MotionTimes`]); the values here are the first guesses, what
/// a NAO takes at a tenth of its rated leg joint speeds (Poubel et al.'s setting).
#[derive(Clone, Debug, PartialEq)]
pub struct FootLookAhead {
    /// The human's foot lifts.
    pub schedule: FootSchedule,
    /// How long before the human lifts a foot the robot starts shifting its weight onto the
    /// other (s), until it has timed a weight shift of its own. Default 1.5: the NAO's weight
    /// shift takes 1.3–2 s.
    pub lift_lead: f64,
    /// How long before the human puts a foot down the robot starts lowering it (s), until it has
    /// timed a lowering of its own. Default 0.8: the NAO's lowering from the lift height takes
    /// about as long.
    pub landing_lead: f64,
}

impl FootLookAhead {
    /// The default lift lead (s).
    pub const DEFAULT_LIFT_LEAD: f64 = 1.5;
    /// The default landing lead (s).
    pub const DEFAULT_LANDING_LEAD: f64 = 0.8;

    /// `schedule` with the default leads.
    pub fn new(schedule: FootSchedule) -> Self {
        Self {
            schedule,
            lift_lead: Self::DEFAULT_LIFT_LEAD,
            landing_lead: Self::DEFAULT_LANDING_LEAD,
        }
    }

    /// The first lead that is not finite and ≥ 0 (name and value).
    pub fn invalid_field(&self) -> Option<(&'static str, f64)> {
        [
            ("look_ahead.lift_lead", self.lift_lead),
            ("look_ahead.landing_lead", self.landing_lead),
        ]
        .into_iter()
        .find(|(_, v)| !(v.is_finite() && *v >= 0.0))
    }
}

/// How long the robot's own weight shift and lowering take (s, robot clock): the leads the
/// look-ahead uses. They start at [`FootLookAhead`]'s and become the duration of the robot's
/// last timed weight shift ("CoM to foot") and of its last lowering ("Lower foot"). A weight shift
/// is timed only when it, not the wait for the human's lift-off, decided when the foot lifted:
/// the lift was allowed at least one update before the foot lifted. (Timing a held shift would
/// lengthen the lead, which holds the next shift longer: the lead would only grow.) A shift given
/// up after the lift was allowed (the human's stance ended first) took longer than it ran: the
/// lift lead becomes at least that.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MotionTimes {
    /// The weight shift's duration (s).
    pub shift: f64,
    /// The lowering's duration (s).
    pub lowering: f64,
    /// The robot's clock (s).
    clock: f64,
    /// The phase last observed, and since when (robot clock).
    current: Option<(SupportPhase, f64)>,
    /// When, in the current weight shift, the lift was first allowed (robot clock).
    open_since: Option<f64>,
    /// The robot clock of the last request.
    last_request: f64,
}

impl MotionTimes {
    /// The first guesses of `ahead`.
    pub fn new(ahead: &FootLookAhead) -> Self {
        Self {
            shift: ahead.lift_lead,
            lowering: ahead.landing_lead,
            clock: 0.0,
            current: None,
            open_since: None,
            last_request: f64::NEG_INFINITY,
        }
    }

    /// The robot is in `phase` (the phase machine's output of the last update), `dt` (s) after
    /// the last observation.
    pub fn observe(&mut self, phase: SupportPhase, dt: f64) {
        self.clock += dt;
        let Some((previous, since)) = self.current else {
            self.current = Some((phase, self.clock));
            return;
        };
        if previous == phase {
            return;
        }
        let took = self.clock - since;
        match (
            previous.take_off(),
            phase.take_off(),
            previous.landing(),
            phase.landing(),
        ) {
            (Some(TakeOff::ComToFoot), Some(TakeOff::LiftFoot), ..)
                if self.open_since.is_some_and(|t| t < self.last_request) =>
            {
                self.shift = took;
            }
            // Given up with the lift allowed: the shift takes longer than that.
            (Some(TakeOff::ComToFoot), None, ..) if self.open_since.is_some() => {
                self.shift = self.shift.max(took);
            }
            (.., Some(Landing::LowerFoot), Some(Landing::ComToMiddle)) => self.lowering = took,
            _ => {}
        }
        self.current = Some((phase, self.clock));
        self.open_since = None;
    }

    /// The planner asked the phase machine for a step with the foot allowed to lift or not.
    pub fn requested(&mut self, lift: bool) {
        self.last_request = self.clock;
        if lift && self.current.is_some_and(|(p, _)| p.shifts_weight()) {
            self.open_since.get_or_insert(self.clock);
        }
    }
}

/// The footprint of a human foot: ankle ground point and heading, the foot's own while it is
/// near flat ([`HumanFrame::foot_heading`]: the toe at least 3 cm ahead and at most 45° below
/// the ankle), else the pelvis'. A walk that started from CMU 05_02's foot in relevé, read as
/// pointing backward, turned the robot 84° left while the human turned 43° right.
pub(crate) fn footprint(frame: &HumanFrame, foot: Side) -> Option<GroundPose> {
    let ankle = frame.get(foot.ankle())?;
    let yaw = (frame.foot_heading(foot, 0.03, 1.0)).or_else(|| frame.pelvis_heading(0.0))?;
    Some(GroundPose {
        xy: ankle.xy(),
        yaw,
    })
}

#[cfg(test)]
mod tests {
    use nalgebra::{Vector2, Vector3};

    use super::*;
    use crate::human::HumanJoint;

    /// A human standing with the ankles 0.2 m apart who, from 0.5 s to 1.1 s, lifts the left
    /// foot 0.2 m, carries it 0.3 m forward and puts it down there; 100 frames per second.
    fn step_clip() -> Vec<HumanFrame> {
        (0..200)
            .map(|i| {
                let t = i as f64 * 0.01;
                let mut frame = HumanFrame::new(t);
                let s = ((t - 0.5) / 0.6).clamp(0.0, 1.0);
                let lift = if (0.5..1.1).contains(&t) { 0.2 } else { 0.0 };
                let left = Vector3::new(0.3 * s, 0.1, 0.08 + lift);
                let right = Vector3::new(0.0, -0.1, 0.08);
                let toe = Vector3::new(0.15, 0.0, -0.06);
                frame.set(HumanJoint::LAnkle, Some(left));
                frame.set(HumanJoint::LToe, Some(left + toe));
                frame.set(HumanJoint::RAnkle, Some(right));
                frame.set(HumanJoint::RToe, Some(right + toe));
                frame.set(HumanJoint::LHip, Some(Vector3::new(0.0, 0.1, 0.9)));
                frame.set(HumanJoint::RHip, Some(Vector3::new(0.0, -0.1, 0.9)));
                frame
            })
            .collect()
    }

    #[test]
    fn a_step_of_the_left_foot_is_one_lift_with_its_landing() {
        let schedule = FootSchedule::of_clip(&step_clip(), SupportConfig::optical()).unwrap();
        assert!(schedule.lifts(Side::Right).is_empty());
        let [lift] = schedule.lifts(Side::Left) else {
            panic!("{schedule:?}");
        };
        // The detector's 30 ms dwell, on 10 ms frames.
        assert!((0.5..=0.55).contains(&lift.start), "{lift:?}");
        assert!((1.1..=1.15).contains(&lift.end), "{lift:?}");
        let landing = lift.landing.unwrap();
        assert!(
            (landing.xy - Vector2::new(0.3, 0.1)).norm() < 1e-9,
            "{landing:?}"
        );
        assert!(landing.yaw.abs() < 1e-9);
        // Looking ahead: seen 0.2 s before it starts, and while it lasts; not after.
        assert_eq!(schedule.lift_within(Side::Left, 0.2, 0.2), None);
        assert_eq!(schedule.lift_within(Side::Left, 0.4, 0.2), Some(lift));
        assert_eq!(schedule.lift_within(Side::Left, 1.0, 0.0), Some(lift));
        assert_eq!(schedule.lift_within(Side::Left, lift.end, 1.0), None);
    }

    #[test]
    fn frames_out_of_order_are_refused() {
        let mut clip = step_clip();
        clip[10].time = clip[9].time;
        assert!(matches!(
            FootSchedule::of_clip(&clip, SupportConfig::optical()),
            Err(LookAheadError::TimeOrder { index: 10, .. })
        ));
        clip[10].time = f64::NAN;
        assert!(FootSchedule::of_clip(&clip, SupportConfig::optical()).is_err());
        let bad = SupportConfig {
            height_on: f64::NAN,
            ..SupportConfig::optical()
        };
        assert!(matches!(
            FootSchedule::of_clip(&clip, bad),
            Err(LookAheadError::Support(_))
        ));
    }

    #[test]
    fn given_lifts_must_be_ordered_intervals() {
        let lift = |foot, start, end| FootLift {
            foot,
            start,
            end,
            landing: None,
        };
        let good = [
            lift(Side::Left, 1.0, 2.0),
            lift(Side::Right, 1.5, 2.5),
            lift(Side::Left, 2.0, f64::INFINITY),
        ];
        let schedule = FootSchedule::from_lifts(&good).unwrap();
        assert_eq!(schedule.lifts(Side::Left).len(), 2);
        assert_eq!(schedule.lifts(Side::Right), &good[1..2]);
        for (bad, index) in [
            (vec![lift(Side::Left, 1.0, 1.0)], 0),
            (vec![lift(Side::Left, f64::NAN, 1.0)], 0),
            (
                vec![lift(Side::Left, 1.0, 2.0), lift(Side::Left, 1.5, 3.0)],
                1,
            ),
        ] {
            assert!(matches!(
                FootSchedule::from_lifts(&bad),
                Err(LookAheadError::LiftOrder { index: i, .. }) if i == index
            ));
        }
    }

    #[test]
    fn motion_times_are_learnt_from_unheld_shifts_and_lowerings() {
        use crate::imitation::phase::{Landing, SupportPhase as P, TakeOff};
        let mut times = MotionTimes::new(&FootLookAhead::new(FootSchedule::default()));
        let guess = (times.shift, times.lowering);
        // Runs `phase` for `seconds` in 10 ms updates with the lift allowed or not.
        let run = |times: &mut MotionTimes, phase, seconds: f64, lift| {
            for _ in 0..(seconds / 0.01).round() as usize {
                times.observe(phase, 0.01);
                times.requested(lift);
            }
        };
        let (shift, lift) = (
            P::DoubleToRight(TakeOff::ComToFoot),
            P::DoubleToRight(TakeOff::LiftFoot),
        );
        // A shift held for the human's lift-off, lifting as soon as allowed: not timed.
        run(&mut times, P::Double, 0.1, true);
        run(&mut times, shift, 1.0, false);
        run(&mut times, shift, 0.01, true);
        run(&mut times, lift, 0.5, true);
        assert_eq!((times.shift, times.lowering), guess);
        // A shift that ends 0.7 s after it starts, the lift allowed throughout: timed.
        run(&mut times, P::Right, 0.2, true);
        run(&mut times, P::RightToDouble(Landing::LowerFoot), 0.45, true);
        run(
            &mut times,
            P::RightToDouble(Landing::ComToMiddle),
            0.3,
            true,
        );
        run(&mut times, P::Double, 0.1, true);
        run(&mut times, P::DoubleToLeft(TakeOff::ComToFoot), 0.7, true);
        run(&mut times, P::DoubleToLeft(TakeOff::LiftFoot), 0.1, true);
        assert!((times.shift - 0.7).abs() < 1e-9, "{times:?}");
        assert!((times.lowering - 0.45).abs() < 1e-9, "{times:?}");
        // A shift given up 1.2 s after it started, the lift allowed for its last 0.5 s: at least
        // 1.2 s. One given up sooner changes nothing.
        run(&mut times, P::Double, 0.1, true);
        run(&mut times, shift, 0.7, false);
        run(&mut times, shift, 0.5, true);
        run(&mut times, P::Double, 0.1, true);
        assert!((times.shift - 1.2).abs() < 1e-9, "{times:?}");
        run(&mut times, shift, 0.3, true);
        run(&mut times, P::Double, 0.1, true);
        assert!((times.shift - 1.2).abs() < 1e-9, "{times:?}");
    }
}
