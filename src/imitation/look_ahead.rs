//! Look-ahead for the feet (Di Fava et al. §III.C, applied to the feet): with the whole
//! recording at hand, the robot knows when the human will lift each foot, for how long, and where
//! it will put it down, before it happens.
//!
//! # The schedule
//!
//! [`FootSchedule::of_clip`] runs the online [`SupportDetector`] over the clip once (so the
//! offline and the online imitation see the same supports; these are also the feet's floor
//! contacts of [`super::contact_events`]) and keeps, per foot, the intervals `[start, end)` of the
//! human's clock (s) during which the foot is off the ground (the other foot alone supports the
//! body; an airborne frame keeps the last support, as the phase machine does), with the
//! footprint it lands on (human world frame: ankle ground point and heading, as
//! [`super::footsteps`] reads it).
//!
//! # What the robot does with it
//!
//! The [`FootstepPlanner`](super::footsteps::FootstepPlanner) looks [`FootLookAhead::lead`]
//! seconds ahead on the human's clock:
//!
//! * **Weight shift before the lift-off.** A lift of the human's foot that starts within the lead
//!   (and, without walking, lasts at least [`FootstepConfig::stance_time`]) starts the robot's
//!   step now: the CoM moves over the other foot while the human still stands on both. The
//!   robot's foot leaves the ground only once the human's has ([`StepRequest::lift`]), so the
//!   robot lifts with the human instead of a weight shift later.
//! * **Lowering before the landing.** A lifted foot is lowered once the human's foot will be down
//!   within the lead, so it lands about when the human's does.
//! * **Walking toward the next footprint.** With walking on, a foot's target is the footprint
//!   where the human's foot will land as soon as its lift is within the lead, not the one it
//!   left: the step is planned a swing earlier.
//!
//! Units: seconds, metres, radians. The schedule is built once (it allocates); looking ahead
//! while stepping does not.
//!
//! [`FootstepConfig::stance_time`]: super::footsteps::FootstepConfig::stance_time
//! [`StepRequest::lift`]: super::footsteps::StepRequest::lift

use thiserror::Error;

use super::footsteps::{GroundPose, footprint};
use super::support::{HumanSupport, SupportConfig, SupportDetector, SupportError};
use crate::human::{HumanFrame, Side};

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
                HumanSupport::Double => [false, false],
                HumanSupport::Right => [true, false],
                HumanSupport::Left => [false, true],
                HumanSupport::Airborne => up,
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

    /// The lifts of `foot`, in time order.
    pub fn lifts(&self, foot: Side) -> &[FootLift] {
        &self.lifts[foot.index()]
    }

    /// The lift of `foot` under way at `now` or starting within `lead` after it (s), if any.
    pub fn lift_within(&self, foot: Side, now: f64, lead: f64) -> Option<&FootLift> {
        let lifts = &self.lifts[foot.index()];
        let next = lifts.partition_point(|l| l.end <= now);
        lifts.get(next).filter(|l| l.start <= now + lead)
    }
}

/// The feet's look-ahead of the offline mode: the recording's schedule and how far ahead the
/// robot acts. The leads are durations of the robot's own motions, not of the human's: the
/// defaults are what a NAO takes at a tenth of its rated leg joint speeds (Poubel et al.'s
/// setting); a faster robot wants shorter ones.
#[derive(Clone, Debug, PartialEq)]
pub struct FootLookAhead {
    /// The human's foot lifts.
    pub schedule: FootSchedule,
    /// How long before the human lifts a foot the robot starts shifting its weight onto the
    /// other (s, human clock). Default 1.5: the NAO's weight shift takes 1.5–2 s.
    pub lift_lead: f64,
    /// How long before the human puts a foot down the robot starts lowering it (s, human clock).
    /// Default 0.8: the NAO's lowering from the lift height takes about as long.
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
