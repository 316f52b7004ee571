//! A frame's z axis along a direction: an upright (or leaning) torso, its heading free.

use std::any::Any;

use faer::MatMut;
use nalgebra::Vector3;

use super::{Task, TaskError, finite_target};
use crate::model::{FrameId, Model, ModelData, ModelError};

/// A named frame whose z axis points along `up` (a unit vector in the base frame): two rows,
/// the horizontal (x, y) rows of the frame's angular-velocity Jacobian and the horizontal part
/// of the rotation vector `z × up` (rad, exact for small tilts). The rotation about the vertical
/// is left free: an upright torso that may turn.
#[derive(Debug, Clone, PartialEq)]
pub struct UprightTask {
    name: String,
    frame: FrameId,
    /// The direction the frame's z axis should take (unit vector, base frame).
    pub up: Vector3<f64>,
}

impl UprightTask {
    /// `frame` with its z axis along the base frame's z; named after the frame.
    ///
    /// # Errors
    /// [`TaskError::Model`] for an unknown frame.
    pub fn new(model: &Model, frame: &str) -> Result<Self, TaskError> {
        Ok(Self {
            name: frame.to_owned(),
            frame: model.frame_id(frame)?,
            up: Vector3::z(),
        })
    }

    /// Another name in the stack (default: the frame's name).
    pub fn named(mut self, name: &str) -> Self {
        self.name = name.to_owned();
        self
    }

    /// Sets [`UprightTask::up`] (normalised).
    ///
    /// # Errors
    /// [`TaskError::NonFiniteTarget`] for a non-finite or zero vector.
    pub fn set_up(&mut self, up: Vector3<f64>) -> Result<(), TaskError> {
        finite_target(&self.name, up.as_slice())?;
        match up.try_normalize(1e-12) {
            Some(unit) => {
                self.up = unit;
                Ok(())
            }
            None => Err(TaskError::NonFiniteTarget {
                task: self.name.clone(),
            }),
        }
    }
}

/// The two rows of [`UprightTask`] for `frame` and direction `up` (unit, base frame): the x and
/// y rows of the angular-velocity Jacobian into `jacobian` (2 × nv) and the x, y components of
/// `z × up` (rad) into `error`, for the forward kinematics in `data`.
///
/// # Errors
/// [`ModelError`] when `data` has no kinematics or the frame is not in `model`.
pub fn upright_rows(
    model: &Model,
    data: &ModelData,
    frame: FrameId,
    up: &Vector3<f64>,
    jacobian: MatMut<'_, f64>,
    error: &mut [f64],
) -> Result<(), ModelError> {
    model.orientation_jacobian_rows(data, frame, 2, jacobian)?;
    upright_error(model, data, frame, up, error)
}

/// The error of [`upright_rows`] alone (rad, 2 entries): for a task model that measures its
/// tasks after its last step, where no Jacobian is needed.
///
/// # Errors
/// [`ModelError`] when `data` has no kinematics, the frame is not in `model` or `error` has
/// fewer than 2 entries.
pub fn upright_error(
    model: &Model,
    data: &ModelData,
    frame: FrameId,
    up: &Vector3<f64>,
    error: &mut [f64],
) -> Result<(), ModelError> {
    model.check_computed(data)?;
    model.check_frame(frame)?;
    super::check_error_len(error, 2)?;
    let rotation = &data.frame_placement(frame).rotation;
    let tilt = (rotation * Vector3::z()).cross(up);
    error[..2].copy_from_slice(&[tilt.x, tilt.y]);
    Ok(())
}

impl Task for UprightTask {
    fn name(&self) -> &str {
        &self.name
    }

    fn rows(&self) -> usize {
        2
    }

    fn write(
        &self,
        model: &Model,
        data: &ModelData,
        _q: &[f64],
        jacobian: MatMut<'_, f64>,
        error: &mut [f64],
    ) -> Result<(), ModelError> {
        upright_rows(model, data, self.frame, &self.up, jacobian, error)
    }

    fn as_any_mut(&mut self) -> &mut dyn Any {
        self
    }
}
