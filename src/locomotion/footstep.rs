//! Footsteps: where a sole is put on the floor, and how long a step takes.

use nalgebra::{Rotation2, Vector2};

use super::LocomotionError;
use crate::human::Side;

/// A sole on the floor, in the world frame: the sole frame's origin `xy` (m) and its yaw about
/// the vertical (rad, 0 = facing world x).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GroundPose {
    /// Position of the sole frame's origin (m, world x y).
    pub xy: Vector2<f64>,
    /// Heading (rad).
    pub yaw: f64,
}

impl GroundPose {
    /// A pose at `(x, y)` (m) with heading `yaw` (rad).
    pub fn new(x: f64, y: f64, yaw: f64) -> Self {
        Self {
            xy: Vector2::new(x, y),
            yaw,
        }
    }

    /// A point given in this sole's frame (m), in the world frame.
    pub fn to_world(&self, local: [f64; 2]) -> Vector2<f64> {
        self.xy + Rotation2::new(self.yaw) * Vector2::new(local[0], local[1])
    }

    /// A world point (m) in this sole's frame.
    pub fn to_local(&self, world: Vector2<f64>) -> Vector2<f64> {
        Rotation2::new(-self.yaw) * (world - self.xy)
    }

    /// `other` seen from this sole: its offset (m, this sole's frame) and relative yaw (rad, in
    /// [−π, π)).
    pub fn relative(&self, other: &GroundPose) -> GroundPose {
        GroundPose {
            xy: self.to_local(other.xy),
            yaw: wrap_angle(other.yaw - self.yaw),
        }
    }

    /// `relative` (in this sole's frame) in the world frame: the inverse of
    /// [`GroundPose::relative`].
    pub fn compose(&self, relative: &GroundPose) -> GroundPose {
        GroundPose {
            xy: self.to_world([relative.xy.x, relative.xy.y]),
            yaw: wrap_angle(self.yaw + relative.yaw),
        }
    }

    pub(super) fn is_finite(&self) -> bool {
        self.xy.iter().all(|v| v.is_finite()) && self.yaw.is_finite()
    }
}

/// The angle `a` (rad) wrapped into [−π, π).
pub fn wrap_angle(a: f64) -> f64 {
    use std::f64::consts::{PI, TAU};
    (a + PI).rem_euclid(TAU) - PI
}

/// The heading halfway between headings `a` and `b` (rad), on the short arc.
pub fn mean_heading(a: f64, b: f64) -> f64 {
    b + wrap_angle(a - b) / 2.0
}

/// How long a step takes (s): the double support in which the weight moves to the stance
/// foot, then the single support in which the other foot swings to its new place.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepTiming {
    /// Both feet on the floor, the ZMP moving onto the stance sole (s, > 0).
    pub double_support: f64,
    /// The stance foot alone on the floor while the swing foot travels (s, > 0).
    pub single_support: f64,
}

impl StepTiming {
    /// The step's whole duration (s).
    pub fn duration(&self) -> f64 {
        self.double_support + self.single_support
    }

    pub(super) fn validate(&self) -> Result<(), LocomotionError> {
        super::preview::positive("double_support", self.double_support)?;
        super::preview::positive("single_support", self.single_support)
    }
}

/// One step: the foot on `side` swings to `target` while the other foot stands.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Footstep {
    /// The foot that moves.
    pub side: Side,
    /// Where its sole lands (world).
    pub target: GroundPose,
    /// How long the step takes.
    pub timing: StepTiming,
}
