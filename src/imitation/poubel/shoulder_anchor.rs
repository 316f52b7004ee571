//! The scaled human's arms hung from the robot's own shoulders.
//!
//! The scaler places each arm from the *scaled* shoulder with the robot's segment lengths
//! ([`crate::imitation::reference::scaler`], eq. 1). The robot's shoulder stands elsewhere whenever its trunk does not
//! follow the scaled trunk: the tables hold the torso upright and facing over the feet while
//! the human's shoulders sway and counter-rotate as they walk (on CMU 07_04 the G1's left
//! shoulder moves 9 cm against the scaled one in 0.13 s), and a robot standing on bent knees
//! carries its hips and shoulders lower and further back (the G1's 4–9 cm behind the scaled
//! shoulders on the bundled clips). A hand reference placed from the scaled shoulder is then
//! out of the robot arm's reach, or asks the arm to make up for the trunk: an error that no
//! speed removes. So each arm of the reference (shoulder, elbow, wrist, hand) is moved by the
//! offset of the robot's shoulder from the scaled one,
//!
//! ```text
//! p ← p + (T_torso(q) · s₀ − p_shoulder^scaled)   for p in the arm's points
//! ```
//!
//! with `T_torso(q)` the placement of the profile's torso frame in the posture before the
//! frame's solve and `s₀` the shoulder point in that frame in the standing posture: the
//! shoulder itself on a robot whose arms hang from its torso (the NAO), and on one with a waist
//! (the G1) the shoulder as it stands with the waist at rest. The human's arm (its joints'
//! directions, the robot's segment lengths) is then copied from where the robot's shoulder
//! stands, as in Koenemann et al.'s method. Not the shoulder through the waist: the waist turns
//! for the hands, and a reference moved with it moves with the hand it aims (the G1's waving
//! arm on Kinect ges01 turned its joints back at speed on 3 of 154 frames). Not low-passed:
//! with the offset averaged over 0.03–2 s the hands came further off on every walk, as the
//! human trunk's sway came back into the references.
//!
//! Measured on the bundled clips (Poubel's method, default settings, mean hand error over the
//! clip, cm): the NAO 4.5 / 8.5 / 4.5 / 4.6 / 4.9 / 11.6 / 3.5 / 2.5 → 4.8 / 8.0 / 3.7 / 1.9 /
//! 2.4 / 7.8 / 3.1 / 3.5 (CMU 02_10, 05_02, 05_12, 07_04, 09_12, 131_01, Kinect ges01, ges02),
//! the G1 5.1 / 14.1 / 6.7 / 10.5 / 11.6 / 17.9 / 7.4 / 5.0 → 4.6 / 12.2 / 5.5 / 2.8 / 4.4 /
//! 9.0 / 7.6 / 4.8; the runs stand in the physics judge as before.
//!
//! Units: metres; positions in the model root's frame.

use nalgebra::Vector3;

use crate::human::{HumanJoint, Side};
use crate::imitation::reach::Arm;
use crate::model::ModelData;

/// Moves each arm of `references` (scaled human points indexed by [`HumanJoint::index`], root
/// frame) by the offset of the robot's shoulder, from the kinematics in `data` (the root
/// model's), from its scaled shoulder. An arm the profile does not map (`arms[side]` `None`) or
/// without a scaled shoulder is left as it is.
pub(crate) fn hang_arms_from_robot_shoulders(
    arms: &[Option<Arm>; 2],
    data: &ModelData,
    references: &mut [Option<Vector3<f64>>],
) {
    for side in Side::BOTH {
        let shoulder = side.pick(HumanJoint::LShoulder, HumanJoint::RShoulder);
        let (Some(arm), Some(scaled)) = (&arms[side.index()], references[shoulder.index()]) else {
            continue;
        };
        let offset = arm.torso_shoulder_point(data) - scaled;
        let chain = [
            shoulder,
            side.pick(HumanJoint::LElbow, HumanJoint::RElbow),
            side.pick(HumanJoint::LWrist, HumanJoint::RWrist),
            side.pick(HumanJoint::LHand, HumanJoint::RHand),
        ];
        for joint in chain {
            if let Some(p) = &mut references[joint.index()] {
                *p += offset;
            }
        }
    }
}
