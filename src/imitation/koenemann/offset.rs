//! The CoM offset between the feet (Koenemann et al. §V.A, eq. 6) and its speed limit.
//!
//! `o = (p_CoM − p_L) · (p_R − p_L) / ‖p_R − p_L‖²`: 0 with the CoM over the left foot's
//! centre, 1 over the right's, the projection of the CoM on the line between the feet. Its
//! speed follows a negative quadratic of `o`, largest at 0.5 and small at 0 and 1, so the CoM
//! leaves and reaches a foot gently:
//! `v(o) = v_max · (b + (1 − b) · 4 o (1 − o))`, `b` the fraction left at the borders.
//!
//! Beyond the paper, the offset's rate also changes by at most `a` per second and slows so it
//! can stop at its target (`|ȯ| ≤ √(2 a |o' − o|)`): the profile alone starts a shift at full
//! speed in one frame, an acceleration of the CoM that on the physics model unloads and lifts
//! the other foot (the judge's CoM-in-contact check failed on CMU 09_12 without it).

use nalgebra::Vector3;

use crate::robots::MotionTuning;

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
    /// Largest change of the offset's rate (1/s²). Default 6: from rest to 1.5 /s in 0.25 s,
    /// about 0.6 m/s² of the CoM on the NAO's 10 cm stance. Infinite: the paper's profile alone.
    pub acceleration: f64,
}

impl Default for OffsetSpeed {
    /// The NAO's ([`crate::robots::nao::TUNING`]).
    fn default() -> Self {
        OffsetSpeed {
            max: 1.5,
            border: 0.1,
            acceleration: 6.0,
        }
    }
}

impl OffsetSpeed {
    /// The default border with a robot's rate and acceleration (its
    /// [`MotionTuning::offset_rate`] and [`MotionTuning::offset_acceleration`]).
    pub fn of_robot(tuning: &MotionTuning) -> Self {
        OffsetSpeed {
            max: tuning.offset_rate,
            acceleration: tuning.offset_acceleration,
            ..Self::default()
        }
    }

    /// The largest speed at offset `o` (clamped to [0, 1]), 1/s.
    pub fn at(&self, o: f64) -> f64 {
        let o = o.clamp(0.0, 1.0);
        self.max * (self.border + (1.0 - self.border) * 4.0 * o * (1.0 - o))
    }

    /// The offset `current`, moving at `rate` (1/s), after `dt` seconds toward `target`: the
    /// rate heads for the largest speed [`OffsetSpeed::at`] allows that can still stop at the
    /// target, changing by at most `acceleration · dt`; the offset never passes the target
    /// (it stops there). Returns the new offset and rate.
    pub fn step(&self, current: f64, rate: f64, target: f64, dt: f64) -> (f64, f64) {
        let gap = target - current;
        if gap == 0.0 {
            return (target, 0.0);
        }
        let limit = self
            .at(current)
            .min((2.0 * self.acceleration * gap.abs()).sqrt());
        let change = self.acceleration * dt;
        let rate = rate + (limit.copysign(gap) - rate).clamp(-change, change);
        let next = current + rate * dt;
        if (target - next) * gap <= 0.0 {
            (target, 0.0)
        } else {
            (next, rate)
        }
    }

    /// The first field that is not finite and > 0 (`border` also ≤ 1), with its value.
    pub fn invalid_field(&self) -> Option<(&'static str, f64)> {
        if !(self.max.is_finite() && self.max > 0.0) {
            return Some(("offset_speed.max", self.max));
        }
        if !(self.border > 0.0 && self.border <= 1.0) {
            return Some(("offset_speed.border", self.border));
        }
        (self.acceleration.is_nan() || self.acceleration <= 0.0)
            .then_some(("offset_speed.acceleration", self.acceleration))
    }
}
