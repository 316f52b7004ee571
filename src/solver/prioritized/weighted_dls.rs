//! [`Method::WeightedDls`](super::Method::WeightedDls): damped least squares with weighted
//! least-norm joint-limit avoidance (Chan & Dubey 1995, the IK of Koenemann et al. 2014).
//!
//! # Method
//!
//! Every level's rows are stacked into one task `J q̇ = ẋ` (the levels lose their priority). With
//! the diagonal weight `W` and the damping `λ`,
//!
//! ```text
//! q̇ = g + W⁻¹ Jᵀ (J W⁻¹ Jᵀ + λ² I)⁻¹ (ẋ − J g),      g = Σ_k κ_k ∇f_k(q)
//! ```
//!
//! the minimizer of `‖J q̇ − ẋ‖² + λ² ‖q̇ − g‖²_W`: the gradient term is followed where the task
//! leaves room. Damping bounds the step near singularities: with `W = I`,
//! `‖q̇ − g‖ ≤ ‖ẋ − J g‖ / (2λ)` whatever the conditioning of `J`.
//!
//! Chan & Dubey's weight grows toward a joint's limits: with the criterion
//! `H(q) = Σ_i (q_max,i − q_min,i)² / (4 (q_max,i − q_i)(q_i − q_min,i))`,
//! `w_i = 1 + |∂H/∂q_i|` while `|∂H/∂q_i|` grows (the joint moves toward a limit), else `w_i = 1`
//! (moving away is not penalized). `w_i → ∞` at a limit, where the joint stops. Unbounded joints
//! have `w_i = 1`. The clamping loop and [`Settings::scale_to_fit`](super::Settings::scale_to_fit)
//! work as for the prioritized method (the step is linear in `ẋ`, `g` and the clamped
//! velocities), so a limit is never violated.
//!
//! Cost: one `m × m` Cholesky factorization per pass, `m` the stack's total rows.

use super::solver::Solver;
use crate::solver::JointBounds;

/// Chan & Dubey's `∂H/∂q_i` for a joint at `q` in `[lower, upper]` (1/rad): 0 at the middle of
/// the range, ±∞ at the limits, 0 for an unbounded or zero-width range.
pub fn limit_criterion_gradient(q: f64, lower: f64, upper: f64) -> f64 {
    if !(lower.is_finite() && upper.is_finite() && upper > lower) {
        return 0.0;
    }
    let range = upper - lower;
    let (to_upper, to_lower) = (upper - q, q - lower);
    range * range * (2.0 * q - upper - lower) / (4.0 * to_upper * to_upper * to_lower * to_lower)
}

/// Chan & Dubey's weight `1 + |∂H/∂q|` of a joint moving toward a limit (∞ at the limit).
pub fn limit_weight(q: f64, lower: f64, upper: f64) -> f64 {
    let g = limit_criterion_gradient(q, lower, upper).abs();
    if g.is_nan() { f64::INFINITY } else { 1.0 + g }
}

impl Solver {
    /// Sets the inverse weights `W⁻¹` for configuration `q` and remembers `|∂H/∂q|` for the
    /// next solve.
    pub(super) fn update_limit_weights(&mut self, q: &[f64], bounds: &JointBounds) {
        let (lower, upper) = (bounds.lower(), bounds.upper());
        for i in 0..q.len() {
            let g = limit_criterion_gradient(q[i], lower[i], upper[i]).abs();
            let g = if g.is_nan() { f64::INFINITY } else { g };
            // Toward a limit (or the first solve): weighted; away from it: free.
            self.inverse_weight[i] = if g >= self.previous_criterion[i] {
                1.0 / (1.0 + g)
            } else {
                1.0
            };
            self.previous_criterion[i] = g;
        }
    }

    /// One damped least-squares pass over the joints not clamped; writes `self.velocity`.
    pub(super) fn weighted_dls_pass(&mut self, damping: f64) {
        let n = self.stack.dof();
        let m = self.stack.total_rows();
        let levels = self.stack.level_count();
        self.free.clear();
        self.free.extend((0..n).filter(|&i| !self.clamped[i]));
        let gradient_scale = self.scales[levels];
        let gradient = self.stack.gradient();
        // g on the free joints, the clamped ones at their fixed velocity.
        self.velocity.copy_from_slice(&self.fixed_velocity);
        for &i in &self.free {
            self.velocity[i] = gradient_scale * gradient[i];
        }
        // Right-hand side ẋ − J (g + q̇_clamped), per level scaled.
        let mut level = 0;
        for r in 0..m {
            while r >= self.stack.level_start(level + 1) {
                level += 1;
            }
            let row = self.stack.row(r);
            let moved: f64 = row.iter().zip(&self.velocity).map(|(a, v)| a * v).sum();
            self.rhs[r] = self.scales[level] * self.stack.stacked_target()[r] - moved;
        }
        // Gram matrix J W⁻¹ Jᵀ + λ² I (lower triangle, row-major m × m).
        let gram = &mut self.gram[..m * m];
        for r in 0..m {
            let row_r = self.stack.row(r);
            for s in 0..=r {
                let row_s = self.stack.row(s);
                let mut sum: f64 = self
                    .free
                    .iter()
                    .map(|&i| row_r[i] * self.inverse_weight[i] * row_s[i])
                    .sum();
                if r == s {
                    sum += damping * damping;
                }
                gram[r * m + s] = sum;
            }
        }
        cholesky_solve(gram, m, &mut self.rhs[..m]);
        for &i in &self.free {
            let mut sum = 0.0;
            for r in 0..m {
                sum += self.stack.row(r)[i] * self.rhs[r];
            }
            self.velocity[i] += self.inverse_weight[i] * sum;
        }
        for j in 0..levels {
            let rows = self.stack.level_start(j + 1) - self.stack.level_start(j);
            let level = &mut self.report.levels[j];
            level.rows = rows;
            level.rank = rows;
            level.damping = damping;
        }
    }
}

/// Solves `A x = b` in place (`b ← x`) for the symmetric positive definite `m × m` matrix whose
/// lower triangle is in `a` (row-major), which is overwritten by its Cholesky factor. A pivot
/// that is not positive (impossible with damping > 0 but for rounding) is taken as its absolute
/// value floored at the smallest normal number, so the result stays finite.
fn cholesky_solve(a: &mut [f64], m: usize, b: &mut [f64]) {
    for j in 0..m {
        let mut d = a[j * m + j];
        for k in 0..j {
            d -= a[j * m + k] * a[j * m + k];
        }
        let d = d.abs().max(f64::MIN_POSITIVE).sqrt();
        a[j * m + j] = d;
        for i in j + 1..m {
            let mut s = a[i * m + j];
            for k in 0..j {
                s -= a[i * m + k] * a[j * m + k];
            }
            a[i * m + j] = s / d;
        }
    }
    for i in 0..m {
        let mut s = b[i];
        for k in 0..i {
            s -= a[i * m + k] * b[k];
        }
        b[i] = s / a[i * m + i];
    }
    for i in (0..m).rev() {
        let mut s = b[i];
        for k in i + 1..m {
            s -= a[k * m + i] * b[k];
        }
        b[i] = s / a[i * m + i];
    }
}
