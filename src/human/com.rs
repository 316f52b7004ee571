//! The human's whole-body centre of mass estimated from joint positions: de Leva's (1996)
//! adjustment of Zatsiorsky–Seluyanov's segment parameters (male), each segment's mass as a
//! fraction of the body mass and its centre of mass at a fraction of its length from the
//! proximal joint:
//!
//! | segment | from → to | mass | CoM from proximal |
//! |---|---|---|---|
//! | head and neck | at [`HumanJoint::Head`] | 6.94 % | — |
//! | trunk | MidShoulder → MidHip | 43.46 % | 44.86 % |
//! | upper arm | Shoulder → Elbow | 2.71 % | 57.72 % |
//! | forearm | Elbow → Wrist | 1.62 % | 45.74 % |
//! | hand | Wrist → Hand | 0.61 % | 79.00 % |
//! | thigh | Hip → Knee | 14.16 % | 40.95 % |
//! | shank | Knee → Ankle | 4.33 % | 44.59 % |
//! | foot | Ankle → Toe | 1.37 % | 44.15 % |
//!
//! The fractions sum to 1. A segment with a missing end is left out and the others are
//! renormalized (a hand without its `Hand` point is placed at the wrist); with less than half
//! the body's mass present there is no estimate.

use nalgebra::Vector3;

use super::{HumanFrame, HumanJoint as J};

/// `(proximal, distal, mass fraction, CoM fraction from proximal)` of every segment.
const SEGMENTS: [(J, J, f64, f64); 14] = [
    (J::Head, J::Head, 0.0694, 0.0),
    (J::MidShoulder, J::MidHip, 0.4346, 0.4486),
    (J::LShoulder, J::LElbow, 0.0271, 0.5772),
    (J::RShoulder, J::RElbow, 0.0271, 0.5772),
    (J::LElbow, J::LWrist, 0.0162, 0.4574),
    (J::RElbow, J::RWrist, 0.0162, 0.4574),
    (J::LWrist, J::LHand, 0.0061, 0.79),
    (J::RWrist, J::RHand, 0.0061, 0.79),
    (J::LHip, J::LKnee, 0.1416, 0.4095),
    (J::RHip, J::RKnee, 0.1416, 0.4095),
    (J::LKnee, J::LAnkle, 0.0433, 0.4459),
    (J::RKnee, J::RAnkle, 0.0433, 0.4459),
    (J::LAnkle, J::LToe, 0.0137, 0.4415),
    (J::RAnkle, J::RToe, 0.0137, 0.4415),
];

/// The estimated whole-body centre of mass (m, the frame's coordinates), or `None` when the
/// segments present carry less than half the body mass.
pub fn centre_of_mass(frame: &HumanFrame) -> Option<Vector3<f64>> {
    let (mut moment, mut mass) = (Vector3::zeros(), 0.0);
    for (proximal, distal, fraction, along) in SEGMENTS {
        let Some(start) = frame.get(proximal) else {
            continue;
        };
        let point = match frame.get(distal) {
            Some(end) => start + (end - start) * along,
            // A hand without its point: at the wrist.
            None if matches!(distal, J::LHand | J::RHand) => start,
            None => continue,
        };
        moment += point * fraction;
        mass += fraction;
    }
    (mass >= 0.5).then(|| moment / mass)
}
