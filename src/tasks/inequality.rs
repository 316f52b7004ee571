//! Inequality tasks: rows that must stay within bounds rather than reach a target.

use std::any::Any;
use std::fmt::Debug;

use faer::MatMut;

use crate::model::{Model, ModelData, ModelError};

/// An inequality task: rows `c(q)` kept within `[l, u]` (task units). For the position-level
/// driver it writes, for the configuration whose forward kinematics `data` holds, the Jacobian
/// `C = ∂c/∂q` and the room left on each side, `l − c(q) ≤ C δq ≤ u − c(q)` (±∞ for an open
/// side); the driver turns the room into velocity bounds (see
/// [`driver`](crate::solver::driver)).
pub trait InequalityTask: Debug + Any {
    /// Name of the task in the stack (unique inside a [`TaskSet`](super::TaskSet)).
    fn name(&self) -> &str;

    /// Number of rows.
    fn rows(&self) -> usize;

    /// Writes the `rows × nv` Jacobian into `jacobian` and the room `l − c(q)`, `u − c(q)` into
    /// `lower`, `upper` (`rows` entries each).
    ///
    /// # Errors
    /// [`ModelError`] when `data` has no kinematics or a frame is not in `model`.
    fn write(
        &self,
        model: &Model,
        data: &ModelData,
        jacobian: MatMut<'_, f64>,
        lower: &mut [f64],
        upper: &mut [f64],
    ) -> Result<(), ModelError>;

    /// `self` as [`Any`], so that [`TaskSet::inequality_mut`](super::TaskSet::inequality_mut)
    /// can hand back the concrete type.
    fn as_any_mut(&mut self) -> &mut dyn Any;
}
