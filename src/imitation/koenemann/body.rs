//! The robot's body as Koenemann et al.'s method sees it, measured once at the standing posture
//! (shoulders, hips, the folded arms' reach, the soles' offset points), and the hand targets
//! kept where the arms can take them (beyond the folded reach, outside the torso).

use nalgebra::Vector3;

use super::goals::in_torso;
use super::mapping::Limbs;
use super::solves::frames;
use crate::human::{HumanJoint, Side};
use crate::imitation::error::ImitationError;
use crate::imitation::reach::Arm;
use crate::imitation::reference::scaler::reference_points;
use crate::robots::BipedProfile;

/// How far beyond the folded arm's reach a hand target is kept (m): at the reach itself the
/// elbow ends a hair past its limit and the IK still pressed it.
const FOLD_CLEARANCE: f64 = 0.005;

/// Robot geometry the method needs, measured once at the standing posture.
#[derive(Debug)]
pub(super) struct Body {
    /// Shoulders and hips in the torso frame (m), `[left, right]`.
    pub(super) shoulders: [Vector3<f64>; 2],
    /// The nearest each hand gets to its shoulder, the elbow at its most bent (m; 0 for an arm
    /// the profile does not map), `[left, right]`.
    pub(super) folded: [f64; 2],
    pub(super) hips: [Vector3<f64>; 2],
    pub(super) limbs: Limbs,
    /// The point of each sole the offset ends at, in the sole frames: its centre, or its
    /// stance point ([`MotionTuning::offset_to_stance_point`](crate::robots::MotionTuning::offset_to_stance_point)).
    pub(super) centres: [Vector3<f64>; 2],
    /// Each ankle in its sole frame.
    pub(super) ankles: [Vector3<f64>; 2],
    /// Each ankle relative to its hip standing (torso axes).
    pub(super) stance: [Vector3<f64>; 2],
}

impl Body {
    pub(super) fn measure(profile: &BipedProfile, q: &[f64]) -> Result<Self, ImitationError> {
        let model = profile.model(Side::Right);
        let mut data = model.new_data();
        model.forward_kinematics(&mut data, q)?;
        let f = frames(profile, Side::Right)?;
        let torso = data.frame_placement(f.torso).inverse();
        let points = reference_points(model, &data, &profile.points)?;
        let point = |joint: HumanJoint| {
            points[joint.index()].ok_or(ImitationError::InvalidParameter {
                name: "profile.points",
                value: joint.index() as f64,
                reason: "the method needs the shoulders, elbows, hips and knees mapped",
            })
        };
        use HumanJoint as J;
        let pair = |l, r| -> Result<[Vector3<f64>; 2], ImitationError> {
            Ok([point(l)?, point(r)?].map(|p| torso.transform_point(&p.into()).coords))
        };
        let shoulders = pair(J::LShoulder, J::RShoulder)?;
        let elbows = pair(J::LElbow, J::RElbow)?;
        let hips = pair(J::LHip, J::RHip)?;
        let knees = pair(J::LKnee, J::RKnee)?;
        let hands = f
            .hands
            .map(|h| in_torso(&data, f.torso, h).translation.vector);
        let ankles = f
            .ankles
            .map(|a| in_torso(&data, f.torso, a).translation.vector);
        let length = |a: &[Vector3<f64>; 2], b: &[Vector3<f64>; 2], c: &[Vector3<f64>; 2]| {
            [0, 1].map(|k| (b[k] - a[k]).norm() + (c[k] - b[k]).norm())
        };
        let sole_ankle = |s: Side| {
            let k = s.index();
            (data.frame_placement(f.soles[k]).inverse() * data.frame_placement(f.ankles[k]))
                .translation
                .vector
        };
        let folded =
            Side::BOTH.map(|side| Arm::of(profile, model, side).map_or(0.0, |a| a.nearest()));
        Ok(Body {
            shoulders,
            folded,
            hips,
            limbs: Limbs {
                arms: length(&shoulders, &elbows, &hands),
                legs: length(&hips, &knees, &ankles),
            },
            centres: Side::BOTH.map(|s| {
                let [x, y] = match profile.tuning.offset_to_stance_point {
                    true => profile.stance_point(s, profile.tuning.support_margin),
                    false => profile.sole_centre(s),
                };
                Vector3::new(x, y, 0.0)
            }),
            ankles: Side::BOTH.map(sole_ankle),
            stance: [0, 1].map(|k| ankles[k] - hips[k]),
        })
    }
}

/// `p` (torso frame, m) pushed along the line from arm `k`'s shoulder until it lies
/// [`FOLD_CLEARANCE`] beyond the nearest its hand gets (the elbow at its most bent). A target
/// the folded arm cannot reach had the arm's IK press the elbow into its limit frame after
/// frame, and the free joints of the wrist turned back and forth at their velocity bound
/// (NAO, CMU 02_10: 145 frames with a joint reversal, 135 of them the right wrist's yaw; 2
/// with the target pushed out).
pub(super) fn beyond_fold(p: Vector3<f64>, k: usize, body: &Body) -> Vector3<f64> {
    let arm = p - body.shoulders[k];
    let nearest = body.folded[k] + FOLD_CLEARANCE;
    match arm.try_normalize(1e-9) {
        Some(direction) if arm.norm() < nearest => body.shoulders[k] + direction * nearest,
        _ => p,
    }
}

/// `p` pushed out of the torso's vertical cylinder of `radius` around the torso's z axis,
/// between the hips and the shoulders (torso frame).
pub(super) fn outside_torso(p: Vector3<f64>, radius: f64, body: &Body) -> Vector3<f64> {
    let (low, high) = (body.hips[0].z, body.shoulders[0].z);
    let across = p.xy().norm();
    if p.z < low || p.z > high || across >= radius {
        return p;
    }
    let direction = if across > 1e-9 {
        p.xy() / across
    } else {
        nalgebra::Vector2::new(1.0, 0.0)
    };
    let xy = direction * radius;
    Vector3::new(xy.x, xy.y, p.z)
}
