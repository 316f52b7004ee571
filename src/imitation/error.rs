//! The imitator's error: everything that can go wrong building an [`Imitator`](crate::imitation::imitator::Imitator)
//! or stepping it, each part's error wrapped.

use thiserror::Error;

use crate::imitation::phase::PhaseError;
use crate::imitation::phase::tables::TableError;
use crate::imitation::reference::scaler::ScaleError;
use crate::imitation::reference::support::SupportError;
use crate::locomotion::LocomotionError;
use crate::model::ModelError;
use crate::robots::ProfileError;
use crate::robots::sway::SwayError;
use crate::solver::SolverError;
use crate::tasks::TaskError;

/// Errors of the imitator.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum ImitationError {
    /// A model query failed (a frame the tables name is missing from the model, …).
    #[error(transparent)]
    Model(#[from] ModelError),
    /// The solver refused its input.
    #[error(transparent)]
    Solver(#[from] SolverError),
    /// The scaler refused its input.
    #[error(transparent)]
    Scale(#[from] ScaleError),
    /// The robot profile is invalid, or its joint-angle map refused its input.
    #[error(transparent)]
    Profile(#[from] ProfileError),
    /// A task table is invalid.
    #[error(transparent)]
    Table(#[from] TableError),
    /// A table's constraint could not be built (e.g. a body's geometry).
    #[error(transparent)]
    Task(#[from] TaskError),
    /// Invalid phase-machine configuration.
    #[error(transparent)]
    Phase(#[from] PhaseError),
    /// The walking pattern generator refused a step or its settings.
    #[error(transparent)]
    Locomotion(#[from] LocomotionError),
    /// Invalid support-detection configuration.
    #[error(transparent)]
    Support(#[from] SupportError),
    /// The sway shaper refused a command (never expected: the imitator's are finite and in
    /// time order).
    #[error(transparent)]
    Sway(#[from] SwayError),
    /// A configuration value out of range.
    #[error("invalid {name} = {value}: {reason}")]
    InvalidParameter {
        /// Parameter name.
        name: &'static str,
        /// The value.
        value: f64,
        /// The valid range.
        reason: &'static str,
    },
    /// Frame times must increase.
    #[error("frame time {time} s does not follow the previous frame's {previous} s")]
    TimeGoesBack {
        /// This frame's time (s).
        time: f64,
        /// The previous frame's time (s).
        previous: f64,
    },
}

impl ImitationError {
    /// The first of `settings` (`(name, value, reason)`, in order) that is set and not finite
    /// and > 0, as [`ImitationError::InvalidParameter`]; unset ones are the defaults.
    pub(crate) fn check_positive(
        settings: &[(&'static str, Option<f64>, &'static str)],
    ) -> Result<(), Self> {
        let bad = |&(name, value, reason): &(&'static str, Option<f64>, &'static str)| {
            let value = value.filter(|v| !(v.is_finite() && *v > 0.0))?;
            Some(ImitationError::InvalidParameter {
                name,
                value,
                reason,
            })
        };
        settings.iter().find_map(bad).map_or(Ok(()), Err)
    }
}
