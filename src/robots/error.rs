//! What a robot profile, a joint-angle map or a robot's self-collision bodies can fail on.

use thiserror::Error;

use crate::model::{ModelError, UrdfError};

/// Errors of a joint-angle map and of a profile.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum ProfileError {
    /// A model query failed (names the frame or variable).
    #[error("robot model: {0}")]
    Model(#[from] ModelError),
    /// The robot description could not be loaded.
    #[error("robot description: {0}")]
    Urdf(#[from] UrdfError),
    /// The profile file could not be read.
    #[error("cannot read {path}: {message}")]
    Io {
        /// The file.
        path: String,
        /// What went wrong.
        message: String,
    },
    /// The profile TOML is malformed (the message names the line and field).
    #[error("profile {path}: {message}")]
    Syntax {
        /// The file, or `<text>`.
        path: String,
        /// The parser's message.
        message: String,
    },
    /// A value of the profile is invalid (names the field).
    #[error("profile field {field}: {reason}")]
    Invalid {
        /// The field, e.g. `feet.left.outline`.
        field: String,
        /// Why.
        reason: String,
    },
    /// An output slice does not have one entry per model variable.
    #[error("joint-angle output has {got} entries, the model has {expected} variables")]
    WrongLength {
        /// Number of variables of the model.
        expected: usize,
        /// Length of the given slice.
        got: usize,
    },
}
