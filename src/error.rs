//! [`Error`](enum@Error): every error of the crate in one type, for applications that handle them alike
//! (`?` converts each module's error into it). Library code returns the module errors, which
//! say more precisely what can fail.

use thiserror::Error;

use crate::batch::BatchError;
use crate::imitation::ImitationError;
use crate::imitation::phase::PhaseError;
use crate::imitation::phase::tables::TableError;
use crate::imitation::reference::scaler::ScaleError;
use crate::imitation::reference::support::SupportError;
use crate::io::bvh::BvhError;
use crate::io::clip::ClipError;
use crate::io::kinect::KinectError;
use crate::locomotion::{LocomotionError, WalkerError};
use crate::model::{DhError, ModelError, UrdfError};
use crate::problem::ProblemError;
use crate::robots::ProfileError;
use crate::solver::SolverError;
use crate::tasks::TaskError;

/// Any error of the crate, wrapping the module error it came from (its message unchanged).
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum Error {
    /// [`SolverError`].
    #[error(transparent)]
    Solver(#[from] SolverError),
    /// [`ModelError`].
    #[error(transparent)]
    Model(#[from] ModelError),
    /// [`DhError`].
    #[error(transparent)]
    Dh(#[from] DhError),
    /// [`UrdfError`].
    #[error(transparent)]
    Urdf(#[from] UrdfError),
    /// [`TaskError`].
    #[error(transparent)]
    Task(#[from] TaskError),
    /// [`ProfileError`].
    #[error(transparent)]
    Profile(#[from] ProfileError),
    /// [`LocomotionError`].
    #[error(transparent)]
    Locomotion(#[from] LocomotionError),
    /// [`WalkerError`].
    #[error(transparent)]
    Walker(#[from] WalkerError),
    /// [`ImitationError`].
    #[error(transparent)]
    Imitation(#[from] ImitationError),
    /// [`ScaleError`].
    #[error(transparent)]
    Scale(#[from] ScaleError),
    /// [`PhaseError`].
    #[error(transparent)]
    Phase(#[from] PhaseError),
    /// [`SupportError`].
    #[error(transparent)]
    Support(#[from] SupportError),
    /// [`TableError`].
    #[error(transparent)]
    Table(#[from] TableError),
    /// [`BvhError`].
    #[error(transparent)]
    Bvh(#[from] BvhError),
    /// [`KinectError`].
    #[error(transparent)]
    Kinect(#[from] KinectError),
    /// [`ClipError`].
    #[error(transparent)]
    Clip(#[from] ClipError),
    /// [`BatchError`].
    #[error(transparent)]
    Batch(#[from] BatchError),
    /// [`ProblemError`].
    #[error(transparent)]
    Problem(#[from] ProblemError),
}
