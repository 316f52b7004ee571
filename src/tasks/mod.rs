//! Ready-made tasks for the solver, built from a [`Model`] by frame name: a frame's position
//! ([`PositionTask`]), orientation ([`OrientationTask`]) or both ([`PoseTask`]), the centre of
//! mass ([`ComTask`]), a joint posture ([`PostureTask`]) and a contact normal
//! ([`ContactNormalTask`], Di Fava et al. eq. 11), a frame's z axis along a direction
//! ([`UprightTask`], its heading free); inequality tasks ([`InequalityTask`]): the
//! CoM inside a support polygon ([`ComPolygonTask`]), capsule–capsule and capsule–plane
//! distances above a margin ([`CapsuleDistanceTask`], [`PlaneDistanceTask`]); the whole-body ZMP
//! inside a support polygon ([`ZmpTask`], rows of a frame's motion); and [`TaskSet`],
//! which stacks them in priority levels and drives the solver with them
//! ([`TaskModel`](crate::solver::driver::TaskModel)).
//!
//! Every task writes, for the configuration whose forward kinematics a [`ModelData`] holds, its
//! Jacobian `J` (rows × nv) and its error `e = x* − x(q)` in task units (metres, radians). The
//! position-level driver then solves `J q̇ = K e` level by level (see [`crate::solver::driver`]);
//! with `K Δt = 1` each iteration is a Gauss–Newton step. Orientation errors are rotation vectors
//! in the base frame, `e = log(R* Rᵀ)` (radians), whose rate is `−ω` to first order: `J` is then
//! the angular-velocity Jacobian.
//!
//! ```
//! use nalgebra::Vector3;
//! use taskstack::robots::nao;
//! use taskstack::solver::driver::{DriverSettings, PositionDriver};
//! use taskstack::solver::Solver;
//! use taskstack::tasks::{joint_bounds, ComTask, PositionTask, TaskSet};
//!
//! let model = nao::rfoot();
//! let hand = PositionTask::new(&model, "l_hand", Vector3::new(0.15, 0.1, 0.35))?;
//! let com = ComTask::ground(&model, [0.0, 0.05])?;
//! let mut set = TaskSet::new(&model)
//!     .level("balance", vec![Box::new(com)])
//!     .level("reach", vec![Box::new(hand)]);
//! let mut solver = Solver::new(&set.shape())?;
//! let mut driver = PositionDriver::new(&solver, DriverSettings::default())?;
//! let mut q = vec![0.0; model.nv()];
//! let report = driver.run(&mut solver, &mut set, &mut q, &joint_bounds(&model)?)?;
//! assert!(report.task_errors()[0] < 1e-4); // the CoM first
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod com;
mod com_polygon;
mod contact_normal;
mod distance;
mod inequality;
mod orientation;
mod pose;
mod position;
mod posture;
mod set;
mod upright;
mod zmp;

use std::any::Any;
use std::fmt::Debug;

use faer::{MatMut, MatRef};
use nalgebra::Vector3;
use thiserror::Error;

use crate::model::{Model, ModelData, ModelError};
use crate::solver::{JointBounds, SolverError};

pub use com::{ComTask, com_error, com_rows};
pub use com_polygon::{ComPolygonTask, convex_hull, hull_margin};
pub use contact_normal::ContactNormalTask;
pub use distance::{Capsule, CapsuleDistanceTask, PlaneDistanceTask, closest_segment_parameters};
pub use inequality::InequalityTask;
pub use orientation::{OrientationTask, orientation_error, orientation_rows};
pub use pose::PoseTask;
pub use position::{FramePoint, PositionTask, point_error, point_rows};
pub use posture::PostureTask;
pub use set::TaskSet;
pub use upright::{UprightTask, upright_error, upright_rows};
pub use zmp::{GRAVITY, ZmpTask};

/// `Ok` when an error output of `error.len()` entries holds a task's `rows` rows, else the
/// [`ModelError::OutputShape`] of an `error.len() × 1` output.
pub(crate) fn check_error_len(error: &[f64], rows: usize) -> Result<(), ModelError> {
    if error.len() < rows {
        return Err(ModelError::OutputShape {
            expected_rows: rows,
            expected_cols: 1,
            rows: error.len(),
            cols: 1,
        });
    }
    Ok(())
}

/// Errors of building or evaluating tasks.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum TaskError {
    /// A model error: unknown frame or variable, kinematics not computed, no mass.
    #[error(transparent)]
    Model(#[from] ModelError),
    /// A solver error: shapes, non-finite numbers.
    #[error(transparent)]
    Solver(#[from] SolverError),
    /// A target or reference that is NaN or infinite.
    #[error("task `{task}`: target is not finite")]
    NonFiniteTarget {
        /// The task's name.
        task: String,
    },
    /// A list of the wrong length (e.g. posture values for the joints named).
    #[error("task `{task}`: {got} values for {expected}")]
    WrongLength {
        /// The task's name.
        task: String,
        /// Expected length.
        expected: usize,
        /// Given length.
        got: usize,
    },
    /// A support polygon that is not convex and counter-clockwise, or a negative margin.
    #[error(
        "task `{task}`: the polygon must be convex, counter-clockwise seen from above, with a margin >= 0"
    )]
    InvalidPolygon {
        /// The task's name.
        task: String,
    },
    /// A geometric parameter out of range (a negative radius or margin, a zero normal).
    #[error("task `{task}`: {reason}")]
    InvalidGeometry {
        /// The task's name.
        task: String,
        /// What is wrong.
        reason: &'static str,
    },
    /// [`TaskSet::task_mut`] found no task of that name and type.
    #[error("no task `{0}` of the requested type")]
    UnknownTask(String),
}

/// A task: rows of the stack with their Jacobian and error.
pub trait Task: Debug + Any {
    /// Name of the task in the stack (unique inside a [`TaskSet`]).
    fn name(&self) -> &str;

    /// Number of rows.
    fn rows(&self) -> usize;

    /// Writes the `rows × nv` Jacobian into `jacobian` and the error `x* − x(q)` into `error`
    /// (`rows` entries), for the configuration `q` whose forward kinematics `data` holds.
    ///
    /// # Errors
    /// [`ModelError`] when `data` has no kinematics or the task's frame is not in `model`.
    fn write(
        &self,
        model: &Model,
        data: &ModelData,
        q: &[f64],
        jacobian: MatMut<'_, f64>,
        error: &mut [f64],
    ) -> Result<(), ModelError>;

    /// `self` as [`Any`], so that [`TaskSet::task_mut`] can hand back the concrete type.
    fn as_any_mut(&mut self) -> &mut dyn Any;
}

/// Writes `wᵀ J` into the one-row view `out`, for a 3 × nv Jacobian `j` (a direction times a
/// point or orientation Jacobian: a distance's or an alignment's rate).
pub(crate) fn combine_rows(weights: &Vector3<f64>, j: MatRef<'_, f64>, mut out: MatMut<'_, f64>) {
    for col in 0..out.ncols() {
        out[(0, col)] = (0..3).map(|r| weights[r] * j[(r, col)]).sum();
    }
}

/// The model's joint position and velocity limits as solver bounds (radians or metres, and per
/// second).
///
/// # Errors
/// [`SolverError`] when a limit is NaN or a lower limit is above its upper limit.
pub fn joint_bounds(model: &Model) -> Result<JointBounds, SolverError> {
    let variables = model.variables();
    let lower: Vec<f64> = variables.iter().map(|v| v.lower).collect();
    let upper: Vec<f64> = variables.iter().map(|v| v.upper).collect();
    let velocity: Vec<f64> = variables.iter().map(|v| v.velocity).collect();
    JointBounds::with_velocity(&lower, &upper, &velocity)
}

fn finite_target(name: &str, values: &[f64]) -> Result<(), TaskError> {
    match values.iter().all(|v| v.is_finite()) {
        true => Ok(()),
        false => Err(TaskError::NonFiniteTarget {
            task: name.to_owned(),
        }),
    }
}
