//! The online imitator: one human frame in, one robot posture out, by either of two methods
//! ([`ImitationMethod`]): Poubel et al.'s task tables (support phases and [`crate::imitation::phase::tables`]) or Koenemann et al.'s
//! posture mapping and stabilization ([`crate::imitation::koenemann`]). Both give the same
//! [`RobotFrame`], so the outputs and metrics of the two compare directly.
//!
//! Everything is allocated in [`Imitator::new`]; [`Imitator::step`] allocates nothing.
//!
//! World frame: the right sole's frame at the first frame (x forward, y left, z up, metres).

use crate::human::{HumanFrame, Side};
use crate::imitation::koenemann::imitator::KoenemannImitator;
use crate::imitation::phase::SupportPhase;
use crate::imitation::phase::tables::TaskTable;
use crate::imitation::poubel::PoubelImitator;
use crate::imitation::state::Shared;
use crate::robots::BipedProfile;
use crate::solver::JointBounds;

// The paths these had before `imitation` re-exported them; kept for one release.
#[doc(hidden)]
pub use crate::imitation::config::{ImitationMethod, ImitatorConfig};
#[doc(hidden)]
pub use crate::imitation::error::ImitationError;
#[doc(hidden)]
pub use crate::imitation::output::{EFFECTORS, RobotFrame};

/// The online imitator.
#[derive(Debug)]
pub struct Imitator(Method);

#[derive(Debug)]
enum Method {
    Poubel(Box<PoubelImitator>),
    Koenemann(Box<KoenemannImitator>),
}

impl Imitator {
    /// An imitator for the biped described by `profile` (checked with
    /// [`BipedProfile::validate`]), by the method of `config.method`.
    ///
    /// # Errors
    /// [`ImitationError`] naming the faulty setting, profile field or table.
    pub fn new(profile: BipedProfile, config: ImitatorConfig) -> Result<Self, ImitationError> {
        config.validate()?;
        profile.validate()?;
        // The shared settings' defaults depend on the method (the legs' velocity fraction):
        // `config` keeps it while each method takes its own settings.
        Ok(Imitator(match config.method.clone() {
            ImitationMethod::Poubel(method) => {
                Method::Poubel(Box::new(PoubelImitator::new(profile, &config, method)?))
            }
            ImitationMethod::Koenemann(method) => {
                Method::Koenemann(Box::new(KoenemannImitator::new(profile, &config, method)?))
            }
        }))
    }

    fn shared(&self) -> &Shared {
        match &self.0 {
            Method::Poubel(p) => &p.shared,
            Method::Koenemann(k) => &k.shared,
        }
    }

    /// Imitates one human frame: returns the robot's posture for it. With hand supports
    /// ([`PoubelConfig::hand_supports`](crate::imitation::poubel::PoubelConfig::hand_supports)), feed the same frame again while the output's
    /// [`RobotFrame::awaiting_contact`] is set: the human's clock pauses while a hand is placed.
    ///
    /// # Errors
    /// [`ImitationError::TimeGoesBack`] when `frame.time` is below the previous frame's, a
    /// scaler error for a non-finite time or joint, and solver or model errors (never expected
    /// from valid input; the imitator is then in an unspecified but safe state).
    pub fn step(&mut self, frame: &HumanFrame) -> Result<&RobotFrame, ImitationError> {
        match &mut self.0 {
            Method::Poubel(p) => p.step(frame),
            Method::Koenemann(k) => k.step(frame),
        }
    }

    /// Names of the joint angles of [`RobotFrame::q`] (the model's variable names).
    pub fn variable_names(&self) -> impl Iterator<Item = &str> {
        (self.profile().model(Side::Right).variables().iter()).map(|v| v.name.as_str())
    }

    /// The current phase.
    pub fn phase(&self) -> SupportPhase {
        self.shared().output.phase
    }

    /// The task table of `phase`; `None` for a method without tables (Koenemann et al.'s).
    pub fn table(&self, phase: SupportPhase) -> Option<&TaskTable> {
        match &self.0 {
            Method::Poubel(p) => Some(p.table(phase)),
            Method::Koenemann(_) => None,
        }
    }

    /// Which of [`EFFECTORS`] the method tracks in `phase`, i.e. whose distance to
    /// [`RobotFrame::reference`] is its tracking error: those of the phase's table for Poubel et
    /// al.'s method (the hands, and the free ankle in single support); the hands and both feet
    /// always for Koenemann et al.'s (their mapped targets, as in the paper's Fig. 7 and 8).
    pub fn tracked_effectors(&self, phase: SupportPhase) -> [bool; 4] {
        match &self.0 {
            Method::Poubel(p) => p.tracked_effectors(phase),
            Method::Koenemann(_) => [true; 4],
        }
    }

    /// The task names of `phase`'s table, in stack order (none for a method without tables).
    pub fn task_names(&self, phase: SupportPhase) -> impl Iterator<Item = String> + '_ {
        let poubel = match &self.0 {
            Method::Poubel(p) => Some(p.task_names(phase)),
            Method::Koenemann(_) => None,
        };
        poubel.into_iter().flatten()
    }

    /// The robot profile (models rooted at either sole, frames, feet).
    pub fn profile(&self) -> &BipedProfile {
        &self.shared().profile
    }

    /// The joint bounds the output respects: position limits, and the rated velocities times
    /// the velocity fraction (legs; the walking velocity fraction when the feet follow the
    /// human's) or the upper-body velocity fraction (the other joints).
    pub fn bounds(&self) -> &JointBounds {
        match &self.0 {
            Method::Poubel(p) => p.bounds(),
            Method::Koenemann(k) => &k.shared.bounds,
        }
    }

    /// Feet not on their targets (the scaled human footprints) after the last frame: the steps
    /// the robot still has to take (0, 1 or 2; always 0 for Koenemann et al.'s method, which
    /// steps where the mapped foot goes).
    pub fn pending_steps(&self) -> usize {
        self.shared().output.pending_steps
    }

    /// The velocity fraction in use (legs).
    pub fn velocity_fraction(&self) -> f64 {
        self.shared().velocity_fraction
    }
}
