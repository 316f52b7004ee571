//! What a solve achieved, level by level: the answer to "why did it fail".

/// Which side of an inequality row `l ≤ c q̇ ≤ u` (or of a joint's interval) holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Bound {
    /// `c q̇ = l`.
    Lower,
    /// `c q̇ = u`.
    Upper,
}

/// An inequality row the active-set solve held at a bound: it is met with equality there (or,
/// when the level gave way, violated by the least-squares amount).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ActiveInequality {
    /// Level index (0 = highest priority).
    pub level: usize,
    /// Row among the level's inequality rows.
    pub row: usize,
    /// The bound it is held at.
    pub bound: Bound,
}

/// Outcome of one level.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct LevelReport {
    /// Rows the level used in the final solve: its equality rows `m_j` and its active inequality
    /// rows.
    pub rows: usize,
    /// Rank of the level inside the null space left by the levels above it (and by the clamped
    /// joints): how many independent directions it could use. `rank < rows` means some rows are
    /// redundant or conflict with higher levels.
    pub rank: usize,
    /// `‖(J_j q̇ − ẋ_j, v_j)‖` for the final `q̇` (task velocity units, e.g. m/s): the equality
    /// residual and the inequality violations `v_j = max(0, C_j q̇ − u_j, l_j − C_j q̇)`.
    pub residual: f64,
    /// `‖v_j‖`, the inequality part of the residual (0 when the level's inequalities hold).
    pub violation: f64,
    /// Whether the residual is within the feasibility tolerance (see
    /// [`Settings::feasibility_tolerance`](super::Settings::feasibility_tolerance)). An infeasible
    /// level got its least-squares best inside the null space of the levels above it.
    pub feasible: bool,
    /// The damping factor `μ` used for this level (0 when it was well conditioned).
    pub damping: f64,
    /// The fraction of its desired velocity the level was given to fit the velocity intervals
    /// ([`Settings::scale_to_fit`](super::Settings::scale_to_fit)); 1 when it was not needed or
    /// scaling is off. The residual is against the unscaled desired velocity.
    pub scale: f64,
}

/// Outcome of a solve, including the clamping loop.
#[derive(Debug, Clone, PartialEq)]
pub struct SolveReport {
    pub(crate) levels: Vec<LevelReport>,
    pub(crate) clamped: Vec<usize>,
    pub(crate) clamping_iterations: usize,
    pub(crate) gradient_scale: f64,
    pub(crate) active: Vec<ActiveInequality>,
    pub(crate) active_set_iterations: usize,
    pub(crate) converged: bool,
}

impl SolveReport {
    pub(crate) fn with_capacity(levels: usize, dof: usize, inequalities: usize) -> Self {
        Self {
            levels: vec![LevelReport::default(); levels],
            clamped: Vec::with_capacity(dof),
            clamping_iterations: 0,
            gradient_scale: 1.0,
            active: Vec::with_capacity(inequalities),
            active_set_iterations: 0,
            converged: true,
        }
    }

    /// The inequality rows held at a bound by the active-set solve (level order, then row
    /// order); empty for a stack without inequality rows.
    pub fn active_inequalities(&self) -> &[ActiveInequality] {
        &self.active
    }

    /// Steps of the active-set method (each a prioritized solve); 0 when the stack was solved by
    /// the clamping loop.
    pub fn active_set_iterations(&self) -> usize {
        self.active_set_iterations
    }

    /// Whether the active-set method reached the lexicographic optimum within its iteration
    /// cap; when it did not, the velocity is the last iterate, which still meets every joint
    /// interval and every inequality row it had not given up. Always true for the clamping loop.
    pub fn converged(&self) -> bool {
        self.converged
    }

    /// Per-level outcomes, highest priority first.
    pub fn levels(&self) -> &[LevelReport] {
        &self.levels
    }

    /// Joints fixed at a bound of their interval for this step: by the clamping loop, in the order
    /// they were clamped; by the active-set method, in index order.
    pub fn clamped_joints(&self) -> &[usize] {
        &self.clamped
    }

    /// Number of prioritized solves the clamping loop ran (1 when no joint had to be clamped).
    pub fn clamping_iterations(&self) -> usize {
        self.clamping_iterations
    }

    /// The scale applied to the gradient term to fit the velocity intervals
    /// ([`Settings::scale_to_fit`](super::Settings::scale_to_fit)); 1 when it was not needed or
    /// scaling is off.
    pub fn gradient_scale(&self) -> f64 {
        self.gradient_scale
    }

    /// Index of the first level that is not feasible, if any: the highest level that gave way.
    pub fn first_infeasible_level(&self) -> Option<usize> {
        self.levels.iter().position(|l| !l.feasible)
    }
}

/// The result of a solve: the joint velocity and the report, borrowed from the solver.
#[derive(Debug, Clone, Copy)]
pub struct Solution<'a> {
    /// Joint velocity `q̇` (rad/s or m/s), one entry per joint.
    pub velocity: &'a [f64],
    /// What each level achieved, and the clamping loop's work.
    pub report: &'a SolveReport,
}
