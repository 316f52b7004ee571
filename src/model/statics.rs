//! Statics: the joint torques that hold a posture still against gravity.
//!
//! With the model's base fixed (a robot standing on its root sole), gravity `g` along −z of the
//! base frame and vertical forces `f_i` (N, upward) pushing on points `i` fixed to links (the
//! centre of pressure of another sole on the floor), the posture is in equilibrium when each
//! variable's actuator gives
//!
//! ```text
//! τ = M g ∂z_c/∂q − Σ_i f_i ∂z_i/∂q        (N·m per radian variable, N per metre variable)
//! ```
//!
//! the gradient of the potential energy `M g z_c − Σ f_i z_i`: `z_c` is the height of the
//! whole-body centre of mass, `z_i` the height of point `i`, `M` the total mass. Rows of
//! [`Model::com_jacobian`] and of the point Jacobians give both derivatives, so the torques cost
//! one CoM Jacobian row and one point row per load. A position servo of stiffness `k` (N·m/rad)
//! holding that torque settles `τ / k` short of its target; a caller that wants the joint at `q`
//! commands `q + τ / k`.

use faer::MatMut;
use nalgebra::Vector3;

use super::{Axis, FrameId, Model, ModelData, ModelError};

/// A vertical force pushing up on a point fixed to a frame: a sole's share of the weight at its
/// centre of pressure.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PointLoad {
    /// The frame the point is fixed to.
    pub frame: FrameId,
    /// The point, in the frame's axes from its origin (m).
    pub offset: Vector3<f64>,
    /// The force along +z of the base frame (N).
    pub force: f64,
}

impl Model {
    /// The actuator torques (1×n row `out`, N·m or N per variable) that hold the posture of
    /// `data` still with the base fixed, under gravity `gravity` (m/s², along −z of the base
    /// frame) and the upward forces `loads`: `τ = M g ∂z_c/∂q − Σ f_i ∂z_i/∂q`, the gradient of
    /// the potential energy (`z_c` the height of the CoM, `z_i` of load `i`'s point).
    ///
    /// # Errors
    /// Kinematics not computed on `data`, a wrong output shape, a model without mass, a frame
    /// of another model, or a non-finite gravity, force or offset.
    pub fn static_torques(
        &self,
        data: &ModelData,
        gravity: f64,
        loads: &[PointLoad],
        mut out: MatMut<'_, f64>,
    ) -> Result<(), ModelError> {
        if let Some(bad) = std::iter::once(gravity)
            .chain(loads.iter().map(|load| load.force))
            .find(|v| !v.is_finite())
        {
            return Err(ModelError::NonFiniteLoad(bad));
        }
        self.com_jacobian_axes(data, &[Axis::Z], out.as_mut())?;
        let weight = self.total_mass() * gravity;
        for k in 0..out.ncols() {
            out[(0, k)] *= weight;
        }
        for load in loads {
            let down = Vector3::new(0.0, 0.0, -load.force);
            self.add_point_jacobian_along(data, load.frame, &load.offset, &down, out.as_mut())?;
        }
        Ok(())
    }
}
