//! A frame at a target orientation.

use std::any::Any;

use faer::MatMut;
use nalgebra::{Rotation3, Vector3};

use super::{Task, TaskError, finite_target};
use crate::model::{FrameId, Model, ModelData, ModelError};

/// A named frame at a target orientation in the base frame: three rows, the rotation vector
/// `e = log(R* R(q)ᵀ)` (radians, base frame) and the frame's angular-velocity Jacobian.
#[derive(Debug, Clone, PartialEq)]
pub struct OrientationTask {
    name: String,
    frame: FrameId,
    /// Target orientation of the frame in the base frame.
    pub target: Rotation3<f64>,
}

impl OrientationTask {
    /// `frame` at orientation `target` (base frame); named after the frame.
    ///
    /// # Errors
    /// [`TaskError::Model`] for an unknown frame, [`TaskError::NonFiniteTarget`].
    pub fn new(model: &Model, frame: &str, target: Rotation3<f64>) -> Result<Self, TaskError> {
        finite_target(frame, target.matrix().as_slice())?;
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

/// The three orientation rows of `frame` toward `target` (base frame): the angular-velocity
/// Jacobian into `jacobian` and the rotation vector `e = log(R* R(q)ᵀ)` (rad) into `error`, for
/// the forward kinematics in `data`. The rows of [`OrientationTask`], for task models that
/// build their own stacks.
///
/// # Errors
/// [`ModelError`] when `data` has no kinematics or the frame is not in `model`.
pub fn orientation_rows(
    model: &Model,
    data: &ModelData,
    frame: FrameId,
    target: &Rotation3<f64>,
    jacobian: MatMut<'_, f64>,
    error: &mut [f64],
) -> Result<(), ModelError> {
    model.orientation_jacobian(data, frame, jacobian)?;
    orientation_error(model, data, frame, target, error)
}

/// The error `e = log(R* R(q)ᵀ)` of [`orientation_rows`] alone (rad, 3 entries): for a task
/// model that measures its tasks after its last step, where no Jacobian is needed.
///
/// # Errors
/// [`ModelError`] when `data` has no kinematics, the frame is not in `model` or `error` has
/// fewer than 3 entries.
pub fn orientation_error(
    model: &Model,
    data: &ModelData,
    frame: FrameId,
    target: &Rotation3<f64>,
    error: &mut [f64],
) -> Result<(), ModelError> {
    model.check_computed(data)?;
    model.check_frame(frame)?;
    super::check_error_len(error, 3)?;
    let current = data.frame_placement(frame).rotation;
    let e = rotation_vector(&(target * current.inverse()));
    error[..3].copy_from_slice(e.as_slice());
    Ok(())
}

/// `log(R)` as a rotation vector (axis × angle, rad), accurate for small angles too: with
/// `v = ½ (R₃₂ − R₂₃, R₁₃ − R₃₁, R₂₁ − R₁₂) = sin θ · u` and `cos θ = ½ (tr R − 1)`,
/// `θ = atan2(|v|, cos θ)` and `log R = v θ / sin θ` (→ v as θ → 0). An angle from `acos` alone
/// loses half the digits near 0, which a task converging to its target lives at. Beyond π/2
/// nalgebra's axis–angle is accurate and handles θ ≈ π, where `v` vanishes.
fn rotation_vector(r: &Rotation3<f64>) -> Vector3<f64> {
    let m = r.matrix();
    let v = 0.5
        * Vector3::new(
            m[(2, 1)] - m[(1, 2)],
            m[(0, 2)] - m[(2, 0)],
            m[(1, 0)] - m[(0, 1)],
        );
    let cos = 0.5 * (m.trace() - 1.0);
    if cos <= 0.0 {
        return r.scaled_axis();
    }
    let sin = v.norm();
    let angle = sin.atan2(cos);
    match sin > 1e-300 {
        true => v * (angle / sin),
        false => v,
    }
}

impl Task for OrientationTask {
    fn name(&self) -> &str {
        &self.name
    }

    fn rows(&self) -> usize {
        3
    }

    fn write(
        &self,
        model: &Model,
        data: &ModelData,
        _q: &[f64],
        jacobian: MatMut<'_, f64>,
        error: &mut [f64],
    ) -> Result<(), ModelError> {
        orientation_rows(model, data, self.frame, &self.target, jacobian, error)
    }

    fn as_any_mut(&mut self) -> &mut dyn Any {
        self
    }
}
