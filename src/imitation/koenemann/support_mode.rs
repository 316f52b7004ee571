//! The robot's support mode (Koenemann et al. §V.B, Fig. 4).
//!
//! Double support changes to single support only when the human is in single support on that
//! foot **and** the robot's offset has reached that foot (0 for the left, 1 for the right,
//! within a tolerance); single support returns to double support as soon as the human is not
//! on that foot alone. The target of the offset is the human's own offset in double support,
//! and the support foot's end (0 or 1) in single support.

use crate::imitation::reference::support::HumanSupport;

/// The robot's support mode.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SupportMode {
    /// Both feet on the ground.
    Double,
    /// On the left foot.
    Left,
    /// On the right foot.
    Right,
}

impl SupportMode {
    /// The mode after `self` given the human's support and the robot's offset `offset`
    /// (Fig. 4). A human in the air keeps the robot in its mode.
    pub fn next(self, human: HumanSupport, offset: f64, tolerance: f64) -> SupportMode {
        use {HumanSupport as H, SupportMode as R};
        match (self, human) {
            (_, H::Airborne) => self,
            (R::Double, H::Left) if offset <= tolerance => R::Left,
            (R::Double, H::Right) if offset >= 1.0 - tolerance => R::Right,
            (R::Left, H::Left) => R::Left,
            (R::Right, H::Right) => R::Right,
            _ => R::Double,
        }
    }
}

/// The offset the robot moves toward: the human's in double support (clamped to [0, 1]), the
/// support foot's end in single support, unchanged when the human is in the air.
pub fn target_offset(human: HumanSupport, human_offset: f64, current: f64) -> f64 {
    match human {
        HumanSupport::Double => human_offset.clamp(0.0, 1.0),
        HumanSupport::Left => 0.0,
        HumanSupport::Right => 1.0,
        HumanSupport::Airborne => current,
    }
}
