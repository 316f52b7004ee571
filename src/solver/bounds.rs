//! Joint limits: position limits (hard) and optional velocity limits, and the per-step velocity
//! interval they allow.
//!
//! For a step of duration `Δt` from `q`, joint `i` may move at a velocity in
//! `[max((q_min,i − q_i)/Δt, −v_max,i), min((q_max,i − q_i)/Δt, v_max,i)]`, rounded so that
//! `q_i + q̇_i Δt` lands inside `[q_min,i, q_max,i]` in floating point too. Position limits are
//! hard: if `q_i` starts outside its range by more than one step at `v_max,i` can recover, the
//! interval collapses onto the velocity that lands on the nearest limit (position wins over
//! velocity). One case cannot be exact: a zero-width range (`q_min,i = q_max,i`) with `q_i` outside
//! it, where no floating-point velocity may land exactly on the single admissible value; there the
//! landing is within a few ulps, and [`JointBounds::clamp_position`] (used by the position-level
//! driver after integrating) removes the rest.

use super::SolverError;
use super::check::check_len;

/// Position limits (rad or m) and velocity limits (rad/s or m/s) per joint.
#[derive(Debug, Clone, PartialEq)]
pub struct JointBounds {
    lower: Vec<f64>,
    upper: Vec<f64>,
    velocity: Vec<f64>,
}

impl JointBounds {
    /// Position limits only (velocity unbounded). `lower[i] ≤ upper[i]`; infinite limits are allowed
    /// (`f64::NEG_INFINITY`/`f64::INFINITY`), NaN is not.
    pub fn new(lower: &[f64], upper: &[f64]) -> Result<Self, SolverError> {
        Self::with_velocity(lower, upper, &vec![f64::INFINITY; lower.len()])
    }

    /// Position and velocity limits. `velocity[i] ≥ 0` is the largest `|q̇_i|`.
    pub fn with_velocity(
        lower: &[f64],
        upper: &[f64],
        velocity: &[f64],
    ) -> Result<Self, SolverError> {
        check_len("upper limits", lower.len(), upper.len())?;
        check_len("velocity limits", lower.len(), velocity.len())?;
        for (joint, ((&lo, &hi), &v)) in lower.iter().zip(upper).zip(velocity).enumerate() {
            if lo.is_nan()
                || hi.is_nan()
                || lo > hi
                || lo == f64::INFINITY
                || hi == f64::NEG_INFINITY
            {
                return Err(SolverError::InvertedLimits {
                    joint,
                    lower: lo,
                    upper: hi,
                });
            }
            if v.is_nan() || v < 0.0 {
                return Err(SolverError::InvalidParameter {
                    name: "velocity limit",
                    value: v,
                    reason: "must be >= 0 (infinity for none)",
                });
            }
        }
        Ok(Self {
            lower: lower.to_vec(),
            upper: upper.to_vec(),
            velocity: velocity.to_vec(),
        })
    }

    /// No limits at all on `dof` joints.
    pub fn unbounded(dof: usize) -> Self {
        Self {
            lower: vec![f64::NEG_INFINITY; dof],
            upper: vec![f64::INFINITY; dof],
            velocity: vec![f64::INFINITY; dof],
        }
    }

    /// Number of joints.
    pub fn dof(&self) -> usize {
        self.lower.len()
    }

    /// Lower position limits.
    pub fn lower(&self) -> &[f64] {
        &self.lower
    }

    /// Upper position limits.
    pub fn upper(&self) -> &[f64] {
        &self.upper
    }

    /// Velocity limits (`|q̇_i| ≤ velocity[i]`).
    pub fn velocity(&self) -> &[f64] {
        &self.velocity
    }

    /// Scales every velocity limit by `fraction` (e.g. 0.1 to run at 10 % of the rated speed).
    pub fn scale_velocity(&mut self, fraction: f64) -> Result<(), SolverError> {
        if !(fraction.is_finite() && fraction >= 0.0) {
            return Err(SolverError::InvalidParameter {
                name: "velocity fraction",
                value: fraction,
                reason: "must be finite and >= 0",
            });
        }
        self.velocity.iter_mut().for_each(|v| *v *= fraction);
        Ok(())
    }

    /// Copies `other` (same number of joints) into `self`, with every velocity limit capped at
    /// `cap`. Allocation-free.
    pub(crate) fn copy_with_velocity_cap(&mut self, other: &JointBounds, cap: f64) {
        self.lower.copy_from_slice(&other.lower);
        self.upper.copy_from_slice(&other.upper);
        for (v, &o) in self.velocity.iter_mut().zip(&other.velocity) {
            *v = o.min(cap);
        }
    }

    /// Copies the limits of the joints `columns` of `other` into `self` (joint `c` of `self` is
    /// joint `columns[c]` of `other`; `self` has `columns.len()` joints): the bounds of a
    /// problem over a subset of the joints. Allocation-free.
    pub(crate) fn copy_columns(&mut self, other: &JointBounds, columns: &[usize]) {
        for (c, &k) in columns.iter().enumerate() {
            self.lower[c] = other.lower[k];
            self.upper[c] = other.upper[k];
            self.velocity[c] = other.velocity[k];
        }
    }

    /// Copies the position limits of `other` (same number of joints) into `self`, narrowed to
    /// what its velocity limits reach from `q` in `dt` seconds: `[max(q_min, q − v Δt),
    /// min(q_max, q + v Δt)]`, or the nearest position limit when `q` is outside its range by
    /// more than that; the velocity limits are copied too. For a position-level solve that must
    /// end within one frame's motion. Allocation-free.
    pub(crate) fn copy_within_reach(&mut self, other: &JointBounds, q: &[f64], dt: f64) {
        for i in 0..self.lower.len() {
            let reach = other.velocity[i] * dt;
            let (lo, hi) = (other.lower[i], other.upper[i]);
            let (from, to) = (lo.max(q[i] - reach), hi.min(q[i] + reach));
            (self.lower[i], self.upper[i]) = if from <= to {
                (from, to)
            } else {
                let nearest = q[i].clamp(lo, hi);
                (nearest, nearest)
            };
            self.velocity[i] = other.velocity[i];
        }
    }

    /// Clamps `q` into the position limits in place.
    pub fn clamp_position(&self, q: &mut [f64]) {
        for ((qi, &lo), &hi) in q.iter_mut().zip(&self.lower).zip(&self.upper) {
            *qi = qi.clamp(lo, hi);
        }
    }

    /// Writes the velocity interval `[lo_i, hi_i]` that one step of `dt` from `q` allows.
    pub(crate) fn step_interval(&self, q: &[f64], dt: f64, lo: &mut [f64], hi: &mut [f64]) {
        for i in 0..q.len() {
            let (qi, v) = (q[i], self.velocity[i]);
            let from_lower = landing_velocity(qi, self.lower[i], dt, Side::Lower);
            let from_upper = landing_velocity(qi, self.upper[i], dt, Side::Upper);
            let (mut l, mut h) = (from_lower.max(-v), from_upper.min(v));
            if l > h {
                // Outside the range and too far to come back at the velocity limit: land on the
                // nearest position limit.
                let guess = if qi > self.upper[i] {
                    from_upper
                } else {
                    from_lower
                };
                let land = inside_landing(qi, guess, dt, self.lower[i], self.upper[i]);
                (l, h) = (land, land);
            }
            lo[i] = l;
            hi[i] = h;
        }
    }
}

#[derive(Clone, Copy, PartialEq)]
enum Side {
    Lower,
    Upper,
}

/// The velocity that takes `q` to `limit` in `dt`, rounded toward the inside of the range so that
/// `q + v·dt` does not cross `limit` in floating point. Infinite limits give infinite velocities.
fn landing_velocity(q: f64, limit: f64, dt: f64, side: Side) -> f64 {
    if limit.is_infinite() {
        return limit;
    }
    let crosses = |v: f64| {
        let landed = q + v * dt;
        match side {
            Side::Upper => landed > limit,
            Side::Lower => landed < limit,
        }
    };
    // `limit - q` and the division each round: aim a little further inside, doubling the margin
    // until the landing point is on the right side.
    let ulp = (limit.next_up() - limit).max(f64::MIN_POSITIVE);
    let mut margin = 0.0;
    loop {
        let target = match side {
            Side::Upper => limit - margin,
            Side::Lower => limit + margin,
        };
        let v = (target - q) / dt;
        if !crosses(v) || margin > 1e6 * ulp {
            return v;
        }
        margin = (2.0 * margin).max(ulp);
    }
}

/// A velocity near `guess` that lands `q` inside `[lower, upper]` after `dt` in floating point
/// (needed when the range has zero width and `q` is outside it, where the rounded landing
/// velocities of the two limits straddle the only admissible point).
fn inside_landing(q: f64, guess: f64, dt: f64, lower: f64, upper: f64) -> f64 {
    let inside = |v: f64| (lower..=upper).contains(&(q + v * dt));
    let (mut up, mut down) = (guess, guess);
    for _ in 0..64 {
        if inside(up) {
            return up;
        }
        if inside(down) {
            return down;
        }
        (up, down) = (up.next_up(), down.next_down());
    }
    guess
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inverted_limits_name_the_joint() {
        let err = JointBounds::new(&[0.0, 1.0], &[1.0, 0.0]).unwrap_err();
        assert_eq!(
            err,
            SolverError::InvertedLimits {
                joint: 1,
                lower: 1.0,
                upper: 0.0
            }
        );
    }

    #[test]
    fn step_interval_combines_position_and_velocity_limits() {
        let b = JointBounds::with_velocity(&[-1.0, -1.0], &[1.0, 1.0], &[0.5, 10.0]).unwrap();
        let (mut lo, mut hi) = ([0.0; 2], [0.0; 2]);
        b.step_interval(&[0.9, 0.9], 0.1, &mut lo, &mut hi);
        // Joint 0: velocity-limited both ways. Joint 1: (1 − 0.9)/0.1 = 1 up, 10 down (velocity).
        assert_eq!((lo[0], hi[0]), (-0.5, 0.5));
        assert!((hi[1] - 1.0).abs() < 1e-12 && lo[1] == -10.0);
    }

    #[test]
    fn landing_is_inside_in_floating_point() {
        let cases = [
            (0.1, 0.3, 0.01, Side::Upper),
            (-2.08567, 2.08567, 0.007, Side::Upper),
            (1.0, -0.7, 3.0, Side::Lower),
            (1.3, 0.9, 0.01, Side::Upper),
            (-1.3, -0.9, 0.01, Side::Lower),
        ];
        for (q, limit, dt, side) in cases {
            let v = landing_velocity(q, limit, dt, side);
            let landed = q + v * dt;
            match side {
                Side::Upper => assert!(landed <= limit),
                Side::Lower => assert!(landed >= limit),
            }
            assert!((landed - limit).abs() < 1e-12);
        }
    }

    #[test]
    fn start_outside_range_lands_on_limit_despite_velocity_limit() {
        let b = JointBounds::with_velocity(&[-1.0], &[1.0], &[0.1]).unwrap();
        let (mut lo, mut hi) = ([0.0], [0.0]);
        b.step_interval(&[2.0], 0.1, &mut lo, &mut hi);
        assert_eq!(lo, hi);
        assert!(2.0 + hi[0] * 0.1 <= 1.0);
    }
}
