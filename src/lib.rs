#![doc = include_str!("../README.md")]
#![forbid(unsafe_code)]
#![deny(missing_docs)]
#![warn(missing_debug_implementations, unreachable_pub)]

pub mod batch;
pub mod error;
pub mod human;
pub mod imitation;
pub mod io;
pub mod model;
pub mod problem;
pub mod robots;
pub mod solver;
pub mod tasks;

// What a user touches most, at the crate root.
pub use error::Error;
pub use human::{HumanFrame, HumanJoint, Side};
pub use imitation::imitator::{ImitationError, Imitator, ImitatorConfig, RobotFrame};
pub use model::{Model, ModelData, ModelError};
pub use robots::{BipedProfile, ProfileError};
pub use solver::{JointBounds, Solver, SolverError, StackShape};
pub use tasks::{
    ComTask, OrientationTask, PoseTask, PositionTask, PostureTask, TaskError, TaskSet,
};

/// The linear-algebra crates of the API, re-exported so that users name the same versions
/// without adding them to their own `Cargo.toml`: `nalgebra` for geometry (points, rotations,
/// rigid transforms), `faer` for the solver's matrix views.
pub use faer;
pub use nalgebra;
/// The geometry types of the API (metres, radians): positions and offsets, planar points,
/// rotations and rigid placements.
pub use nalgebra::{IsometryMatrix3, Rotation3, Vector2, Vector3};
