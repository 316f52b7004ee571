//! The CoM offset between the feet (Koenemann et al. §V.A, eq. 6) and its speed limit.
//!
//! `o = (p_CoM − p_L) · (p_R − p_L) / ‖p_R − p_L‖²`: 0 with the CoM over the left foot's
//! centre, 1 over the right's, the projection of the CoM on the line between the feet. Its
//! speed follows a negative quadratic of `o`, largest at 0.5 and small at 0 and 1, so the CoM
//! leaves and reaches a foot gently:
//! `v(o) = v_max · (b + (1 − b) · 4 o (1 − o))`, `b` the fraction left at the borders.

use nalgebra::Vector3;

/// Eq. 6: the offset of `com` between the foot centres `left` and `right` (any common frame);
/// `None` when the feet coincide.
pub fn offset(com: &Vector3<f64>, left: &Vector3<f64>, right: &Vector3<f64>) -> Option<f64> {
    let line = right - left;
    let length2 = line.norm_squared();
    (length2 > 1e-12).then(|| (com - left).dot(&line) / length2)
}

/// The speed limit of the offset.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OffsetSpeed {
    /// Largest speed, at o = 0.5 (1/s). Default 1.5: a shift from the middle to a foot in
    /// about 0.6 s.
    pub max: f64,
    /// Fraction of `max` left at o = 0 and o = 1. Default 0.1.
    pub border: f64,
}

impl Default for OffsetSpeed {
    fn default() -> Self {
        OffsetSpeed {
            max: 1.5,
            border: 0.1,
        }
    }
}

impl OffsetSpeed {
    /// The largest speed at offset `o` (clamped to [0, 1]), 1/s.
    pub fn at(&self, o: f64) -> f64 {
        let o = o.clamp(0.0, 1.0);
        self.max * (self.border + (1.0 - self.border) * 4.0 * o * (1.0 - o))
    }

    /// `current` moved toward `target` for `dt` seconds at most at the speed [`OffsetSpeed::at`]
    /// allows, without passing it.
    pub fn step(&self, current: f64, target: f64, dt: f64) -> f64 {
        let reach = self.at(current) * dt;
        current + (target - current).clamp(-reach, reach)
    }

    /// The first field that is not finite and > 0 (`border` also ≤ 1), with its value.
    pub fn invalid_field(&self) -> Option<(&'static str, f64)> {
        if !(self.max.is_finite() && self.max > 0.0) {
            return Some(("offset_speed.max", self.max));
        }
        (!(self.border > 0.0 && self.border <= 1.0)).then_some(("offset_speed.border", self.border))
    }
}
