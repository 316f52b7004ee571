//! The whole body's zero-moment point inside the support polygon, and the vertical moment on the
//! standing soles bounded: balance that sees the arms move, not only the centre of mass.
//!
//! # Maths
//!
//! The model's base is a sole standing on the floor (fixed in the world; z up, the floor the
//! plane z = 0, gravity `−g ẑ`). The rate of the whole body's angular momentum about the
//! base origin `O` is the moment of the external forces about it: gravity's `m c × (−g ẑ)` and
//! the floor's. The floor's moment about the zero-moment point `p` (on the floor) has no
//! horizontal part, so, with the floor's vertical force `m (g + c̈_z) ≈ m g`,
//!
//! ```text
//! p_x = c_x − Ḣ_y / (m g),    p_y = c_y + Ḣ_x / (m g),    τ_z = Ḣ_z
//! ```
//!
//! (`H = A_O q̇`, [`Model::angular_momentum_jacobian`]; the CoM's acceleration is inside `Ḣ`,
//! whose `m c × c̈` part gives the cart-table's `−(z_c/g) c̈`; `τ_z` is the vertical moment the
//! floor must supply about `O`, which friction must hold or the foot turns). Over one frame of
//! `Δt` from the posture `q₀`, after a frame in which the joints moved at `v₋`,
//!
//! ```text
//! Ḣ(q) = A_O(q) ((q − q₀)/Δt − v₋) / Δt
//! ```
//!
//! (the frame's joint acceleration; the `Ȧ q̇` term, the links' centripetal part, is left out:
//! it is second order in the joint speeds, which the imitation keeps low). The rows are, for
//! each edge `i` of the polygon (outward normal `n_i` through vertex `v_i`),
//! `n_iᵀ p ≤ n_iᵀ v_i − margin`, and `−τ_max ≤ τ_z ≤ τ_max`; their Jacobian is
//! `n_iᵀ (J_c,xy + [−A_y; A_x] / (m g Δt²))` and `A_z / Δt²` (`A_O`'s rows; its own change
//! with `q` left out, as the `Ȧ q̇` term).
//!
//! [`ZmpTask::seeing`] restricts `A_O` to some joints (the imitation's arms): the rows then
//! hold the CoM's statics plus those joints' dynamics, for a robot whose CoM reference is
//! shaped on its own and whose legs' frame-to-frame steps are not smooth enough to be read as
//! accelerations at `1/Δt²`.
//!
//! Units: metres, seconds, newton-metres.

use faer::MatMut;

use super::{ComPolygonTask, TaskError, finite_target};
use crate::model::{Model, ModelData, ModelError};
use crate::solver::check::check_len;

/// Standard gravity (m/s²).
pub const GRAVITY: f64 = 9.81;

/// The whole-body ZMP inside a convex support polygon (shrunk by a margin) and the floor's
/// vertical moment within `±max_yaw_moment`, for one frame of motion (module docs). Rows: one
/// per polygon edge (as [`ComPolygonTask`], spare rows open), then the vertical moment; named
/// `"zmp"`.
///
/// Not an [`InequalityTask`](super::InequalityTask): its rows depend on how far `q` moved in
/// the frame, not on the posture alone; [`ZmpTask::write`] takes `q`.
#[derive(Debug, Clone, PartialEq)]
pub struct ZmpTask {
    polygon: ComPolygonTask,
    max_yaw_moment: f64,
    /// The frame's length (s), its start posture and the joints' velocity in the frame before.
    dt: f64,
    start: Vec<f64>,
    velocity: Vec<f64>,
    /// The joints whose momentum the rows see (`None`: all).
    seen: Option<Vec<bool>>,
}

impl ZmpTask {
    /// A task with room for `capacity` polygon vertices (≥ 4: its rows serve as scratch for the
    /// CoM and momentum Jacobians), holding `vertices` with `margin` (m, as
    /// [`ComPolygonTask::set_polygon`]) and the vertical moment bound `max_yaw_moment` (N·m,
    /// positive). The frame starts at rest at the zero posture with `Δt` = 0.01 s until
    /// [`ZmpTask::begin_frame`].
    ///
    /// # Errors
    /// As [`ComPolygonTask::new`]; [`TaskError::InvalidGeometry`] for a capacity below 4 or a
    /// bound that is not finite and > 0.
    pub fn new(
        model: &Model,
        capacity: usize,
        vertices: &[[f64; 2]],
        margin: f64,
        max_yaw_moment: f64,
    ) -> Result<Self, TaskError> {
        let invalid = |reason| TaskError::InvalidGeometry {
            task: "zmp".to_owned(),
            reason,
        };
        if capacity < 4 {
            return Err(invalid("room for fewer than 4 vertices"));
        }
        if !(max_yaw_moment.is_finite() && max_yaw_moment > 0.0) {
            return Err(invalid("the vertical moment bound must be finite and > 0"));
        }
        let nv = model.nv();
        Ok(Self {
            polygon: ComPolygonTask::new(model, capacity, vertices, margin)?,
            max_yaw_moment,
            dt: 0.01,
            start: vec![0.0; nv],
            velocity: vec![0.0; nv],
            seen: None,
        })
    }

    /// Replaces the polygon (as [`ComPolygonTask::set_polygon`]). Does not allocate.
    ///
    /// # Errors
    /// As [`ComPolygonTask::set_polygon`].
    pub fn set_polygon(&mut self, vertices: &[[f64; 2]], margin: f64) -> Result<(), TaskError> {
        self.polygon.set_polygon(vertices, margin)
    }

    /// Starts a frame of `dt` seconds (> 0) at posture `start`, the joints having moved at
    /// `velocity` (per second, one per variable) in the frame before. Does not allocate.
    ///
    /// # Errors
    /// [`TaskError::Solver`] for a wrong length, [`TaskError::NonFiniteTarget`] for a NaN or
    /// infinite entry or a `dt` that is not > 0.
    pub fn begin_frame(
        &mut self,
        start: &[f64],
        velocity: &[f64],
        dt: f64,
    ) -> Result<(), TaskError> {
        check_len("zmp start posture", self.start.len(), start.len())?;
        check_len("zmp joint velocity", self.velocity.len(), velocity.len())?;
        finite_target("zmp", start)?;
        finite_target("zmp", velocity)?;
        if !(dt.is_finite() && dt > 0.0) {
            return Err(TaskError::NonFiniteTarget {
                task: "zmp".to_owned(),
            });
        }
        self.start.copy_from_slice(start);
        self.velocity.copy_from_slice(velocity);
        self.dt = dt;
        Ok(())
    }

    /// The same task seeing only the momentum of `joints` (one per variable; the CoM rows
    /// still see every joint): the rows then bound what those joints' motion adds to the
    /// statics, e.g. the arms' on a robot whose CoM reference is shaped on its own.
    ///
    /// # Errors
    /// [`TaskError::Solver`] when `joints` does not have one entry per variable.
    pub fn seeing(mut self, joints: Vec<bool>) -> Result<Self, TaskError> {
        check_len("zmp joints seen", self.start.len(), joints.len())?;
        self.seen = Some(joints);
        Ok(self)
    }

    /// Number of rows: the polygon's capacity and the vertical moment.
    pub fn rows(&self) -> usize {
        self.polygon.capacity() + 1
    }

    /// Writes, for `q` (whose forward kinematics `data` holds), the `rows × nv` Jacobian and the
    /// room `l − c(q)`, `u − c(q)` of each row (m for the edges, N·m for the moment), as an
    /// [`InequalityTask`](super::InequalityTask) does. Does not allocate.
    ///
    /// # Errors
    /// [`ModelError`] for kinematics not computed, a model without mass, or sizes that do not
    /// match the model.
    pub fn write(
        &self,
        model: &Model,
        data: &ModelData,
        q: &[f64],
        mut jacobian: MatMut<'_, f64>,
        lower: &mut [f64],
        upper: &mut [f64],
    ) -> Result<(), ModelError> {
        if q.len() != self.start.len() {
            return Err(ModelError::WrongQLength {
                expected: self.start.len(),
                got: q.len(),
            });
        }
        let rows = self.rows();
        if jacobian.nrows() != rows || lower.len() != rows || upper.len() != rows {
            return Err(ModelError::OutputShape {
                expected_rows: rows,
                expected_cols: self.start.len(),
                rows: jacobian.nrows().min(lower.len()).min(upper.len()),
                cols: jacobian.ncols(),
            });
        }
        let c = model.com(data)?;
        model.com_jacobian_rows(data, 2, jacobian.as_mut().subrows_mut(0, 2))?;
        model.angular_momentum_jacobian(data, jacobian.as_mut().subrows_mut(2, 3))?;
        if let Some(seen) = &self.seen {
            for (k, _) in seen.iter().enumerate().filter(|(_, s)| !**s) {
                for r in 2..5 {
                    jacobian[(r, k)] = 0.0;
                }
            }
        }
        let dt = self.dt;
        // Ḣ = A_O q̈, with the frame's joint acceleration q̈ = ((q − q₀)/Δt − v₋)/Δt.
        let rate = |r: usize| -> f64 {
            (0..jacobian.ncols())
                .map(|k| jacobian[(r, k)] * ((q[k] - self.start[k]) / dt - self.velocity[k]) / dt)
                .sum()
        };
        let h_rate = [rate(2), rate(3), rate(4)];
        let weight = model.total_mass() * GRAVITY;
        let zmp = [c.x - h_rate[1] / weight, c.y + h_rate[0] / weight];
        let scale = 1.0 / (weight * dt * dt);
        let capacity = self.polygon.capacity();
        for col in 0..jacobian.ncols() {
            let x = jacobian[(0, col)] - jacobian[(3, col)] * scale;
            let y = jacobian[(1, col)] + jacobian[(2, col)] * scale;
            let yaw = jacobian[(4, col)] / (dt * dt);
            for (i, edge) in self.polygon.edges().iter().enumerate() {
                jacobian[(i, col)] = match edge {
                    Some(([nx, ny], _)) => nx * x + ny * y,
                    None => 0.0,
                };
            }
            jacobian[(capacity, col)] = yaw;
        }
        let margin = self.polygon.margin();
        for (i, edge) in self.polygon.edges().iter().enumerate() {
            lower[i] = f64::NEG_INFINITY;
            upper[i] = match edge {
                Some(([nx, ny], offset)) => offset - margin - (nx * zmp[0] + ny * zmp[1]),
                None => f64::INFINITY,
            };
        }
        lower[capacity] = -self.max_yaw_moment - h_rate[2];
        upper[capacity] = self.max_yaw_moment - h_rate[2];
        Ok(())
    }
}
