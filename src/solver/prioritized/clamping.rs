//! [`Solver::solve`] and [`Solver::solve_unbounded`]: the clamping loop around the passes
//! (Baerlocher & Boulic 2004, one joint at a time), and the scales that fit a step inside the
//! joint intervals ([`Settings::scale_to_fit`](crate::solver::Settings::scale_to_fit)).

use super::settings::Method;
use super::solver::Solver;
use crate::solver::SolverError;
use crate::solver::bounds::JointBounds;
use crate::solver::check::{check_finite_slice, check_len};
use crate::solver::report::Solution;

/// What [`Solver::fit_scales`] leaves for the clamping loop.
enum Fitted {
    /// The whole step fits: `velocity` is the step.
    Step,
    /// `velocity` holds the scaled parts; the factorization is of the joints still free.
    Factored,
    /// The clamping ran out of joints to clamp: the next pass must factor again.
    Refactor,
}

impl Solver {
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
}
