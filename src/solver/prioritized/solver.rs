//! The solver's state ([`Solver`]): the stack, the workspace every solve reuses, and the last
//! result; its construction and accessors. The solves are in `clamping` (the clamping loop
//! and the scales that fit a step), `pass` (one prioritized pass) and `active_set`.

use super::active_set::workspace::ActiveSetWorkspace;
use super::rows::{LevelFactor, UsedRow};
use super::settings::Settings;
use crate::solver::SolverError;
use crate::solver::report::{Bound, SolveReport};
use crate::solver::stack::{StackShape, TaskStack, prefix_sums};

/// A prioritized task-stack solver: the stack, its workspace, and the last result.
///
/// Everything is allocated in [`Solver::new`]; [`Solver::solve`] allocates nothing.
#[derive(Debug, Clone)]
pub struct Solver {
    pub(super) stack: TaskStack,
    pub(super) settings: Settings,
    // Workspace, sized for (n, level rows).
    pub(super) factors: Vec<LevelFactor>,
    /// First buffer row of each level (its equality rows plus all its inequality rows), and the
    /// total.
    pub(super) seg_start: Vec<usize>,
    /// The rows each level uses in the current pass, at `seg_start`.
    pub(super) used: Vec<UsedRow>,
    /// Per inequality row: the bound it is held at, or `None` while inactive.
    pub(super) inequality_state: Vec<Option<Bound>>,
    pub(super) active_set: ActiveSetWorkspace,
    /// `A_jᵀ` per level, column-major with leading dimension `r_{j−1}`, at offset `n · seg_j`;
    /// after factorization, `R_j` and the reflectors.
    pub(super) qr: Vec<f64>,
    pub(super) tau: Vec<f64>,
    pub(super) perm: Vec<usize>,
    /// Per used row (at `n · (seg_j + t)`): its coordinates along the range bases of the levels
    /// above, `U_iᵀ J_rowᵀ` for i < j (the first `Σ_{i<j} k_i` entries), kept from the pass that
    /// factored them, so that a new right-hand side needs no new projection.
    pub(super) projections: Vec<f64>,
    /// Right-hand side `b_j` per row, then `w_j` per level (at the level's start).
    pub(super) rhs: Vec<f64>,
    pub(super) coeff: Vec<f64>,
    /// Per level (at the level's start): the damping reference's coordinates `U_jᵀ q̇_ref`
    /// along its range basis, the `w` a damped level is damped toward.
    pub(super) reference_coeff: Vec<f64>,
    /// Whether this pass has a nonzero damping reference.
    pub(super) damp_toward_reference: bool,
    /// The damping reference in reduced coordinates, rotated level by level (length n).
    pub(super) reference_coords: Vec<f64>,
    /// Per level (from `damped_start[j]`): the QR of a damped or rank-deficient level's
    /// stacked matrix `[Rᵀ; μ I]`, factored once per pass and reused for every right-hand side
    /// of the pass's repeats ([`Solver::repeat_pass`]); its reflectors' factors at the level's
    /// start in `damped_tau`.
    pub(super) damped_qr: Vec<f64>,
    pub(super) damped_start: Vec<usize>,
    pub(super) damped_tau: Vec<f64>,
    /// Damped least-squares right-hand side (`2 m_max`).
    pub(super) ls_rhs: Vec<f64>,
    /// Vector in reduced coordinates (length n).
    pub(super) coords: Vec<f64>,
    pub(super) free: Vec<usize>,
    pub(super) clamped: Vec<bool>,
    pub(super) fixed_velocity: Vec<f64>,
    pub(super) step_lo: Vec<f64>,
    pub(super) step_hi: Vec<f64>,
    pub(super) velocity: Vec<f64>,
    /// Scale of each level's desired velocity in this solve, then of the gradient term.
    pub(super) scales: Vec<f64>,
    /// The part of the step due to each level, then to the gradient (levels + 1 rows of n).
    pub(super) contributions: Vec<f64>,
    /// Velocity limits of this solve.
    pub(super) step_vmax: Vec<f64>,
    /// Largest row norm of the level being projected.
    pub(super) row_scale: f64,
    /// The part of the step due to the clamped joints' fixed velocities, and a copy of those.
    pub(super) base_velocity: Vec<f64>,
    pub(super) saved_fixed: Vec<f64>,
    /// Weighted DLS: the `m × m` Gram matrix, `W⁻¹`, and `|∂H/∂q|` of the previous solve.
    pub(super) gram: Vec<f64>,
    pub(super) inverse_weight: Vec<f64>,
    pub(super) previous_criterion: Vec<f64>,
    pub(super) report: SolveReport,
}

impl Solver {
    /// A solver for stacks of this shape, with default [`Settings`].
    pub fn new(shape: &StackShape) -> Result<Self, SolverError> {
        Self::with_settings(shape, Settings::default())
    }

    /// A solver for stacks of this shape with the given settings.
    pub fn with_settings(shape: &StackShape, settings: Settings) -> Result<Self, SolverError> {
        settings.validate(shape.has_inequalities())?;
        let stack = TaskStack::new(shape)?;
        let n = stack.dof();
        let total = stack.total_rows();
        let inequalities = stack.total_inequality_rows();
        let levels = stack.level_count();
        // Each level's buffers hold its equality rows and every inequality row it could activate.
        let capacities: Vec<usize> = shape
            .level_rows()
            .zip(shape.level_inequality_rows())
            .map(|(m, p)| m + p)
            .collect();
        let m_max = capacities.iter().copied().max().unwrap_or(0);
        // A level's stacked matrix: its rows plus one damping row per kept direction, by the
        // kept directions (at most the level's rows and the joints).
        let damped_start = prefix_sums(capacities.iter().map(|&m| (m + m.min(n)) * m.min(n)));
        let seg_start = prefix_sums(capacities.into_iter());
        let capacity = seg_start[levels];
        Ok(Self {
            factors: vec![LevelFactor::default(); levels],
            seg_start,
            used: vec![UsedRow::Equality(0); capacity],
            inequality_state: vec![None; inequalities],
            active_set: ActiveSetWorkspace::new(n, levels, capacity, inequalities, m_max),
            qr: vec![0.0; n * capacity],
            projections: vec![0.0; n * capacity],
            tau: vec![0.0; capacity],
            perm: vec![0; capacity],
            rhs: vec![0.0; capacity],
            coeff: vec![0.0; capacity],
            reference_coeff: vec![0.0; capacity],
            damp_toward_reference: false,
            reference_coords: vec![0.0; n],
            damped_qr: vec![0.0; damped_start[levels]],
            damped_start,
            damped_tau: vec![0.0; capacity],
            ls_rhs: vec![0.0; 2 * m_max],
            coords: vec![0.0; n],
            free: Vec::with_capacity(n),
            clamped: vec![false; n],
            fixed_velocity: vec![0.0; n],
            step_lo: vec![0.0; n],
            step_hi: vec![0.0; n],
            velocity: vec![0.0; n],
            scales: vec![1.0; levels + 1],
            contributions: vec![0.0; (levels + 1) * n],
            step_vmax: vec![0.0; n],
            row_scale: 0.0,
            base_velocity: vec![0.0; n],
            saved_fixed: vec![0.0; n],
            gram: vec![0.0; total * total],
            inverse_weight: vec![1.0; n],
            previous_criterion: vec![0.0; n],
            report: SolveReport::with_capacity(levels, n, inequalities),
            stack,
            settings,
        })
    }

    /// The task stack (read).
    pub fn stack(&self) -> &TaskStack {
        &self.stack
    }

    /// The task stack, to fill Jacobians, desired velocities and the gradient term.
    pub fn stack_mut(&mut self) -> &mut TaskStack {
        &mut self.stack
    }

    /// The numerical settings.
    pub fn settings(&self) -> &Settings {
        &self.settings
    }

    /// Replaces the numerical settings.
    pub fn set_settings(&mut self, settings: Settings) -> Result<(), SolverError> {
        settings.validate(self.stack.shape().has_inequalities())?;
        self.settings = settings;
        Ok(())
    }

    /// The joint velocity `q̇` of the last successful solve (rad/s or m/s).
    pub fn velocity(&self) -> &[f64] {
        &self.velocity
    }

    /// The report of the last successful solve.
    pub fn report(&self) -> &SolveReport {
        &self.report
    }
}
