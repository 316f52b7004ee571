//! The active-set method's scratch ([`ActiveSetWorkspace`]), sized when the solver is built.

use crate::solver::report::{Bound, LevelReport};

/// Scratch of the active-set method, sized at construction.
#[derive(Debug, Clone)]
pub(crate) struct ActiveSetWorkspace {
    /// The iterate `x` (n).
    pub(super) point: Vec<f64>,
    /// `x* − x` (n).
    pub(super) direction: Vec<f64>,
    /// `−∇_j` minus the rows' parts found so far (n).
    pub(super) residual: Vec<f64>,
    /// `ν` per used row, at the level's buffer offset.
    pub(super) multipliers: Vec<f64>,
    /// Back-substitution scratch (largest level).
    pub(super) mu: Vec<f64>,
    /// Bounds whose fate a higher level already decided.
    pub(super) decided_rows: Vec<bool>,
    pub(super) decided_joints: Vec<bool>,
    /// The active sets met at their optimum in this solve, one [`Self::state_len`] slot each
    /// (a joint's or row's bound: 0 none, 1 lower, 2 upper), and one slot more for the set
    /// being checked.
    pub(super) seen: Vec<u8>,
    /// Slots of `seen` in use.
    pub(super) seen_count: usize,
    /// The level reports of the pass at the last optimum, for a run that ends there without
    /// solving it again ([`Solver::run_active_set`]).
    pub(super) optimum_levels: Vec<LevelReport>,
    /// The bound each joint and inequality row was held at when the last solve ended: the
    /// start of the next one with [`Settings::warm_start`](crate::solver::Settings::warm_start).
    pub(super) warm_joints: Vec<Option<Bound>>,
    pub(super) warm_rows: Vec<Option<Bound>>,
    /// Whether the last solve converged: only then is its active set worth starting from.
    pub(super) warm_valid: bool,
}

impl ActiveSetWorkspace {
    pub(crate) fn new(
        dof: usize,
        levels: usize,
        capacity: usize,
        inequalities: usize,
        level_max: usize,
    ) -> Self {
        Self {
            point: vec![0.0; dof],
            direction: vec![0.0; dof],
            residual: vec![0.0; dof],
            multipliers: vec![0.0; capacity],
            mu: vec![0.0; level_max],
            decided_rows: vec![false; inequalities],
            decided_joints: vec![false; dof],
            seen: vec![0; (iteration_cap(dof, inequalities) + 1) * (dof + inequalities)],
            seen_count: 0,
            optimum_levels: vec![LevelReport::default(); levels],
            warm_joints: vec![None; dof],
            warm_rows: vec![None; inequalities],
            warm_valid: false,
        }
    }

    /// Entries of one active set in `seen`.
    pub(super) fn state_len(&self) -> usize {
        self.decided_joints.len() + self.decided_rows.len()
    }
}

/// Most steps of the active-set method for `n` joints and `p` inequality rows.
pub(super) fn iteration_cap(n: usize, p: usize) -> usize {
    4 * (n + p) + 8
}
