//! A frame at a target pose (position and orientation).

use std::any::Any;

use faer::MatMut;
use nalgebra::{IsometryMatrix3, Vector3};

use super::orientation::orientation_rows;
use super::{Task, TaskError, finite_target};
use crate::model::{FrameId, Model, ModelData, ModelError};

/// A named frame at a target placement in the base frame: six rows, the origin's position error
/// (m, x y z) then the rotation vector `log(R* Rᵀ)` (rad, base frame). Holding a foot flat on the
/// floor where it stands is a `PoseTask` at its current placement.
#[derive(Debug, Clone, PartialEq)]
pub struct PoseTask {
    name: String,
    frame: FrameId,
    /// Target placement of the frame in the base frame (m, rad).
    pub target: IsometryMatrix3<f64>,
}

impl PoseTask {
    /// `frame` at placement `target` (base frame); named after the frame.
    ///
    /// # Errors
    /// [`TaskError::Model`] for an unknown frame, [`TaskError::NonFiniteTarget`].
    pub fn new(
        model: &Model,
        frame: &str,
        target: IsometryMatrix3<f64>,
    ) -> Result<Self, TaskError> {
        finite_target(frame, target.translation.vector.as_slice())?;
        finite_target(frame, target.rotation.matrix().as_slice())?;
        Ok(Self {
            name: frame.to_owned(),
            frame: model.frame_id(frame)?,
            target,
        })
    }

    /// Another name in the stack (default: the frame's name).
    pub fn named(mut self, name: &str) -> Self {
        self.name = name.to_owned();
        self
    }
}

impl Task for PoseTask {
    fn name(&self) -> &str {
        &self.name
    }

    fn rows(&self) -> usize {
        6
    }

    fn write(
        &self,
        model: &Model,
        data: &ModelData,
        _q: &[f64],
        mut jacobian: MatMut<'_, f64>,
        error: &mut [f64],
    ) -> Result<(), ModelError> {
        let zero = Vector3::zeros();
        model.point_jacobian(data, self.frame, &zero, jacobian.as_mut().subrows_mut(0, 3))?;
        let x = model.point_position(data, self.frame, &zero)?;
        let e = self.target.translation.vector - x;
        error[..3].copy_from_slice(e.as_slice());
        orientation_rows(
            model,
            data,
            self.frame,
            &self.target.rotation,
            jacobian.subrows_mut(3, 3),
            &mut error[3..6],
        )
    }

    fn as_any_mut(&mut self) -> &mut dyn Any {
        self
    }
}
