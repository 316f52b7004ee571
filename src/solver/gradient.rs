//! Optimization (gradient) tasks: `q̇ = κ ∇f(q)` (eq. 3), summed and projected into the null space
//! of every equality level (eq. 6).
//!
//! Built in are the paper's two criteria: joint-limit avoidance (eq. 7)
//! `f_ℓ = Σ ((q_i − q̄_i)/(q_max,i − q_min,i))²` and joint-space tracking (eq. 8)
//! `f_h = Σ w_i (q_i − q^h_i)²`. Any other criterion implements [`GradientFunction`].

use super::SolverError;
use super::bounds::JointBounds;
use super::check::{check_finite_slice, check_len};

/// A differentiable scalar criterion `f(q)` whose gradient the solver can follow.
pub trait GradientFunction {
    /// Adds `scale · ∇f(q)` to `out` (both of length `n`). Must not allocate and must leave `out`
    /// finite for finite input.
    fn add_scaled_gradient(
        &self,
        q: &[f64],
        scale: f64,
        out: &mut [f64],
    ) -> Result<(), SolverError>;
}

/// `f(q) = Σ w_i (q_i − c_i)²`: the shape of both built-in criteria.
#[derive(Debug, Clone, PartialEq)]
struct WeightedQuadratic {
    center: Vec<f64>,
    weight: Vec<f64>,
}

impl GradientFunction for WeightedQuadratic {
    fn add_scaled_gradient(
        &self,
        q: &[f64],
        scale: f64,
        out: &mut [f64],
    ) -> Result<(), SolverError> {
        check_len("q", self.center.len(), q.len())?;
        check_len("gradient output", self.center.len(), out.len())?;
        check_finite_slice("q", q)?;
        for (((o, &qi), &c), &w) in out.iter_mut().zip(q).zip(&self.center).zip(&self.weight) {
            *o += scale * 2.0 * w * (qi - c);
        }
        Ok(())
    }
}

/// Joint-limit avoidance (eq. 7): pushes each joint toward the middle of its range, with the
/// squared distance normalized by the range. Joints with an unbounded or zero-width range do not
/// contribute.
#[derive(Debug, Clone, PartialEq)]
pub struct JointLimitAvoidance(WeightedQuadratic);

impl JointLimitAvoidance {
    /// The criterion for the position limits in `bounds`.
    pub fn new(bounds: &JointBounds) -> Self {
        let (center, weight) = bounds
            .lower()
            .iter()
            .zip(bounds.upper())
            .map(|(&lo, &hi)| {
                let range = hi - lo;
                if range.is_finite() && range > 0.0 {
                    (0.5 * (lo + hi), 1.0 / (range * range))
                } else {
                    (0.0, 0.0)
                }
            })
            .unzip();
        Self(WeightedQuadratic { center, weight })
    }
}

impl GradientFunction for JointLimitAvoidance {
    fn add_scaled_gradient(
        &self,
        q: &[f64],
        scale: f64,
        out: &mut [f64],
    ) -> Result<(), SolverError> {
        self.0.add_scaled_gradient(q, scale, out)
    }
}

/// Joint-space tracking (eq. 8): `f = Σ w_i (q_i − q^h_i)²`, pulling the joints toward a reference
/// posture (the human's joint angles, in rad). A weight of 0 leaves a joint untracked.
#[derive(Debug, Clone, PartialEq)]
pub struct JointTracking(WeightedQuadratic);

impl JointTracking {
    /// Tracks `reference` with unit weight on every joint.
    pub fn new(reference: &[f64]) -> Result<Self, SolverError> {
        Self::weighted(reference, &vec![1.0; reference.len()])
    }

    /// Tracks `reference` with per-joint weights `weight` (≥ 0).
    pub fn weighted(reference: &[f64], weight: &[f64]) -> Result<Self, SolverError> {
        check_len("joint tracking weights", reference.len(), weight.len())?;
        check_finite_slice("joint tracking reference", reference)?;
        check_finite_slice("joint tracking weights", weight)?;
        if let Some(&w) = weight.iter().find(|w| **w < 0.0) {
            return Err(SolverError::InvalidParameter {
                name: "joint tracking weight",
                value: w,
                reason: "weights must be >= 0",
            });
        }
        Ok(Self(WeightedQuadratic {
            center: reference.to_vec(),
            weight: weight.to_vec(),
        }))
    }

    /// Replaces the reference posture (same length), e.g. with the next frame's human angles.
    pub fn set_reference(&mut self, reference: &[f64]) -> Result<(), SolverError> {
        check_len(
            "joint tracking reference",
            self.0.center.len(),
            reference.len(),
        )?;
        check_finite_slice("joint tracking reference", reference)?;
        self.0.center.copy_from_slice(reference);
        Ok(())
    }

    /// The reference posture (rad).
    pub fn reference(&self) -> &[f64] {
        &self.0.center
    }
}

impl GradientFunction for JointTracking {
    fn add_scaled_gradient(
        &self,
        q: &[f64],
        scale: f64,
        out: &mut [f64],
    ) -> Result<(), SolverError> {
        self.0.add_scaled_gradient(q, scale, out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Central finite difference of `f` at `q` along joint `i`.
    fn fd(f: impl Fn(&[f64]) -> f64, q: &[f64], i: usize) -> f64 {
        let h = 1e-6;
        let (mut qp, mut qm) = (q.to_vec(), q.to_vec());
        qp[i] += h;
        qm[i] -= h;
        (f(&qp) - f(&qm)) / (2.0 * h)
    }

    #[test]
    fn joint_limit_gradient_matches_finite_difference_of_eq7() {
        let bounds = JointBounds::new(&[-1.0, 0.0, -2.0], &[1.0, 0.5, 3.0]).unwrap();
        let f = |q: &[f64]| -> f64 {
            let (lo, hi) = (bounds.lower(), bounds.upper());
            (0..3)
                .map(|i| ((q[i] - 0.5 * (lo[i] + hi[i])) / (hi[i] - lo[i])).powi(2))
                .sum()
        };
        let q = [0.3, 0.1, -1.5];
        let mut g = [0.0; 3];
        JointLimitAvoidance::new(&bounds)
            .add_scaled_gradient(&q, 1.0, &mut g)
            .unwrap();
        for i in 0..3 {
            assert!((g[i] - fd(f, &q, i)).abs() < 1e-8, "joint {i}");
        }
    }

    #[test]
    fn joint_tracking_gradient_matches_finite_difference_of_eq8() {
        let reference = [0.2, -0.4];
        let weight = [1.0, 0.5];
        let f = |q: &[f64]| -> f64 {
            (0..2)
                .map(|i| weight[i] * (q[i] - reference[i]).powi(2))
                .sum()
        };
        let q = [1.0, 1.0];
        let mut g = [0.0; 2];
        JointTracking::weighted(&reference, &weight)
            .unwrap()
            .add_scaled_gradient(&q, 1.0, &mut g)
            .unwrap();
        for i in 0..2 {
            assert!((g[i] - fd(f, &q, i)).abs() < 1e-8, "joint {i}");
        }
    }

    #[test]
    fn negative_tracking_weight_is_rejected() {
        assert!(matches!(
            JointTracking::weighted(&[0.0], &[-1.0]),
            Err(SolverError::InvalidParameter { .. })
        ));
    }
}
