//! The centre of mass at a target.

use std::any::Any;

use faer::MatMut;
use nalgebra::Vector3;

use super::{Task, TaskError, finite_target};
use crate::model::{Model, ModelData, ModelError};

/// The whole-body centre of mass at a target in the base frame (m): its ground projection (x, y;
/// [`ComTask::ground`], the balance task of a robot rooted at a sole) or all of x, y, z
/// ([`ComTask::new`]). Named `"com"` unless [`ComTask::named`] says otherwise.
#[derive(Debug, Clone, PartialEq)]
pub struct ComTask {
    name: String,
    rows: usize,
    /// Target (m, base frame); z is read only by a three-row task.
    pub target: Vector3<f64>,
}

impl ComTask {
    /// The CoM at `target` (x, y, z).
    ///
    /// # Errors
    /// [`TaskError::Model`] when the model has no mass, [`TaskError::NonFiniteTarget`].
    pub fn new(model: &Model, target: Vector3<f64>) -> Result<Self, TaskError> {
        Self::with_rows(model, 3, target)
    }

    /// The CoM's ground projection at `xy` (x, y), its height free.
    ///
    /// # Errors
    /// As [`ComTask::new`].
    pub fn ground(model: &Model, xy: [f64; 2]) -> Result<Self, TaskError> {
        Self::with_rows(model, 2, Vector3::new(xy[0], xy[1], 0.0))
    }

    fn with_rows(model: &Model, rows: usize, target: Vector3<f64>) -> Result<Self, TaskError> {
        finite_target("com", target.as_slice())?;
        if model.total_mass() <= 0.0 {
            return Err(ModelError::NoMass.into());
        }
        Ok(Self {
            name: "com".to_owned(),
            rows,
            target,
        })
    }
}

impl ComTask {
    /// Another name in the stack (default `"com"`): a second CoM task at another level.
    pub fn named(mut self, name: &str) -> Self {
        self.name = name.to_owned();
        self
    }
}

/// The first `target.len()` (2: the ground projection, or 3) rows of the centre of mass at
/// `target` (base frame, m): the CoM Jacobian rows into `jacobian` and `e = c* − c(q)` into
/// `error`, for the forward kinematics in `data`. The rows of [`ComTask`], for task models that
/// build their own stacks.
///
/// # Errors
/// [`ModelError`] when `data` has no kinematics or the model has no mass.
pub fn com_rows(
    model: &Model,
    data: &ModelData,
    target: &[f64],
    jacobian: MatMut<'_, f64>,
    error: &mut [f64],
) -> Result<(), ModelError> {
    model.com_jacobian_rows(data, target.len(), jacobian)?;
    com_error(model, data, target, error)
}

/// The error `e = c* − c(q)` of [`com_rows`] alone (m, `target.len()` entries): for a task
/// model that measures its tasks after its last step, where no Jacobian is needed.
///
/// # Errors
/// [`ModelError`] when `data` has no kinematics, the model has no mass, `target` has not 1 to 3
/// entries or `error` fewer.
pub fn com_error(
    model: &Model,
    data: &ModelData,
    target: &[f64],
    error: &mut [f64],
) -> Result<(), ModelError> {
    if target.is_empty() || target.len() > 3 {
        return Err(ModelError::BadRowCount(target.len()));
    }
    super::check_error_len(error, target.len())?;
    let c = model.com(data)?;
    for (r, t) in target.iter().enumerate() {
        error[r] = t - c[r];
    }
    Ok(())
}

impl Task for ComTask {
    fn name(&self) -> &str {
        &self.name
    }

    fn rows(&self) -> usize {
        self.rows
    }

    fn write(
        &self,
        model: &Model,
        data: &ModelData,
        _q: &[f64],
        jacobian: MatMut<'_, f64>,
        error: &mut [f64],
    ) -> Result<(), ModelError> {
        com_rows(
            model,
            data,
            &self.target.as_slice()[..self.rows],
            jacobian,
            error,
        )
    }

    fn as_any_mut(&mut self) -> &mut dyn Any {
        self
    }
}
