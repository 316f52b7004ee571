//! A point of a frame at a target position.

use std::any::Any;

use faer::MatMut;
use nalgebra::Vector3;

use super::{Task, TaskError, finite_target};
use crate::model::{Axis, FrameId, Model, ModelData, ModelError};

/// A point fixed in a frame: the frame and the point's offset from its origin (m, in the frame's
/// axes).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FramePoint {
    /// The frame the point moves with.
    pub frame: FrameId,
    /// Offset from the frame's origin, in the frame's axes (m).
    pub offset: Vector3<f64>,
}

/// The rows of `point` at `target` (base frame, m) on `axes`, in that order: the point's
/// Jacobian rows (`axes.len() × nv`) into `jacobian` and `e = x* − x(q)` into `error`, for the
/// forward kinematics in `data`. The rows of [`PositionTask`], for task models that build their
/// own stacks.
///
/// # Errors
/// [`ModelError`] when `data` has no kinematics or the frame is not in `model`.
pub fn point_rows(
    model: &Model,
    data: &ModelData,
    point: &FramePoint,
    axes: &[Axis],
    target: &Vector3<f64>,
    mut jacobian: MatMut<'_, f64>,
    error: &mut [f64],
) -> Result<(), ModelError> {
    let FramePoint { frame, offset } = point;
    // All three axes in order: one walk of the chain instead of three.
    if axes == [Axis::X, Axis::Y, Axis::Z] {
        model.point_jacobian(data, *frame, offset, jacobian.as_mut())?;
    } else {
        for (r, &axis) in axes.iter().enumerate() {
            let row = jacobian.as_mut().subrows_mut(r, 1);
            model.point_jacobian_row(data, *frame, offset, axis, row)?;
        }
    }
    point_error(model, data, point, axes, target, error)
}

/// The error `e = x* − x(q)` of [`point_rows`] alone (m, `axes.len()` entries): for a task
/// model that measures its tasks after its last step, where no Jacobian is needed.
///
/// # Errors
/// [`ModelError`] when `data` has no kinematics, the frame is not in `model` or `error` is
/// shorter than `axes`.
pub fn point_error(
    model: &Model,
    data: &ModelData,
    point: &FramePoint,
    axes: &[Axis],
    target: &Vector3<f64>,
    error: &mut [f64],
) -> Result<(), ModelError> {
    super::check_error_len(error, axes.len())?;
    let x = model.point_position(data, point.frame, &point.offset)?;
    for (r, &axis) in axes.iter().enumerate() {
        error[r] = target[axis as usize] - x[axis as usize];
    }
    Ok(())
}

/// A point of a named frame at a target position in the base frame (metres), on all three axes
/// or on some ([`PositionTask::axes`]): one row per axis, `e = x* − x(q)`.
#[derive(Debug, Clone, PartialEq)]
pub struct PositionTask {
    name: String,
    point: FramePoint,
    axes: Vec<Axis>,
    /// Target position in the base frame (m); only the constrained axes are read.
    pub target: Vector3<f64>,
}

impl PositionTask {
    /// The origin of `frame` at `target` (base frame, m), on x, y and z; named after the frame.
    ///
    /// # Errors
    /// [`TaskError::Model`] for an unknown frame, [`TaskError::NonFiniteTarget`].
    pub fn new(model: &Model, frame: &str, target: Vector3<f64>) -> Result<Self, TaskError> {
        finite_target(frame, target.as_slice())?;
        Ok(Self {
            name: frame.to_owned(),
            point: FramePoint {
                frame: model.frame_id(frame)?,
                offset: Vector3::zeros(),
            },
            axes: vec![Axis::X, Axis::Y, Axis::Z],
            target,
        })
    }

    /// The point at `offset` (m, in the frame's axes) from the frame's origin instead.
    ///
    /// # Errors
    /// [`TaskError::NonFiniteTarget`] for a NaN or infinite offset.
    pub fn with_offset(mut self, offset: Vector3<f64>) -> Result<Self, TaskError> {
        finite_target(&self.name, offset.as_slice())?;
        self.point.offset = offset;
        Ok(self)
    }

    /// Only these axes of the base frame (e.g. `[Axis::Z]` for a height), in this row order.
    pub fn axes(mut self, axes: &[Axis]) -> Self {
        self.axes = axes.to_vec();
        self
    }

    /// Another name in the stack (default: the frame's name).
    pub fn named(mut self, name: &str) -> Self {
        self.name = name.to_owned();
        self
    }
}

impl Task for PositionTask {
    fn name(&self) -> &str {
        &self.name
    }

    fn rows(&self) -> usize {
        self.axes.len()
    }

    fn write(
        &self,
        model: &Model,
        data: &ModelData,
        _q: &[f64],
        jacobian: MatMut<'_, f64>,
        error: &mut [f64],
    ) -> Result<(), ModelError> {
        point_rows(
            model,
            data,
            &self.point,
            &self.axes,
            &self.target,
            jacobian,
            error,
        )
    }

    fn as_any_mut(&mut self) -> &mut dyn Any {
        self
    }
}
