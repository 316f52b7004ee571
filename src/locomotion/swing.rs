//! The swing foot's path: lift, carry, land flat with zero speed.
//!
//! Over the single support, with `τ ∈ [0, 1]` its phase, the sole's height is
//! `h(τ) = H · 64 τ³ (1 − τ)³` (peak `H` at mid-swing; height, vertical speed and acceleration
//! zero at lift-off and touchdown), and its horizontal position and yaw move along the quintic
//! `s(σ) = 10σ³ − 15σ⁴ + 6σ⁵` of `σ = (τ − a)/(1 − 2a)` clamped to [0, 1], `a` the lift share:
//! the sole leaves the floor vertically, is carried while it is up, and comes down vertically
//! and flat. Every derivative up to the acceleration is zero at both ends, so a foot lands with
//! zero speed.

use super::footstep::{GroundPose, wrap_angle};

/// Where the swing sole is at one instant (world): origin position (m) and yaw (rad); the sole
/// is kept level.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SolePose {
    /// Position of the sole frame's origin (m, world x y z; z = 0 on the floor).
    pub position: [f64; 3],
    /// Heading (rad).
    pub yaw: f64,
}

impl SolePose {
    /// A sole standing on the floor at `pose`.
    pub fn on_floor(pose: &GroundPose) -> Self {
        Self {
            position: [pose.xy.x, pose.xy.y, 0.0],
            yaw: pose.yaw,
        }
    }
}

/// The shape of every swing: its peak height and the share of the swing spent rising before the
/// foot moves sideways (and, mirrored, descending after).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SwingProfile {
    /// Peak height of the sole above the floor (m).
    pub height: f64,
    /// Share of the single support at each end in which the foot moves only vertically
    /// (in [0, 0.5)).
    pub lift_share: f64,
}

impl SwingProfile {
    /// The swing sole at phase `tau` (clamped to [0, 1]) of a swing from `from` to `to`.
    pub fn at(&self, from: &GroundPose, to: &GroundPose, tau: f64) -> SolePose {
        let tau = tau.clamp(0.0, 1.0);
        let sigma = ((tau - self.lift_share) / (1.0 - 2.0 * self.lift_share)).clamp(0.0, 1.0);
        let s = quintic(sigma);
        let xy = from.xy + (to.xy - from.xy) * s;
        let yaw = from.yaw + wrap_angle(to.yaw - from.yaw) * s;
        let bump = tau * (1.0 - tau);
        SolePose {
            position: [xy.x, xy.y, self.height * 64.0 * bump * bump * bump],
            yaw: wrap_angle(yaw),
        }
    }
}

/// `10σ³ − 15σ⁴ + 6σ⁵`: from 0 to 1 with zero first and second derivatives at both ends.
fn quintic(sigma: f64) -> f64 {
    sigma * sigma * sigma * (10.0 + sigma * (-15.0 + 6.0 * sigma))
}
