//! Di Fava et al.'s contact orientation task (eq. 11): a link's contact normal along the
//! surface's.

use std::any::Any;
use std::cell::RefCell;

use faer::{Mat, MatMut};
use nalgebra::Vector3;

use super::{Task, TaskError, combine_rows, finite_target};
use crate::model::{FrameId, Model, ModelData, ModelError};

/// The one-dimensional task `φ = ⟨ν_k, ν_env⟩ → 1` (eq. 11): the unit normal `ν_k` of a link's
/// contact surface (fixed in its frame) turned to the environment surface's normal `ν_env` (base
/// frame), leaving the rotation about it free. Error `1 − φ` (dimensionless); Jacobian
/// `(ν_k × ν_env)ᵀ J_ω`, since `ν̇_k = ω × ν_k`. The Jacobian vanishes at alignment (and at
/// the opposite direction), so the error shrinks like `1 − cos θ`: a task to approach a contact,
/// not to hold it.
#[derive(Debug, Clone)]
pub struct ContactNormalTask {
    name: String,
    frame: FrameId,
    /// The link's contact normal, in its frame's axes (unit).
    local_normal: Vector3<f64>,
    /// The surface's normal in the base frame (unit).
    pub surface_normal: Vector3<f64>,
    /// Orientation-Jacobian scratch (3 × nv), so that writing does not allocate.
    scratch: RefCell<Mat<f64>>,
}

impl ContactNormalTask {
    /// The normal `local_normal` (in `frame`'s axes) of `frame` turned to `surface_normal` (base
    /// frame); both are normalized. Named `"<frame>_normal"`.
    ///
    /// # Errors
    /// [`TaskError::Model`] for an unknown frame, [`TaskError::NonFiniteTarget`],
    /// [`TaskError::InvalidGeometry`] for a zero normal.
    pub fn new(
        model: &Model,
        frame: &str,
        local_normal: Vector3<f64>,
        surface_normal: Vector3<f64>,
    ) -> Result<Self, TaskError> {
        let name = format!("{frame}_normal");
        let id = model.frame_id(frame)?;
        finite_target(&name, local_normal.as_slice())?;
        finite_target(&name, surface_normal.as_slice())?;
        if local_normal.norm() < 1e-12 || surface_normal.norm() < 1e-12 {
            return Err(TaskError::InvalidGeometry {
                task: name,
                reason: "zero normal",
            });
        }
        Ok(Self {
            name,
            frame: id,
            local_normal: local_normal.normalize(),
            surface_normal: surface_normal.normalize(),
            scratch: RefCell::new(Mat::zeros(3, model.nv())),
        })
    }

    /// `φ = ⟨ν_k, ν_env⟩` at the forward kinematics in `data`.
    pub fn alignment(&self, model: &Model, data: &ModelData) -> Result<f64, ModelError> {
        Ok(self.link_normal(model, data)?.dot(&self.surface_normal))
    }

    fn link_normal(&self, model: &Model, data: &ModelData) -> Result<Vector3<f64>, ModelError> {
        let placement = model.placement_in_world(data, &Default::default(), self.frame)?;
        Ok(placement.rotation * self.local_normal)
    }
}

impl Task for ContactNormalTask {
    fn name(&self) -> &str {
        &self.name
    }

    fn rows(&self) -> usize {
        1
    }

    fn write(
        &self,
        model: &Model,
        data: &ModelData,
        _q: &[f64],
        mut jacobian: MatMut<'_, f64>,
        error: &mut [f64],
    ) -> Result<(), ModelError> {
        let nu = self.link_normal(model, data)?;
        let axis = nu.cross(&self.surface_normal);
        let mut j = self.scratch.borrow_mut();
        model.orientation_jacobian(data, self.frame, j.as_mut())?;
        combine_rows(&axis, j.as_ref(), jacobian.as_mut());
        error[0] = 1.0 - nu.dot(&self.surface_normal);
        Ok(())
    }

    fn as_any_mut(&mut self) -> &mut dyn Any {
        self
    }
}
