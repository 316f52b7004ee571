//! Inequality rows at any level, and joint intervals above every level, by a primal active-set
//! method on the prioritized null-space solve (Kanoun, Lamiraux & Wieber 2011; Escande, Mansard &
//! Wieber 2014).
//!
//! # Problem
//!
//! Level `j` has equality rows `J_j q̇ = ẋ_j` and inequality rows `l_j ≤ C_j q̇ ≤ u_j`; above every
//! level, each joint's interval for this step `lo ≤ q̇ ≤ hi` (position limits over `Δt` and
//! velocity limits, see [`JointBounds`](crate::solver::JointBounds)); below every level, the
//! gradient term `q̇ = g` (`g = 0` without an optimization task: the minimum-norm solution). The
//! solve is lexicographic: the joint intervals hold; level 1 minimizes
//! `‖J_1 q̇ − ẋ_1‖² + ‖v_1(q̇)‖²`, with `v_j = max(0, C_j q̇ − u_j, l_j − C_j q̇)` the violations,
//! among the joint-feasible `q̇`; level 2 does the same among the minimizers of level 1; and so on;
//! last, `‖q̇ − g‖²` picks the one minimizer. A level's inequalities are thus met whenever the
//! levels above leave room, and otherwise violated by the least-squares amount, without costing a
//! higher level anything. Inequality rows of a level that gave way stay bounds for the levels
//! below at the violated value.
//!
//! # Method
//!
//! An **active set** holds the inequality rows and joints currently held at a bound. With it fixed,
//! the problem is an equality hierarchy — each active row an equality row of its own level at its
//! bound, each active joint clamped — solved exactly by the null-space recursion of
//! [`prioritized`](super). The iterate `x` starts at `0` with the joints outside their interval
//! clamped to it and the rows it violates active; from then on every inactive row and free joint
//! holds at `x`. A **warm start** ([`Settings::warm_start`](crate::solver::Settings::warm_start))
//! starts from the bounds the previous solve ended with instead, and when the first `x*` meets
//! every bound, `x = x*` (a feasible iterate) and the method goes on at step 3, which releases
//! the bounds not wanted; in a control loop most solves end there. Each step:
//!
//! 1. `x* =` the hierarchy's solution for the active set.
//! 2. If moving from `x` to `x*` would take an inactive row or a free joint past a bound, move to
//!    the first such bound and activate it (primal feasibility is kept).
//! 3. Otherwise `x = x*`, and the **lexicographic multipliers** decide whether an active bound may
//!    go. For level `j` (and last the gradient level), `−∇_j = −J_jᵀ (J_j x − ẋ_j)` (active rows
//!    included) is written as `Σ_{p<j} J_pᵀ ν_p + Σ_clamped ν_i e_i` by back-substitution through
//!    the factorization: `U_pᵀ r = R_p Π_pᵀ ν_p` for the range basis `U_p` of level `p`, deepest
//!    level first, subtracting `J_pᵀ ν_p` as it goes (from `r`'s coordinates `U_iᵀ r` too, by
//!    the rows' projections `U_iᵀ J_pᵀ` kept from the pass, so that the reflectors are applied
//!    once per level judged); what remains on a clamped joint is its multiplier. A row held at
//!    its upper bound is wanted there at level `j` if `ν > 0`, at its lower bound if `ν < 0` (a
//!    clamped joint likewise). A row's own level speaks first: its residual `C q̇ − u` is its
//!    multiplier there. Levels are read top-down; the first level that has a bound it does not
//!    want, among bounds no higher level decided on, releases the most unwanted one.
//!
//! With exact least squares at every level the objective decreases lexicographically at every
//! step, so no active set comes back and the method ends. A **damped** level (near-singular, see
//! [`Settings::max_damping`](crate::solver::Settings::max_damping)) does not minimize its exact
//! residual, so its multipliers can ask for a bound that its own damped solve then crosses
//! again, and the method comes back to an active set it had: on the NAO a CoM level near a
//! stretched knee released a bound that the next solve crossed at once (`τ = 0`), on one frame
//! in fifteen of a walk clip, and two joints of a lifting leg took turns in a six-step loop;
//! each ran to the cap, 20–35× a frame's median time. The method is deterministic and its
//! iterate at an active set's optimum (`x = x*`, step 3) depends on the set alone, so a set met
//! there again would only repeat the same steps: the solve **ends** at once with that iterate,
//! not converged (in the `τ = 0` cycles the iterate the cap would have returned). When the
//! bound released at an optimum blocks the very next step at `τ = 0`, the set and the iterate
//! are that optimum's again before any solve: the run ends there one prioritized solve sooner,
//! with the same iterate. Keeping the bound and going on instead changed where other solves
//! ended and let a placed hand sink into its support in a test. An iteration cap
//! (`4 (n + p) + 8` prioritized solves, `p` the inequality rows) bounds any other cycle; the
//! report says whether the method converged. The iterate keeps every joint interval at every
//! step, so even a capped solve never violates a limit. A budget of passes per solve
//! ([`Settings::max_passes`](crate::solver::Settings::max_passes)) bounds a control tick's time
//! more tightly: the iterate it ends at is feasible in the same way.

pub(super) mod workspace;

use super::rows::{UsedRow, apply_chain, used_row};
use super::solver::Solver;
use crate::solver::householder::{dot, norm, solve_upper};
use crate::solver::report::Bound;
use workspace::iteration_cap;

/// A multiplier is taken as zero below this fraction of its level's gradient norm (plus one).
const MULTIPLIER_TOLERANCE: f64 = 1e-9;

/// A bound's code in an active-set record.
fn bound_code(bound: Option<Bound>) -> u8 {
    match bound {
        None => 0,
        Some(Bound::Lower) => 1,
        Some(Bound::Upper) => 2,
    }
}

/// The bound a joint is held at: `None` while free, else the side its fixed velocity `fixed`
/// sits on (`hi`, the interval's upper end, or the lower one).
fn held_bound(clamped: bool, fixed: f64, hi: f64) -> Option<Bound> {
    clamped.then_some(if fixed == hi {
        Bound::Upper
    } else {
        Bound::Lower
    })
}

/// A joint's velocity at a cold start: 0, or the end of its interval nearest 0 when the
/// interval excludes 0.
fn cold_start_velocity(lo: f64, hi: f64) -> f64 {
    if lo > 0.0 {
        lo
    } else if hi < 0.0 {
        hi
    } else {
        0.0
    }
}

/// The velocity a joint with the interval `lo..=hi` is held at when a run starts, if held: at
/// its `warm` bound where that is finite, else at the end nearest 0 of an interval that
/// excludes 0.
fn start_hold(warm: Option<Bound>, lo: f64, hi: f64) -> Option<f64> {
    match warm {
        Some(Bound::Upper) if hi.is_finite() => Some(hi),
        Some(Bound::Lower) if lo.is_finite() => Some(lo),
        _ => Some(cold_start_velocity(lo, hi)).filter(|&x| x != 0.0),
    }
}

/// The bound of `lower ≤ value ≤ upper` that `value` violates, if any.
fn violated_bound(value: f64, lower: f64, upper: f64) -> Option<Bound> {
    if value > upper {
        Some(Bound::Upper)
    } else if value < lower {
        Some(Bound::Lower)
    } else {
        None
    }
}

/// Whether a row's `bound` side is finite (a side at ±∞ cannot hold).
fn finite_bound(bound: Bound, lower: f64, upper: f64) -> bool {
    match bound {
        Bound::Upper => upper.is_finite(),
        Bound::Lower => lower.is_finite(),
    }
}

/// Why a run of the active-set method ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum End {
    /// At the lexicographic optimum.
    Converged,
    /// At an active set met at its optimum before in this run.
    Cycle,
    /// After the steps it was allowed (the method's cap or the settings' budget).
    Budget,
}

/// A bound that enters or leaves the active set: a joint's interval, or an inequality row.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Constraint {
    Joint(usize, Bound),
    Row(usize, Bound),
}

/// The most unwanted bound found so far at one level, and how unwanted (a negative pull).
type Worst = Option<(f64, Constraint)>;

/// How much a row or joint held at `bound` is wanted there, from the signed amount `toward_upper`
/// by which something pushes it toward its upper side (a residual or a multiplier).
fn pull(bound: Bound, toward_upper: f64) -> f64 {
    match bound {
        Bound::Upper => toward_upper,
        Bound::Lower => -toward_upper,
    }
}

/// Records a bound's pull (how much a level wants it held: > 0 wanted, < 0 not): a clear answer
/// decides its fate; an unwanted one is a release candidate.
fn judge(pull: f64, tolerance: f64, bound: Constraint, decided: &mut bool, worst: &mut Worst) {
    if pull > tolerance {
        *decided = true;
    } else if pull < -tolerance {
        *decided = true;
        if worst.is_none_or(|(p, _)| pull < p) {
            *worst = Some((pull, bound));
        }
    }
}

impl Solver {
    /// Solves with the joint intervals in `step_lo`/`step_hi` (±∞ for none) and the inequality
    /// rows by the active-set method; writes `velocity` and the report's joint and iteration
    /// entries. A warm start that does not converge (a damped level's cycle, or the cap) is
    /// solved again cold: a bound the warm set carried in can keep such a cycle going frame
    /// after frame (on the NAO's hand levels it left the hands 15 cm off), where a cold
    /// start's path would not have met it. A warm start that holds the very bounds a cold
    /// start holds is run as the cold start, once (the cold run would repeat its steps). After a solve that did not converge the next one
    /// starts cold: where the cold method itself cycles (the NAO's lift and landing phases,
    /// frame after frame), a warm try first only doubled the cost. With a budget
    /// ([`Settings::max_passes`](crate::solver::Settings::max_passes)) the two runs share it; a
    /// run that spends it ends there.
    pub(super) fn solve_active_set(&mut self) {
        let n = self.stack.dof();
        self.scales.fill(1.0);
        let cap = iteration_cap(n, self.stack.total_inequality_rows());
        let budget = self.settings.max_passes;
        let limit = budget.map_or(cap, |b| b.min(cap));
        let warm =
            self.settings.warm_start && self.active_set.warm_valid && !self.warm_start_is_cold();
        let (mut iterations, mut end) = self.run_active_set(warm, limit);
        // Out of budget, the warm iterate is the answer; otherwise a warm start that did not
        // converge is retried cold with what is left.
        let retry = match budget {
            None => cap,
            Some(_) if end == End::Budget => 0,
            Some(_) => limit - iterations,
        };
        if warm && end != End::Converged && retry > 0 {
            let (cold, cold_end) = self.run_active_set(false, retry);
            (iterations, end) = (iterations + cold, cold_end);
        }
        self.velocity.copy_from_slice(&self.active_set.point);
        self.keep_active_set();
        // Only an optimum's set is a start: a set cut short by the budget is one the method
        // was passing through, and warm starts from such sets, frame after frame, left the
        // NAO's higher levels a fraction of their motion (a held foot turned 2–6° in physics).
        self.active_set.warm_valid = end == End::Converged;
        self.report.clamped.clear();
        self.report
            .clamped
            .extend((0..n).filter(|&i| self.clamped[i]));
        self.report.clamping_iterations = 0;
        self.report.active_set_iterations = iterations;
        self.report.converged = end == End::Converged;
    }

    /// The method's steps from a cold or `warm` start until it converges, meets an active set
    /// again or has taken `limit` steps; the iterate is left in the workspace's `point`.
    /// Returns the steps taken and why it ended.
    fn run_active_set(&mut self, warm: bool, limit: usize) -> (usize, End) {
        let n = self.stack.dof();
        self.start_active_set(warm);
        // The bound released at the last optimum, until the next step.
        let mut released = None;
        for iterations in 1..=limit {
            self.prioritized_pass();
            // A warm set's first solution that meets every bound is a feasible iterate
            // itself: the method goes on from there.
            let warm_start_met = warm && iterations == 1 && self.meets_bounds();
            let ws = &mut self.active_set;
            for i in 0..n {
                ws.direction[i] = self.velocity[i] - ws.point[i];
            }
            let blocking = match warm_start_met {
                true => None,
                false => self.first_blocking(),
            };
            if let Some((tau, blocking)) = blocking {
                let ws = &mut self.active_set;
                for i in 0..n {
                    ws.point[i] += tau * ws.direction[i];
                }
                self.activate(blocking);
                let back = tau == 0.0 && released == Some(blocking) && iterations < limit;
                if back && self.optimum_repeated() {
                    return (iterations, End::Cycle);
                }
                released = None;
                continue;
            }
            self.active_set.point.copy_from_slice(&self.velocity);
            if self.met_before() {
                // The same steps would follow again, and end here again.
                return (iterations, End::Cycle);
            }
            match self.release_candidate() {
                Some(bound) => {
                    let levels = &self.report.levels;
                    self.active_set.optimum_levels.copy_from_slice(levels);
                    self.release(bound);
                    released = Some(bound);
                }
                None => return (iterations, End::Converged),
            }
        }
        (limit, End::Budget)
    }

    /// Records the bounds held at the end of this solve for the next one's warm start.
    fn keep_active_set(&mut self) {
        let ws = &mut self.active_set;
        for (i, warm) in ws.warm_joints.iter_mut().enumerate() {
            *warm = held_bound(self.clamped[i], self.fixed_velocity[i], self.step_hi[i]);
        }
        ws.warm_rows.copy_from_slice(&self.inequality_state);
    }

    /// `x = 0`, with the joints whose interval excludes 0 clamped to it and the rows `x` violates
    /// active. With a `warm` start the bounds the last solve ended with are active instead,
    /// where finite (a joint whose interval excludes 0 is clamped all the same): the first `x*`
    /// then starts the method where it meets every bound, and otherwise a row `x` violates
    /// blocks the first step at once.
    fn start_active_set(&mut self, warm: bool) {
        self.clamped.fill(false);
        self.fixed_velocity.fill(0.0);
        let ws = &mut self.active_set;
        ws.seen_count = 0;
        for i in 0..self.stack.dof() {
            let (lo, hi) = (self.step_lo[i], self.step_hi[i]);
            ws.point[i] = cold_start_velocity(lo, hi);
            let Some(held) = start_hold(ws.warm_joints[i].filter(|_| warm), lo, hi) else {
                continue;
            };
            self.clamped[i] = true;
            self.fixed_velocity[i] = held;
        }
        for r in 0..self.stack.total_inequality_rows() {
            let (lower, upper) = self.stack.inequality_bounds(r);
            self.inequality_state[r] = if warm {
                ws.warm_rows[r].filter(|&b| finite_bound(b, lower, upper))
            } else {
                violated_bound(dot(self.stack.inequality_row(r), &ws.point), lower, upper)
            };
        }
    }

    /// Whether a warm start would begin with the very bounds a cold start holds: the two runs
    /// would then take the same steps, and a warm run that does not converge is not worth
    /// retrying cold.
    fn warm_start_is_cold(&mut self) -> bool {
        let ws = &mut self.active_set;
        for i in 0..self.stack.dof() {
            let (lo, hi) = (self.step_lo[i], self.step_hi[i]);
            // `direction` is free until the run starts: it holds the cold start point here.
            ws.direction[i] = cold_start_velocity(lo, hi);
            if start_hold(ws.warm_joints[i], lo, hi) != start_hold(None, lo, hi) {
                return false;
            }
        }
        (0..self.stack.total_inequality_rows()).all(|r| {
            let (lower, upper) = self.stack.inequality_bounds(r);
            let value = dot(self.stack.inequality_row(r), &ws.direction);
            let cold = violated_bound(value, lower, upper);
            let warm = ws.warm_rows[r].filter(|&b| finite_bound(b, lower, upper));
            warm == cold
        })
    }

    /// Whether `velocity` keeps every free joint in its interval and every inactive row within
    /// its bounds (up to the feasibility tolerance).
    fn meets_bounds(&self) -> bool {
        let joints_in = (self.free.iter())
            .all(|&i| self.step_lo[i] <= self.velocity[i] && self.velocity[i] <= self.step_hi[i]);
        joints_in
            && (0..self.stack.total_inequality_rows())
                .filter(|&r| self.inequality_state[r].is_none())
                .all(|r| {
                    let value = dot(self.stack.inequality_row(r), &self.velocity);
                    let (lower, upper) = self.stack.inequality_bounds(r);
                    lower - self.slack(lower) <= value && value <= upper + self.slack(upper)
                })
    }

    /// How far past `bound` a row may be and still count as within it.
    fn slack(&self, bound: f64) -> f64 {
        self.settings.feasibility_tolerance * (1.0 + bound.abs())
    }

    /// The first bound the step `x → x + direction` crosses, with the step fraction `τ < 1` that
    /// reaches it. Joint intervals are exact; a row crosses only if the full step would violate it
    /// by more than the feasibility tolerance. A row released from one bound while its level's
    /// least-squares fit had taken it past the other is violated at `x` already: it blocks at
    /// `τ = 0`, which moves it to the other bound.
    fn first_blocking(&self) -> Option<(f64, Constraint)> {
        let ws = &self.active_set;
        let mut best: Option<(f64, Constraint)> = None;
        let mut consider = |tau: f64, c: Constraint| {
            let tau = tau.max(0.0);
            if tau < best.map_or(1.0, |(t, _)| t) {
                best = Some((tau, c));
            }
        };
        for &i in &self.free {
            let (x, d) = (ws.point[i], ws.direction[i]);
            if x + d > self.step_hi[i] {
                consider(
                    (self.step_hi[i] - x) / d,
                    Constraint::Joint(i, Bound::Upper),
                );
            } else if x + d < self.step_lo[i] {
                consider(
                    (self.step_lo[i] - x) / d,
                    Constraint::Joint(i, Bound::Lower),
                );
            }
        }
        for r in 0..self.stack.total_inequality_rows() {
            if self.inequality_state[r].is_some() {
                continue;
            }
            let row = self.stack.inequality_row(r);
            let (value, change) = (dot(row, &ws.point), dot(row, &ws.direction));
            let (lower, upper) = self.stack.inequality_bounds(r);
            let (above, below) = (upper + self.slack(upper), lower - self.slack(lower));
            if value > above {
                consider(0.0, Constraint::Row(r, Bound::Upper));
            } else if value < below {
                consider(0.0, Constraint::Row(r, Bound::Lower));
            } else if value + change > above {
                consider((upper - value) / change, Constraint::Row(r, Bound::Upper));
            } else if value + change < below {
                consider((lower - value) / change, Constraint::Row(r, Bound::Lower));
            }
        }
        best
    }

    fn activate(&mut self, c: Constraint) {
        match c {
            Constraint::Joint(i, bound) => {
                self.clamped[i] = true;
                self.fixed_velocity[i] = match bound {
                    Bound::Lower => self.step_lo[i],
                    Bound::Upper => self.step_hi[i],
                };
                // The step onto the bound may round past it; the iterate holds it exactly.
                self.active_set.point[i] = self.fixed_velocity[i];
            }
            Constraint::Row(r, bound) => self.inequality_state[r] = Some(bound),
        }
    }

    fn release(&mut self, c: Constraint) {
        match c {
            Constraint::Joint(i, _) => {
                self.clamped[i] = false;
                self.fixed_velocity[i] = 0.0;
            }
            Constraint::Row(r, _) => self.inequality_state[r] = None,
        }
    }

    /// Whether the current active set was met at its optimum before in this solve; records it
    /// if not.
    fn met_before(&mut self) -> bool {
        if self.seen_before() {
            return true;
        }
        // Past the cap's number of slots the loop ends anyway.
        let ws = &mut self.active_set;
        if (ws.seen_count + 2) * ws.state_len() <= ws.seen.len() {
            ws.seen_count += 1;
        }
        false
    }

    /// Whether the current active set was met at its optimum before in this solve; writes it
    /// into the slot after the recorded ones.
    fn seen_before(&mut self) -> bool {
        let ws = &mut self.active_set;
        let len = ws.state_len();
        let (seen, slot) = ws.seen.split_at_mut(ws.seen_count * len);
        let slot = &mut slot[..len];
        let (joints, rows) = slot.split_at_mut(self.clamped.len());
        for (code, i) in joints.iter_mut().zip(0..) {
            *code = bound_code(held_bound(
                self.clamped[i],
                self.fixed_velocity[i],
                self.step_hi[i],
            ));
        }
        for (code, state) in rows.iter_mut().zip(&self.inequality_state) {
            *code = bound_code(*state);
        }
        seen.chunks_exact(len).any(|old| old == slot)
    }

    /// Whether the bound just released at an optimum, crossed again at once (`τ = 0`) and held
    /// again, brought the run back to that optimum, to end there as the next step would: the
    /// active set is the optimum's again and `x` its solution unchanged, so the next pass would
    /// give `x* = x` bit for bit, no bound would block, and the set would be met before (a
    /// damped level's cycle, see the module docs). Saves that pass; the report's levels are the
    /// optimum's pass's again. Checks what the next step would: no row blocks at `x`, and the
    /// set is on record.
    fn optimum_repeated(&mut self) -> bool {
        self.active_set.direction.fill(0.0);
        if self.first_blocking().is_some() || !self.seen_before() {
            return false;
        }
        let levels = &self.active_set.optimum_levels;
        self.report.levels.copy_from_slice(levels);
        true
    }

    /// The bound to release at `x = x*`, if any (step 3 of the method in the module docs).
    fn release_candidate(&mut self) -> Option<Constraint> {
        let levels = self.stack.level_count();
        self.active_set.decided_rows.fill(false);
        self.active_set.decided_joints.fill(false);
        for j in 0..=levels {
            // A level only speaks on the bounds no level above decided on.
            if self.every_bound_decided() {
                return None;
            }
            let mut worst: Worst = None;
            if j < levels {
                self.judge_own_rows(j, &mut worst);
            }
            self.load_negative_gradient(j);
            let tolerance = MULTIPLIER_TOLERANCE * (1.0 + norm(&self.active_set.residual));
            self.residual_coordinates(j);
            for p in (0..j).rev() {
                self.back_substitute(p);
            }
            self.judge_multipliers(j, tolerance, &mut worst);
            if let Some((_, c)) = worst {
                return Some(c);
            }
        }
        None
    }

    /// Whether a level above decided the fate of every active bound: every active inequality
    /// row, and every clamped joint whose interval has room (a zero-width one is pinned
    /// whatever the levels want). The levels below then have nothing to release.
    fn every_bound_decided(&self) -> bool {
        let ws = &self.active_set;
        let rows = (self.inequality_state.iter().zip(&ws.decided_rows))
            .all(|(state, &decided)| state.is_none() || decided);
        rows && (0..self.stack.dof())
            .all(|i| !self.clamped[i] || ws.decided_joints[i] || self.step_lo[i] >= self.step_hi[i])
    }

    /// Level j's active rows at their own level: the residual beyond the bound is the multiplier
    /// of the row's slack.
    fn judge_own_rows(&mut self, j: usize, worst: &mut Worst) {
        let seg = self.seg_start[j];
        let tolerance = self.settings.feasibility_tolerance;
        for t in 0..self.factors[j].rows {
            let UsedRow::Inequality(r, bound) = self.used[seg + t] else {
                continue;
            };
            let (row, value) = used_row(&self.stack, self.used[seg + t], 1.0);
            let reached = dot(row, &self.active_set.point);
            let decided = &mut self.active_set.decided_rows[r];
            judge(
                pull(bound, reached - value),
                tolerance * (1.0 + value.abs()),
                Constraint::Row(r, bound),
                decided,
                worst,
            );
        }
    }

    /// `−∇_j` at `x` into `residual`: level j's used rows, or for `j = levels` the gradient level
    /// `g − x`.
    fn load_negative_gradient(&mut self, j: usize) {
        let levels = self.stack.level_count();
        let ws = &mut self.active_set;
        if j == levels {
            let g = self.stack.gradient();
            for i in 0..ws.point.len() {
                ws.residual[i] = self.scales[levels] * g[i] - ws.point[i];
            }
            return;
        }
        ws.residual.fill(0.0);
        let seg = self.seg_start[j];
        for t in 0..self.factors[j].rows {
            let (row, target) = used_row(&self.stack, self.used[seg + t], self.scales[j]);
            let error = dot(row, &ws.point) - target;
            for (r, a) in ws.residual.iter_mut().zip(row) {
                *r -= error * a;
            }
        }
    }

    /// `r`'s coordinates along the range bases of levels `0..j` into `coords`: one pass
    /// through their reflectors per level judged, instead of one per level above it.
    fn residual_coordinates(&mut self, j: usize) {
        if j == 0 {
            return;
        }
        let ws = &self.active_set;
        for (c, &i) in self.coords.iter_mut().zip(&self.free) {
            *c = ws.residual[i];
        }
        let (n, factors) = (self.stack.dof(), &self.factors[..j]);
        apply_chain(
            &self.qr,
            n,
            &self.tau,
            factors,
            &self.seg_start,
            &mut self.coords,
            n,
        );
    }

    /// Finds level p's multipliers `ν_p` from `U_pᵀ r = R_p Π_pᵀ ν_p` (rows beyond the rank get
    /// 0; `U_pᵀ r` read from `coords`, which hold `r`'s coordinates along the range bases of
    /// levels `0..=p`) and subtracts `J_pᵀ ν_p` from `r`, and its coordinates along the levels
    /// above p (the rows' stored projections) from `coords`.
    fn back_substitute(&mut self, p: usize) {
        let n = self.stack.dof();
        let f = self.factors[p];
        let seg = self.seg_start[p];
        let above: usize = self.factors[..p].iter().map(|f| f.rank).sum();
        let ws = &mut self.active_set;
        let mu = &mut ws.mu[..f.rank];
        mu.copy_from_slice(&self.coords[above..above + f.rank]);
        solve_upper(&self.qr[n * seg..], f.dim, f.rank, mu);
        let nu = &mut ws.multipliers[seg..seg + f.rows];
        nu.fill(0.0);
        for (c, &m) in mu.iter().enumerate() {
            nu[self.perm[seg + c]] = m;
        }
        for t in 0..f.rows {
            let weight = ws.multipliers[seg + t];
            if weight != 0.0 {
                let (row, _) = used_row(&self.stack, self.used[seg + t], 1.0);
                for (r, a) in ws.residual.iter_mut().zip(row) {
                    *r -= weight * a;
                }
                let projection = &self.projections[n * (seg + t)..n * (seg + t) + above];
                for (c, a) in self.coords[..above].iter_mut().zip(projection) {
                    *c -= weight * a;
                }
            }
        }
    }

    /// Judges, at level j, the active rows of the levels above and the clamped joints by their
    /// multipliers.
    fn judge_multipliers(&mut self, j: usize, tolerance: f64, worst: &mut Worst) {
        let ws = &mut self.active_set;
        for p in 0..j {
            let seg = self.seg_start[p];
            for t in 0..self.factors[p].rows {
                let UsedRow::Inequality(r, bound) = self.used[seg + t] else {
                    continue;
                };
                if ws.decided_rows[r] {
                    continue;
                }
                let wanted = pull(bound, ws.multipliers[seg + t]);
                let c = Constraint::Row(r, bound);
                judge(wanted, tolerance, c, &mut ws.decided_rows[r], worst);
            }
        }
        for i in 0..self.stack.dof() {
            // A zero-width interval pins the joint whatever the levels want.
            let held = held_bound(self.clamped[i], self.fixed_velocity[i], self.step_hi[i]);
            let Some(bound) = held else { continue };
            if ws.decided_joints[i] || self.step_lo[i] >= self.step_hi[i] {
                continue;
            }
            let wanted = pull(bound, ws.residual[i]);
            let c = Constraint::Joint(i, bound);
            judge(wanted, tolerance, c, &mut ws.decided_joints[i], worst);
        }
    }
}
