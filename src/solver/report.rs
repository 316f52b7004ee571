//! What a solve achieved, level by level: the answer to "why did it fail".

/// Outcome of one equality level.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct LevelReport {
    /// Rows of the level, `m_j`.
    pub rows: usize,
    /// Rank of the level inside the null space left by the levels above it (and by the clamped
    /// joints): how many independent directions it could use. `rank < rows` means some rows are
    /// redundant or conflict with higher levels.
    pub rank: usize,
    /// `‖J_j q̇ − ẋ_j‖` for the final `q̇` (task velocity units, e.g. m/s).
    pub residual: f64,
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
}

impl SolveReport {
    pub(crate) fn with_capacity(levels: usize, dof: usize) -> Self {
        Self {
            levels: vec![LevelReport::default(); levels],
            clamped: Vec::with_capacity(dof),
            clamping_iterations: 0,
            gradient_scale: 1.0,
        }
    }

    /// Per-level outcomes, highest priority first.
    pub fn levels(&self) -> &[LevelReport] {
        &self.levels
    }

    /// Joints fixed at a bound by the clamping loop (indices, in the order they were clamped).
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
