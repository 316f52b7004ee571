//! The prioritized solve (eq. 4–6) with the clamping loop.
//!
//! # Method
//!
//! The textbook recursion is `q̇_j = q̇_{j−1} + (J_j P^a_{j−1})⁺ (ẋ_j − J_j q̇_{j−1})` with
//! `P^a_j = I − (J^a_j)⁺ J^a_j`. Instead of forming `n × n` projectors we carry an orthonormal basis
//! `Z_j` of the null space of levels `1..j`, so that `P^a_j = Z_j Z_jᵀ` and
//! `(J_j P^a_{j−1})⁺ = Z_{j−1} (J_j Z_{j−1})⁺` (valid because `Z_{j−1}` has orthonormal columns).
//!
//! * `Z_0` selects the joints that are not clamped; clamped joints move at their fixed velocity,
//!   whose effect `J_j q̇_clamped` is moved to the right-hand side of every level.
//! * Level `j`: `A_j = J_j Z_{j−1}` (`m_j × r_{j−1}`). A Householder QR with column pivoting of
//!   `A_jᵀ = Q_j [R_j; 0] Πᵀ`, truncated where the remaining row norm falls to
//!   [`Settings::rank_tolerance`], gives the rank `k_j`. The level's minimum-norm (damped)
//!   least-squares step is `Z_{j−1} Q_j[:, ..k_j] w_j` with
//!   `w_j = argmin ‖R_jᵀ w − Πᵀ b_j‖² + μ_j² ‖w‖²`, and the next basis is
//!   `Z_j = Z_{j−1} Q_j[:, k_j..]`.
//! * `Z_j` is never formed: it is the product of the stored reflectors, applied to each new task row
//!   (`Z_{j−1}ᵀ J_jᵀ`), to the gradient (`Z_Nᵀ g`), and once, back, to assemble `q̇`.
//! * Damping: when the smallest kept pivot `σ` of a level is below
//!   [`Settings::damping_threshold`] `ε`, `μ² = μ_max² (1 − (σ/ε)²)` (Nakamura–Hanafusa style,
//!   continuous in `σ`); otherwise `μ = 0` and the level is solved exactly. A damped level is
//!   damped toward the stack's damping reference `q̇_ref`
//!   ([`TaskStack::damping_reference_mut`](super::TaskStack::damping_reference_mut), zero by
//!   default): `w_j = argmin ‖R_jᵀ w − Πᵀ b_j‖² + μ_j² ‖w − U_jᵀ q̇_ref‖²`, `U_j` the level's
//!   range basis, so that its poorly conditioned directions keep the reference's motion rather
//!   than come to rest (over the level's range this is `(JᵀJ + μ²I)⁻¹(Jᵀẋ + μ² P q̇_ref)`). A
//!   level holding inequality rows at a bound is damped toward rest: a bound never gives way
//!   to the reference.
//!
//! Lower levels act only in `Z_j`, so they cannot disturb a higher level: its residual is the same
//! with or without them (strict priority), up to rounding and the truncated directions whose
//! singular values are below the rank tolerance.
//!
//! The gradient term is added as `Z_N Z_Nᵀ Σ κ_k ∇f_k` (eq. 6).
//!
//! The clamping loop (Baerlocher & Boulic 2004): after a solve, the free joint whose velocity
//! leaves the interval allowed for this step (position limits over `Δt`, and velocity limits) by
//! the most is fixed at the violated bound and removed from `Z_0`; the stack is solved again, until
//! no free joint violates its interval. (The paper clamps every violator at once; one at a time, like
//! an active-set method, keeps joints free that a near-singular first solution would have pinned.)
//! Each pass clamps one joint, so at most `n + 1` passes run, and the result never violates a
//! limit.

use super::SolverError;
use super::bounds::JointBounds;
use super::check::{check_finite_slice, check_len};
use super::householder::{
    apply_qt, apply_reflector, dot, norm, qr_col_pivoting, qr_factor, solve_upper,
    solve_upper_transposed,
};
use super::report::{ActiveInequality, Bound, Solution, SolveReport};
use super::stack::{StackShape, TaskStack, prefix_sums};

pub mod active_set;
mod weighted_dls;

use active_set::ActiveSetWorkspace;

pub use weighted_dls::{limit_criterion_gradient, limit_weight};

/// How the stack is solved.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum Method {
    /// Strict priorities by null-space projection (the method described above). Default.
    #[default]
    Prioritized,
    /// Every level's rows in one damped least-squares problem with Chan & Dubey's (1995)
    /// weighted least-norm joint-limit avoidance: no priorities, but a bounded step near
    /// singularities and joints slowed down as they near a limit.
    ///
    /// `q̇ = g + W⁻¹ Jᵀ (J W⁻¹ Jᵀ + λ² I)⁻¹ (ẋ − J g)`, `J` and `ẋ` all levels stacked,
    /// `g = Σ κ_k ∇f_k` the gradient term: the minimizer of `‖J q̇ − ẋ‖² + λ² ‖q̇ − g‖²_W`. With
    /// `W = I`, `‖q̇ − g‖ ≤ ‖ẋ − J g‖ / (2λ)` however ill-conditioned `J` is. `W` is diagonal,
    /// `w_i = 1 + |∂H/∂q_i|` while `|∂H/∂q_i|` grows (the joint nears a limit; see
    /// [`limit_weight`]) and 1 otherwise, with
    /// `H(q) = Σ_i (q_max,i − q_min,i)² / (4 (q_max,i − q_i)(q_i − q_min,i))`. The clamping loop
    /// and [`Settings::scale_to_fit`] apply as for the prioritized method, so no limit is
    /// violated. The level reports give each level's residual; their rank is the level's row
    /// count. Cost: an `m × m` Cholesky factorization per pass (`m` the total rows).
    WeightedDls {
        /// Damping factor `λ` (task units per rad, e.g. m): larger is slower and steadier.
        /// Must be finite and > 0.
        damping: f64,
    },
}

/// Directions whose remaining norm is below this fraction of their level's largest row norm are
/// rounding noise, whatever [`Settings::rank_tolerance`] says.
const RELATIVE_RANK_TOLERANCE: f64 = 1e-12;

/// Numerical settings of the solve. All are absolute, in the units of the task rows (e.g. m/rad
/// for position tasks); the defaults suit Jacobians whose entries are of order 0.01–1.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Settings {
    /// Directions of a projected level whose remaining norm (≈ singular value) is at or below this
    /// are treated as null: they are neither used by the level nor removed from the space left to
    /// lower levels. Default `1e-9`. Never below 1e-12 times the level's largest row norm, the
    /// rounding noise of the projection.
    pub rank_tolerance: f64,
    /// A level whose smallest kept singular value estimate `σ` is below this is damped. Default
    /// `2e-2`. Set to 0 to disable damping (pure truncation).
    pub damping_threshold: f64,
    /// Largest damping factor `μ_max`, reached as `σ → 0`. Default `2e-2`. A damped level is
    /// damped toward the stack's damping reference (zero by default, see the module docs).
    pub max_damping: f64,
    /// A level is reported feasible when `‖J_j q̇ − ẋ_j‖ ≤ feasibility_tolerance · (1 + ‖ẋ_j‖)`.
    /// Default `1e-8`.
    pub feasibility_tolerance: f64,
    /// Before the clamping loop, slow the levels down, lowest priority first, until the step fits
    /// each joint's velocity interval: the step is `Σ_k s_k C_k`, with `C_k` the (linear) part of
    /// the solution due to level `k`'s desired velocity (and last, the gradient term), and each
    /// scale `s_k ∈ [0, 1]` taken as large as the joint intervals allow given the levels above it
    /// ("saturation in the null space", Flacco et al. 2012, with whole-level scaling). A level
    /// keeps its direction and never costs a higher level any of its motion. The clamping loop
    /// then only has the joints whose interval excludes 0 (a start outside the limits). A step
    /// that fits every interval unscaled is taken as it is, in one pass (every scale 1). Off by
    /// default: the paper's clamping loop alone, which keeps higher levels exact by pinning joints
    /// at their bounds, but can leave them few joints when a lower level asks for much more than
    /// the limits allow.
    pub scale_to_fit: bool,
    /// Strict priorities (default) or weighted damped least squares.
    pub method: Method,
    /// Handle the joint intervals as inequality rows above every level, by the active-set
    /// method (see [`active_set`]), instead of the clamping loop: a joint held at a bound is
    /// released again when the levels would rather move it inward, so the result is the
    /// lexicographic optimum under the joint intervals. Always the case for a stack with
    /// inequality rows; this switch asks for it on equality-only stacks too. Default off.
    /// Not available with [`Settings::scale_to_fit`] or [`Method::WeightedDls`].
    pub limits_by_active_set: bool,
    /// Start the active-set method from the bounds held at the end of the previous solve
    /// instead of from none (a warm start): the method activates what that guess lacks and
    /// releases what it holds wrongly, so the result is the same lexicographic optimum up to
    /// rounding whenever the method converges (it is unique: the last level is `‖q̇ − g‖²`).
    /// In a control loop, where one tick's active bounds are mostly the last tick's, most of
    /// the passes that add them one at a time are saved. A warm solve that does not converge
    /// (a damped level's cycle, or the cap) is solved again cold and returns the cold
    /// solve's result (a warm start holding what a cold start holds is the cold solve, run
    /// once), and the solve after one that did not converge starts cold; a damped
    /// level's optimum may still depend on the path, so a converged
    /// warm result can differ a little from the cold one there.
    /// Default off: each solve starts from no active bound. Only the active-set method starts
    /// warm (a stack with inequality rows, or [`Settings::limits_by_active_set`]); the
    /// clamping loop's result depends on the order it pins joints in, so it always starts cold.
    pub warm_start: bool,
    /// Largest number of prioritized passes (each a projection and factorization of every
    /// level) one solve of the active-set method may take, a warm start and its cold retry
    /// together: a bound on a solve's time for a controller that must keep its rate. A solve
    /// that reaches it returns its iterate, which keeps every joint interval and every
    /// inequality row it had not given up (the method is primal feasible) and has moved from
    /// the start toward the optimum, and reports it not converged; the next solve starts
    /// cold, as after any solve that did not converge (warm starts from sets cut short, tick
    /// after tick, kept the higher levels from their motion: on the NAO a held foot turned).
    /// A budget trades progress for time: where a cold solve needs more passes than the
    /// budget tick after tick, each tick gets only part of the way. `None`
    /// (default): the method's own cap, `4 (n + p) + 8` passes, with a warm start that does
    /// not converge retried cold. `Some(0)` is refused. The clamping loop ignores it (it
    /// takes at most one pass per joint).
    pub max_passes: Option<usize>,
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            rank_tolerance: 1e-9,
            damping_threshold: 2e-2,
            max_damping: 2e-2,
            feasibility_tolerance: 1e-8,
            scale_to_fit: false,
            method: Method::Prioritized,
            limits_by_active_set: false,
            warm_start: false,
            max_passes: None,
        }
    }
}

impl Settings {
    /// Checks the fields; `inequalities`: whether the stack has inequality rows.
    fn validate(&self, inequalities: bool) -> Result<(), SolverError> {
        if inequalities || self.limits_by_active_set {
            let reason = "not available with inequality rows or limits_by_active_set";
            if self.scale_to_fit {
                return Err(SolverError::InvalidParameter {
                    name: "scale_to_fit",
                    value: 1.0,
                    reason,
                });
            }
            if let Method::WeightedDls { damping } = self.method {
                return Err(SolverError::InvalidParameter {
                    name: "method (weighted DLS damping)",
                    value: damping,
                    reason,
                });
            }
        }
        let check = |name, value: f64, positive: bool| {
            let ok = value.is_finite() && if positive { value > 0.0 } else { value >= 0.0 };
            if ok {
                Ok(())
            } else {
                Err(SolverError::InvalidParameter {
                    name,
                    value,
                    reason: if positive {
                        "must be finite and > 0"
                    } else {
                        "must be finite and >= 0"
                    },
                })
            }
        };
        if self.max_passes == Some(0) {
            return Err(SolverError::InvalidParameter {
                name: "max_passes",
                value: 0.0,
                reason: "a solve takes at least one pass",
            });
        }
        check("rank_tolerance", self.rank_tolerance, true)?;
        check("damping_threshold", self.damping_threshold, false)?;
        check("max_damping", self.max_damping, false)?;
        check("feasibility_tolerance", self.feasibility_tolerance, false)?;
        match self.method {
            Method::Prioritized => Ok(()),
            Method::WeightedDls { damping } => check("damping", damping, true),
        }
    }
}

/// What [`Solver::fit_scales`] leaves for the clamping loop.
enum Fitted {
    /// The whole step fits: `velocity` is the step.
    Step,
    /// `velocity` holds the scaled parts; the factorization is of the joints still free.
    Factored,
    /// The clamping ran out of joints to clamp: the next pass must factor again.
    Refactor,
}

/// Per-level factorization data, in the stacked workspace buffers.
#[derive(Debug, Clone, Copy, Default)]
struct LevelFactor {
    /// Dimension of the space the level was solved in, `r_{j−1}`.
    dim: usize,
    /// Rank used, `k_j`.
    rank: usize,
    /// Rows used: the level's equality rows and its active inequality rows.
    rows: usize,
    /// Damping `μ_j` of the level's least-squares solve (0: undamped).
    damping: f64,
}

/// A row a pass uses: an equality row (stacked index), or an active inequality row held at one of
/// its bounds.
#[derive(Debug, Clone, Copy)]
enum UsedRow {
    Equality(usize),
    Inequality(usize, Bound),
}

/// The Jacobian row and the desired velocity of a used row.
fn used_row(stack: &TaskStack, row: UsedRow, scale: f64) -> (&[f64], f64) {
    match row {
        UsedRow::Equality(r) => (stack.row(r), scale * stack.stacked_target()[r]),
        UsedRow::Inequality(r, bound) => {
            let (lower, upper) = stack.inequality_bounds(r);
            let value = match bound {
                Bound::Lower => lower,
                Bound::Upper => upper,
            };
            (stack.inequality_row(r), value)
        }
    }
}

/// Applies the reflectors of `factors` (levels `0..factors.len()`, level j's stored at
/// `n · seg_start[j]` in `qr`) to each vector `v` of free-joint coordinates stored `stride`
/// apart in `vectors`: afterwards `v[o_j..o_j + k_j]` is `U_jᵀ v` for each level's range basis
/// `U_j = Z_{j−1} Q_j[:, ..k_j]`. Returns the offset where the remaining null-space coordinates
/// start.
///
/// Each reflector goes to every vector before the next one does: a reflector's product waits
/// on the last one's update of the same vector, and the other vectors' products fill that
/// wait. Each vector sees the same operations in the same order as alone, so the result is
/// the same bit for bit; with a level's rows passed together, whole solves took 6–14 % less
/// time than with the rows one by one (`cargo bench --bench solver`).
fn apply_chain(
    qr: &[f64],
    n: usize,
    tau: &[f64],
    factors: &[LevelFactor],
    seg_start: &[usize],
    vectors: &mut [f64],
    stride: usize,
) -> usize {
    let mut offset = 0;
    for (j, f) in factors.iter().enumerate() {
        let start = seg_start[j];
        apply_level(&qr[n * start..], &tau[start..], f, vectors, stride, offset);
        offset += f.rank;
    }
    offset
}

/// Applies the reflectors of one level `f` (its factor and `tau` from the level's start) to
/// each vector `v` stored `stride` apart in `vectors`, whose `r_{j−1}` coordinates start at
/// `offset`: afterwards `v[offset..offset + k_j]` is `Q_j[:, ..k_j]ᵀ` of them. Reflector by
/// reflector, every vector in turn ([`apply_chain`]).
fn apply_level(
    factor: &[f64],
    tau: &[f64],
    f: &LevelFactor,
    vectors: &mut [f64],
    stride: usize,
    offset: usize,
) {
    for l in 0..f.rank {
        let reflector = &factor[l * f.dim + l..(l + 1) * f.dim];
        for v in vectors.chunks_mut(stride) {
            apply_reflector(reflector, tau[l], &mut v[offset + l..offset + f.dim]);
        }
    }
}

/// A prioritized task-stack solver: the stack, its workspace, and the last result.
///
/// Everything is allocated in [`Solver::new`]; [`Solver::solve`] allocates nothing.
#[derive(Debug, Clone)]
pub struct Solver {
    stack: TaskStack,
    settings: Settings,
    // Workspace, sized for (n, level rows).
    factors: Vec<LevelFactor>,
    /// First buffer row of each level (its equality rows plus all its inequality rows), and the
    /// total.
    seg_start: Vec<usize>,
    /// The rows each level uses in the current pass, at `seg_start`.
    used: Vec<UsedRow>,
    /// Per inequality row: the bound it is held at, or `None` while inactive.
    inequality_state: Vec<Option<Bound>>,
    active_set: ActiveSetWorkspace,
    /// `A_jᵀ` per level, column-major with leading dimension `r_{j−1}`, at offset `n · seg_j`;
    /// after factorization, `R_j` and the reflectors.
    qr: Vec<f64>,
    tau: Vec<f64>,
    perm: Vec<usize>,
    /// Per used row (at `n · (seg_j + t)`): its coordinates along the range bases of the levels
    /// above, `U_iᵀ J_rowᵀ` for i < j (the first `Σ_{i<j} k_i` entries), kept from the pass that
    /// factored them, so that a new right-hand side needs no new projection.
    projections: Vec<f64>,
    /// Right-hand side `b_j` per row, then `w_j` per level (at the level's start).
    rhs: Vec<f64>,
    coeff: Vec<f64>,
    /// Per level (at the level's start): the damping reference's coordinates `U_jᵀ q̇_ref`
    /// along its range basis, the `w` a damped level is damped toward.
    reference_coeff: Vec<f64>,
    /// Whether this pass has a nonzero damping reference.
    damp_toward_reference: bool,
    /// The damping reference in reduced coordinates, rotated level by level (length n).
    reference_coords: Vec<f64>,
    /// Per level (from `damped_start[j]`): the QR of a damped or rank-deficient level's
    /// stacked matrix `[Rᵀ; μ I]`, factored once per pass and reused for every right-hand side
    /// of the pass's repeats ([`Solver::repeat_pass`]); its reflectors' factors at the level's
    /// start in `damped_tau`.
    damped_qr: Vec<f64>,
    damped_start: Vec<usize>,
    damped_tau: Vec<f64>,
    /// Damped least-squares right-hand side (`2 m_max`).
    ls_rhs: Vec<f64>,
    /// Vector in reduced coordinates (length n).
    coords: Vec<f64>,
    free: Vec<usize>,
    clamped: Vec<bool>,
    fixed_velocity: Vec<f64>,
    step_lo: Vec<f64>,
    step_hi: Vec<f64>,
    velocity: Vec<f64>,
    /// Scale of each level's desired velocity in this solve, then of the gradient term.
    scales: Vec<f64>,
    /// The part of the step due to each level, then to the gradient (levels + 1 rows of n).
    contributions: Vec<f64>,
    /// Velocity limits of this solve.
    step_vmax: Vec<f64>,
    /// Largest row norm of the level being projected.
    row_scale: f64,
    /// The part of the step due to the clamped joints' fixed velocities, and a copy of those.
    base_velocity: Vec<f64>,
    saved_fixed: Vec<f64>,
    /// Weighted DLS: the `m × m` Gram matrix, `W⁻¹`, and `|∂H/∂q|` of the previous solve.
    gram: Vec<f64>,
    inverse_weight: Vec<f64>,
    previous_criterion: Vec<f64>,
    report: SolveReport,
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

    /// Solves the stack for `q̇` at configuration `q` with the clamping loop: `q + q̇ Δt` stays within
    /// the position limits and `|q̇|` within the velocity limits of `bounds` (see
    /// [`JointBounds`] for a `q` that starts outside its limits).
    ///
    /// `q` (rad or m) is only used for the bounds; Jacobians, targets and the gradient term are the
    /// ones in [`Solver::stack_mut`]. `dt` is the step duration in seconds (> 0).
    pub fn solve(
        &mut self,
        q: &[f64],
        bounds: &JointBounds,
        dt: f64,
    ) -> Result<Solution<'_>, SolverError> {
        let n = self.stack.dof();
        check_len("q", n, q.len())?;
        check_len("joint bounds", n, bounds.dof())?;
        check_finite_slice("q", q)?;
        if !(dt.is_finite() && dt > 0.0) {
            return Err(SolverError::InvalidParameter {
                name: "dt",
                value: dt,
                reason: "the time step must be finite and > 0 s",
            });
        }
        self.stack.check_finite()?;
        bounds.step_interval(q, dt, &mut self.step_lo, &mut self.step_hi);
        if self.uses_active_set() {
            self.solve_active_set();
            self.finish_report();
            return Ok(Solution {
                velocity: &self.velocity,
                report: &self.report,
            });
        }
        self.step_vmax.copy_from_slice(bounds.velocity());
        self.clamped.fill(false);
        self.fixed_velocity.fill(0.0);
        self.report.clamped.clear();
        self.report.clamping_iterations = 0;
        self.scales.fill(1.0);
        if let Method::WeightedDls { .. } = self.settings.method {
            self.update_limit_weights(q, bounds);
        }
        let mut next = match self.settings.scale_to_fit {
            true => self.fit_scales(),
            false => Fitted::Refactor,
        };
        loop {
            self.report.clamping_iterations += 1;
            match std::mem::replace(&mut next, Fitted::Refactor) {
                Fitted::Step => {}
                Fitted::Factored => self.repeat_pass(),
                Fitted::Refactor => self.pass(),
            }
            // Clamp the worst violator only, then solve again: clamping every violator at once
            // lets a near-singular raw solution decide the fate of joints it would not need.
            let mut worst: Option<(usize, f64, f64)> = None;
            for &i in &self.free {
                let v = self.velocity[i];
                let (bound, excess) = if v < self.step_lo[i] {
                    (self.step_lo[i], self.step_lo[i] - v)
                } else if v > self.step_hi[i] {
                    (self.step_hi[i], v - self.step_hi[i])
                } else {
                    continue;
                };
                if worst.is_none_or(|(_, _, e)| excess > e) {
                    worst = Some((i, bound, excess));
                }
            }
            let Some((i, bound, _)) = worst else { break };
            self.clamped[i] = true;
            self.fixed_velocity[i] = bound;
            self.report.clamped.push(i);
        }
        self.finish_report();
        Ok(Solution {
            velocity: &self.velocity,
            report: &self.report,
        })
    }

    /// Solves the stack without any joint limit (no clamping loop; the weighted DLS method
    /// uses unit weights).
    pub fn solve_unbounded(&mut self) -> Result<Solution<'_>, SolverError> {
        self.stack.check_finite()?;
        if self.uses_active_set() {
            self.step_lo.fill(f64::NEG_INFINITY);
            self.step_hi.fill(f64::INFINITY);
            self.solve_active_set();
            self.finish_report();
            return Ok(Solution {
                velocity: &self.velocity,
                report: &self.report,
            });
        }
        self.inverse_weight.fill(1.0);
        self.clamped.fill(false);
        self.fixed_velocity.fill(0.0);
        self.report.clamped.clear();
        self.report.clamping_iterations = 1;
        self.scales.fill(1.0);
        self.pass();
        self.finish_report();
        Ok(Solution {
            velocity: &self.velocity,
            report: &self.report,
        })
    }

    /// Sets `self.scales` (see [`Settings::scale_to_fit`]). The step is linear in the desired
    /// velocities: `base + Σ_k s_k C_k`, with `base` the part due to the clamped joints' fixed
    /// velocities and `C_k` the part due to level `k` alone (the last `k`: the gradient term), each
    /// one prioritized pass. A free joint at a position limit that the unscaled step pushes
    /// through it is clamped first (no scale can help it); then, highest level first, each scale
    /// is the largest in [0, 1] that keeps the running sum inside every free joint's interval.
    /// The whole step, every scale 1, comes first: when it fits, it is the step
    /// ([`Fitted::Step`]), and the parts are not computed.
    fn fit_scales(&mut self) -> Fitted {
        self.scales.fill(1.0);
        self.pass();
        let fits = |i: &usize| (self.step_lo[*i]..=self.step_hi[*i]).contains(&self.velocity[*i]);
        if self.free.iter().all(fits) {
            return Fitted::Step;
        }
        // The whole step's pass factored the free joints, and none has a fixed velocity yet.
        let mut factored = true;
        let mut fitted = Fitted::Refactor;
        for _ in 0..=self.stack.dof() {
            self.solve_parts(std::mem::take(&mut factored));
            if !self.clamp_blocked() {
                fitted = Fitted::Factored;
                break;
            }
        }
        self.sum_scaled_parts();
        fitted
    }

    /// The base part into `base_velocity` and each level's and the gradient's part into
    /// `contributions`, over the free joints; `factored`: the last pass factored them and no
    /// joint has a fixed velocity.
    fn solve_parts(&mut self, factored: bool) {
        let (n, parts) = (self.stack.dof(), self.scales.len());
        // Without fixed velocities there is no base part: the factoring pass gives level 0's
        // part instead.
        let no_base = self.fixed_velocity.iter().all(|&v| v == 0.0);
        let first_part = if factored {
            self.base_velocity.fill(0.0);
            0
        } else if no_base {
            self.scales.fill(0.0);
            self.scales[0] = 1.0;
            self.pass();
            self.base_velocity.fill(0.0);
            self.contributions[..n].copy_from_slice(&self.velocity);
            1
        } else {
            self.scales.fill(0.0);
            self.pass();
            self.base_velocity.copy_from_slice(&self.velocity);
            0
        };
        self.saved_fixed.copy_from_slice(&self.fixed_velocity);
        self.fixed_velocity.fill(0.0);
        // Each part is the same factorization with another right-hand side; the levels above
        // part k have none.
        for k in first_part..parts {
            self.scales.fill(0.0);
            self.scales[k] = 1.0;
            self.repeat_pass_from(k);
            self.contributions[k * n..(k + 1) * n].copy_from_slice(&self.velocity);
        }
        self.fixed_velocity.copy_from_slice(&self.saved_fixed);
    }

    /// Clamps every free joint that the running sum of the parts pushes through a position
    /// limit; returns whether it clamped any (the parts must then be solved again).
    ///
    /// A bound tighter than the velocity limit comes from a position limit: a joint pushed
    /// through it is clamped there (the paper's clamping), since slowing the step would only
    /// have it creep toward the limit. Velocity limits are left to the scales. The running sums
    /// are checked level by level, as the scales add them up: a joint at its limit that a
    /// higher level pushes out and a lower one pulls back in would otherwise scale the higher
    /// level, and every level after it, to zero, and the robot would stop for good. Every such
    /// joint is clamped at once (each is pinned by its own limit, whatever the others do).
    fn clamp_blocked(&mut self) -> bool {
        let (n, parts) = (self.stack.dof(), self.scales.len());
        let mut blocked = false;
        for i in 0..n {
            if self.clamped[i] {
                continue;
            }
            let (lo, hi, v) = (self.step_lo[i], self.step_hi[i], self.step_vmax[i]);
            let mut sum = self.base_velocity[i];
            for k in 0..parts {
                sum += self.contributions[k * n + i];
                let bound = if sum > hi && hi < v {
                    hi
                } else if sum < lo && lo > -v {
                    lo
                } else {
                    continue;
                };
                self.clamped[i] = true;
                self.fixed_velocity[i] = bound;
                self.report.clamped.push(i);
                blocked = true;
                break;
            }
        }
        blocked
    }

    /// Each scale, highest level first, the largest in [0, 1] that keeps the running sum of the
    /// scaled parts inside every free joint's interval; the sum into `velocity`.
    fn sum_scaled_parts(&mut self) {
        let (n, parts) = (self.stack.dof(), self.scales.len());
        self.velocity.copy_from_slice(&self.base_velocity);
        for k in 0..parts {
            let part = &self.contributions[k * n..(k + 1) * n];
            let mut scale = 1.0_f64;
            for i in (0..n).filter(|&i| !self.clamped[i]) {
                let (lo, hi, sum, c) =
                    (self.step_lo[i], self.step_hi[i], self.velocity[i], part[i]);
                if lo > 0.0 || hi < 0.0 {
                    continue; // outside its range: the clamping loop lands it
                }
                if sum + c > hi {
                    scale = scale.min(((hi - sum) / c).max(0.0));
                } else if sum + c < lo {
                    scale = scale.min(((lo - sum) / c).max(0.0));
                }
            }
            self.scales[k] = scale;
            for (v, c) in self.velocity.iter_mut().zip(part) {
                *v += scale * c;
            }
        }
    }

    /// One solve by the configured method over the joints not clamped; writes `self.velocity`.
    fn pass(&mut self) {
        match self.settings.method {
            Method::Prioritized => self.prioritized_pass(),
            Method::WeightedDls { damping } => self.weighted_dls_pass(damping),
        }
    }

    /// One prioritized solve over the joints not clamped; writes `self.velocity`.
    fn prioritized_pass(&mut self) {
        let n = self.stack.dof();
        self.free.clear();
        self.free.extend((0..n).filter(|&i| !self.clamped[i]));
        let mut dim = self.free.len();
        let reference = self.stack.damping_reference();
        self.damp_toward_reference = reference.iter().any(|&v| v != 0.0);
        for (c, &i) in self.reference_coords.iter_mut().zip(&self.free) {
            *c = reference[i];
        }
        let mut offset = 0;
        for j in 0..self.stack.level_count() {
            let rows = self.project_level_rows(j, dim);
            let (rank, damping) = self.factor_level(j, dim, rows);
            self.factors[j] = LevelFactor {
                dim,
                rank,
                rows,
                damping,
            };
            if self.damp_toward_reference {
                self.project_reference(j, offset);
            }
            self.solve_level(j, true);
            dim -= rank;
            offset += rank;
        }
        self.assemble_velocity();
    }

    /// Level j's range coordinates of the damping reference, `U_jᵀ q̇_ref`, into
    /// `reference_coeff`: `reference_coords[offset..]` holds `Z_{j−1}ᵀ q̇_ref` on entry and
    /// level j's reflectors are applied to it ([`apply_level`]).
    fn project_reference(&mut self, j: usize, offset: usize) {
        let (n, start, f) = (self.stack.dof(), self.seg_start[j], self.factors[j]);
        let cur = &mut self.reference_coords[offset..offset + f.dim];
        let dim = cur.len();
        apply_level(&self.qr[n * start..], &self.tau[start..], &f, cur, dim, 0);
        self.reference_coeff[start..start + f.rank].copy_from_slice(&cur[..f.rank]);
    }

    /// The last prioritized pass again for the current scales and fixed velocities, on its
    /// factorization (same free joints, same used rows): the velocity a new pass would give,
    /// bit for bit, without projecting and factoring the levels again.
    fn repeat_pass(&mut self) {
        self.repeat_pass_from(0);
    }

    /// [`Solver::repeat_pass`] for a right-hand side that is zero on the levels above `first`
    /// (their scales 0, no fixed velocities): their coefficients are zero and not solved for.
    fn repeat_pass_from(&mut self, first: usize) {
        if !matches!(self.settings.method, Method::Prioritized) {
            return self.pass();
        }
        for j in 0..self.stack.level_count() {
            if j < first {
                let start = self.seg_start[j];
                self.coeff[start..start + self.factors[j].rows].fill(0.0);
            } else {
                self.solve_level(j, false);
            }
        }
        self.assemble_velocity();
    }

    /// Lists the rows level `j` uses in this pass (its equality rows, then its active inequality
    /// rows), writes `A_jᵀ = Z_{j−1}ᵀ J_jᵀ` into level j's QR buffer and each row's
    /// coordinates along the levels above into `projections`. Returns the number of rows.
    fn project_level_rows(&mut self, j: usize, dim: usize) -> usize {
        let n = self.stack.dof();
        let seg = self.seg_start[j];
        let rows = self.list_used_rows(j);
        // Each row's free-joint coordinates, rotated in place in its `projections` slot (n
        // entries): the first `offset` are the row's coordinates along the levels above, the
        // next `dim` its column of `A_jᵀ`.
        let block = &mut self.projections[n * seg..n * (seg + rows)];
        self.row_scale = 0.0;
        for (t, coords) in block.chunks_mut(n).enumerate() {
            let (row, _) = used_row(&self.stack, self.used[seg + t], self.scales[j]);
            self.row_scale = self.row_scale.max(norm(row));
            for (c, &i) in coords.iter_mut().zip(&self.free) {
                *c = row[i];
            }
        }
        let (head, tail) = self.qr.split_at_mut(n * seg);
        let (factors, seg_start) = (&self.factors[..j], &self.seg_start);
        let offset = apply_chain(head, n, &self.tau, factors, seg_start, block, n);
        for (t, coords) in block.chunks(n).enumerate() {
            tail[t * dim..(t + 1) * dim].copy_from_slice(&coords[offset..offset + dim]);
        }
        rows
    }

    /// Writes level j's right-hand side `b_j = ẋ_j − J_j q̇_{j−1}` into `rhs`: the scaled
    /// targets less the clamped joints' and the levels above's velocities along each row.
    fn level_rhs(&mut self, j: usize) {
        let (n, seg) = (self.stack.dof(), self.seg_start[j]);
        for t in 0..self.factors[j].rows {
            let (row, target) = used_row(&self.stack, self.used[seg + t], self.scales[j]);
            let mut b = target - dot(row, &self.fixed_velocity);
            let projection = &self.projections[n * (seg + t)..];
            let mut level_offset = 0;
            for (i, f) in self.factors[..j].iter().enumerate() {
                let level_seg = self.seg_start[i];
                b -= dot(
                    &projection[level_offset..level_offset + f.rank],
                    &self.coeff[level_seg..level_seg + f.rank],
                );
                level_offset += f.rank;
            }
            self.rhs[seg + t] = b;
        }
    }

    /// Fills `used[seg_start[j]..]` with level j's equality rows, then its active inequality rows.
    fn list_used_rows(&mut self, j: usize) -> usize {
        let seg = self.seg_start[j];
        let (eq_start, eq_end) = (self.stack.level_start(j), self.stack.level_start(j + 1));
        let (in_start, in_end) = (
            self.stack.inequality_start(j),
            self.stack.inequality_start(j + 1),
        );
        let mut t = seg;
        for r in eq_start..eq_end {
            self.used[t] = UsedRow::Equality(r);
            t += 1;
        }
        for r in in_start..in_end {
            if let Some(side) = self.inequality_state[r] {
                self.used[t] = UsedRow::Inequality(r, side);
                t += 1;
            }
        }
        t - seg
    }

    /// Factorizes level j's `rows` projected rows. Returns the rank used and the damping its
    /// smallest kept singular value calls for.
    fn factor_level(&mut self, j: usize, dim: usize, rows: usize) -> (usize, f64) {
        let n = self.stack.dof();
        let start = self.seg_start[j];
        let a = &mut self.qr[n * start..n * start + dim * rows];
        let tau = &mut self.tau[start..start + rows];
        let perm = &mut self.perm[start..start + rows];
        // Rounding leaves ~1e-16 of a row's norm behind in the directions removed by the levels
        // above; on rows of any scale that noise must not count as rank.
        let tolerance = self
            .settings
            .rank_tolerance
            .max(RELATIVE_RANK_TOLERANCE * self.row_scale);
        let rank = qr_col_pivoting(a, dim, rows, tolerance, tau, perm);
        let mut damping = 0.0;
        if rank > 0 {
            let sigma = a[(rank - 1) * dim + rank - 1].abs();
            let eps = self.settings.damping_threshold;
            if sigma < eps {
                let ratio = sigma / eps;
                damping = self.settings.max_damping * (1.0 - ratio * ratio).sqrt();
            }
        }
        self.report.levels[j].rank = rank;
        self.report.levels[j].rows = rows;
        self.report.levels[j].damping = damping;
        (rank, damping)
    }

    /// Level j's right-hand side ([`Solver::level_rhs`]) and its least-squares coefficients
    /// `w_j` from the level's factorization; with `factor`, a damped or rank-deficient level's
    /// stacked matrix is factored first (once per pass: the repeats reuse it).
    fn solve_level(&mut self, j: usize, factor: bool) {
        self.level_rhs(j);
        let n = self.stack.dof();
        let start = self.seg_start[j];
        let LevelFactor {
            dim,
            rank,
            rows,
            damping,
        } = self.factors[j];
        let a = &self.qr[n * start..n * start + dim * rows];
        let perm = &self.perm[start..start + rows];
        let w = &mut self.coeff[start..start + rows];
        w.fill(0.0);
        if rank > 0 {
            let c = &mut self.ls_rhs[..rows + rank];
            for (ck, &p) in c.iter_mut().zip(perm.iter()) {
                *ck = self.rhs[start + p];
            }
            if rank == rows && damping == 0.0 {
                solve_upper_transposed(a, dim, rank, c);
            } else {
                // min ‖[Rᵀ; μ I] w − [c; μ w_ref]‖ by a QR of the stacked matrix, w_ref the
                // damping reference's coordinates (0 without one), scaled with the level.
                let aug_rows = rows + if damping > 0.0 { rank } else { 0 };
                let m = &mut self.damped_qr[self.damped_start[j]..][..aug_rows * rank];
                let tau = &mut self.damped_tau[start..start + rank];
                if factor {
                    m.fill(0.0);
                    for l in 0..rank {
                        // Rᵀ is lower-trapezoidal; below R's diagonal `a` holds reflectors.
                        for t in l..rows {
                            m[l * aug_rows + t] = a[t * dim + l];
                        }
                        if damping > 0.0 {
                            m[l * aug_rows + rows + l] = damping;
                        }
                    }
                    qr_factor(m, aug_rows, rank, tau);
                }
                c[rows..aug_rows].fill(0.0);
                // A level holding inequality rows at their bounds is damped toward rest: a
                // bound must not give way to the last step's momentum.
                let equalities = self.stack.level_start(j + 1) - self.stack.level_start(j);
                if damping > 0.0 && self.damp_toward_reference && rows == equalities {
                    let reference = &self.reference_coeff[start..start + rank];
                    for (ck, &r) in c[rows..aug_rows].iter_mut().zip(reference) {
                        *ck = damping * self.scales[j] * r;
                    }
                }
                apply_qt(m, aug_rows, rank, tau, &mut c[..aug_rows]);
                solve_upper(m, aug_rows, rank, c);
            }
            w[..rank].copy_from_slice(&c[..rank]);
        }
    }

    /// `q̇ = q̇_clamped + Z_0 (Σ_j Z-chain [w_j] + Z_N Z_Nᵀ g)`, folding the levels back from the
    /// deepest.
    fn assemble_velocity(&mut self) {
        let n = self.stack.dof();
        let levels = self.stack.level_count();
        // Z_Nᵀ g: the gradient through every level's reflectors.
        let gradient = self.stack.gradient();
        for (c, &i) in self.coords.iter_mut().zip(&self.free) {
            *c = self.scales[levels] * gradient[i];
        }
        let mut offset = apply_chain(
            &self.qr,
            n,
            &self.tau,
            &self.factors,
            &self.seg_start,
            &mut self.coords,
            n,
        );
        // Fold back: at level j the vector is [w_j; (deeper part)] in r_{j−1} coordinates.
        for j in (0..levels).rev() {
            let f = self.factors[j];
            let start = self.seg_start[j];
            offset -= f.rank;
            let factor = &self.qr[n * start..];
            let cur = &mut self.coords[offset..offset + f.dim];
            cur[..f.rank].copy_from_slice(&self.coeff[start..start + f.rank]);
            for l in (0..f.rank).rev() {
                apply_reflector(
                    &factor[l * f.dim + l..(l + 1) * f.dim],
                    self.tau[start + l],
                    &mut cur[l..],
                );
            }
        }
        self.velocity.copy_from_slice(&self.fixed_velocity);
        for (&c, &i) in self.coords.iter().zip(&self.free) {
            self.velocity[i] = c;
        }
    }

    /// Whether joint intervals and inequality rows are handled by the active-set method.
    fn uses_active_set(&self) -> bool {
        self.settings.limits_by_active_set || self.stack.total_inequality_rows() > 0
    }

    /// Residuals, violations and feasibility of every level for the final velocity, and the
    /// active inequality rows.
    fn finish_report(&mut self) {
        self.report.gradient_scale = self.scales[self.scales.len() - 1];
        self.report.active.clear();
        for j in 0..self.stack.level_count() {
            let (violation, bound_scale) = self.level_violation(j);
            let start = self.stack.level_start(j);
            let end = self.stack.level_start(j + 1);
            let targets = &self.stack.stacked_target()[start..end];
            // Reuse the least-squares scratch for the residual vector.
            let r = &mut self.ls_rhs[..end - start];
            for (t, (ri, &x)) in r.iter_mut().zip(targets).enumerate() {
                *ri = dot(self.stack.row(start + t), &self.velocity) - x;
            }
            let residual = norm(r);
            let level = &mut self.report.levels[j];
            level.residual = norm(&[residual, violation]);
            level.violation = violation;
            level.feasible = level.residual
                <= self.settings.feasibility_tolerance * (1.0 + norm(targets) + bound_scale);
            level.scale = self.scales[j];
        }
    }

    /// `‖v_j‖` of level j's inequality rows for the final velocity, and the norm of the bounds
    /// they violate (for the relative tolerance); lists the level's active rows in the report.
    fn level_violation(&mut self, j: usize) -> (f64, f64) {
        let (first, last) = (
            self.stack.inequality_start(j),
            self.stack.inequality_start(j + 1),
        );
        let (mut violation, mut bounds) = (0.0_f64, 0.0_f64);
        for r in first..last {
            let value = dot(self.stack.inequality_row(r), &self.velocity);
            let (lower, upper) = self.stack.inequality_bounds(r);
            let (v, b) = if value > upper {
                (value - upper, upper)
            } else if value < lower {
                (lower - value, lower)
            } else {
                (0.0, 0.0)
            };
            violation = norm(&[violation, v]);
            bounds = norm(&[bounds, b]);
            if let Some(bound) = self.inequality_state[r] {
                self.report.active.push(ActiveInequality {
                    level: j,
                    row: r - first,
                    bound,
                });
            }
        }
        (violation, bounds)
    }
}
