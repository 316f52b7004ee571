//! How the stack is solved ([`Method`]) and the solver's numerical settings ([`Settings`]).

use crate::solver::SolverError;

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
    /// [`limit_weight`](super::limit_weight)) and 1 otherwise, with
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
pub(super) const RELATIVE_RANK_TOLERANCE: f64 = 1e-12;

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
    /// method (see [`active_set`](super::active_set)), instead of the clamping loop: a joint held at a bound is
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
    pub(super) fn validate(&self, inequalities: bool) -> Result<(), SolverError> {
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
