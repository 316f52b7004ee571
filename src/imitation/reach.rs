//! Hand references beyond the robot arm's reach: a hand error that is not lateness.
//!
//! A hand's scaled reference is placed from the *scaled* shoulder with the robot's segment
//! lengths ([`super::scaler`], eq. 1), so it is always within the arm's length of that point.
//! The robot's own shoulder is elsewhere whenever its trunk does not follow the scaled one: the
//! tables hold the torso upright over the stance foot, a robot standing on bent knees carries
//! its hips lower than the scaled hips, and a robot whose waist is not tracked (the G1) keeps
//! its shoulders where its posture puts them. Per frame of the clip the meter measures how far
//! each hand's reference lies beyond the arm's reach from the robot's current shoulder:
//!
//! ```text
//! shortfall = max(0, |p_hand^ref − p_shoulder^robot(q)| − L_arm)
//! ```
//!
//! with `L_arm` the sum of the robot segment lengths shoulder → elbow → wrist → hand of the
//! [`RobotSkeleton`] (metres, reference posture). The sum is an upper bound of the reach (joint
//! limits may keep the arm from stretching straight), so the unreachable frames counted are a
//! lower bound, and a hand's error on such a frame is at least its shortfall whatever the arm
//! does. Positions in the left-rooted model's base frame; the references are moved there from
//! the frame's root.

use nalgebra::{IsometryMatrix3, Vector3};

use super::imitator::RobotFrame;
use super::output::EFFECTORS;
use super::scaler::RobotSkeleton;
use crate::human::{HumanJoint, Side};
use crate::model::{FrameId, Model, ModelData};
use crate::robots::{BipedProfile, RobotPoint};

/// How far one hand's references lay beyond the arm's reach over the frames measured.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HandReach {
    /// The arm's length: the robot segments from the shoulder to the hand (m).
    pub reach_m: f64,
    /// Frames measured (the clip's frames with a reference for this hand).
    pub frames: usize,
    /// Frames whose reference lay beyond `reach_m` from the robot's shoulder.
    pub unreachable_frames: usize,
    /// Mean shortfall over the unreachable frames (m); `None` without any.
    pub mean_shortfall_m: Option<f64>,
    /// Largest shortfall (m); `None` without any unreachable frame.
    pub max_shortfall_m: Option<f64>,
}

/// One robot arm in the meter's model: the frames of its shoulder point and its length.
#[derive(Debug, Clone, Copy)]
struct Arm {
    hand: HumanJoint,
    /// The shoulder point is the mean of these frames' origins (the same frame twice for a
    /// [`RobotPoint::Frame`]).
    shoulder: [FrameId; 2],
    reach: f64,
}

impl Arm {
    /// The `side` arm of `profile` in `model`; `None` when its hand or shoulder is not mapped or
    /// a frame is unknown.
    fn of(
        profile: &BipedProfile,
        skeleton: &RobotSkeleton,
        model: &Model,
        side: Side,
    ) -> Option<Self> {
        let (hand, shoulder) = match side {
            Side::Left => (EFFECTORS[0].1, HumanJoint::LShoulder),
            Side::Right => (EFFECTORS[1].1, HumanJoint::RShoulder),
        };
        let mut reach = 0.0;
        let mut joint = hand;
        while joint != shoulder {
            reach += skeleton.length(joint)?;
            joint = skeleton.antecedent(joint)?;
        }
        let frame = |name: &str| model.frame_id(name).ok();
        let shoulder = match &profile.points.iter().find(|(j, _)| *j == shoulder)?.1 {
            RobotPoint::Frame(a) => [frame(a)?; 2],
            RobotPoint::Midpoint(a, b) => [frame(a)?, frame(b)?],
        };
        Some(Self {
            hand,
            shoulder,
            reach,
        })
    }

    /// How far `target` (model base frame, m) lies beyond the arm's reach from the shoulder
    /// point of the kinematics in `data` (m; negative within it).
    fn shortfall(&self, data: &ModelData, target: &Vector3<f64>) -> f64 {
        let [a, b] = self
            .shoulder
            .map(|f| data.frame_placement(f).translation.vector);
        (target - (a + b) * 0.5).norm() - self.reach
    }
}

/// Measures [`HandReach`] frame by frame (see the module docs).
#[derive(Debug, Clone)]
pub struct ReachMeter {
    model: Model,
    data: ModelData,
    /// The soles in the left-rooted model (`[left, right]`): where a frame's root is.
    soles: [FrameId; 2],
    arms: [Arm; 2],
    counts: [(usize, usize, f64, f64); 2],
}

impl ReachMeter {
    /// A meter for `profile`'s arms; `None` when a hand or shoulder is not mapped or the profile
    /// cannot be measured (the imitator validated its profile, so that is the unmapped case).
    pub fn new(profile: &BipedProfile) -> Option<Self> {
        let skeleton = RobotSkeleton::of(profile).ok()?;
        let model = profile.models[Side::Left.index()].clone();
        let arm = |side| Arm::of(profile, &skeleton, &model, side);
        let arms = [arm(Side::Left)?, arm(Side::Right)?];
        let sole = |side: Side| model.frame_id(&profile.foot(side).sole).ok();
        Some(Self {
            data: model.new_data(),
            soles: [sole(Side::Left)?, sole(Side::Right)?],
            model,
            arms,
            counts: [(0, 0, 0.0, 0.0); 2],
        })
    }

    /// Records one frame of the clip.
    pub fn record(&mut self, frame: &RobotFrame) {
        if self
            .model
            .forward_kinematics(&mut self.data, &frame.q)
            .is_err()
        {
            return;
        }
        let base_t_root: IsometryMatrix3<f64> =
            *self.data.frame_placement(self.soles[frame.root.index()]);
        for (arm, counts) in self.arms.iter().zip(&mut self.counts) {
            let Some(reference) = frame.reference[arm.hand.index()] else {
                continue;
            };
            let reference = base_t_root.transform_point(&reference.into()).coords;
            let shortfall = arm.shortfall(&self.data, &reference);
            counts.0 += 1;
            if shortfall > 0.0 {
                counts.1 += 1;
                counts.2 += shortfall;
                counts.3 = counts.3.max(shortfall);
            }
        }
    }

    /// The reach of both hands (`[left, right]`) over the frames recorded.
    pub fn reach(&self) -> [HandReach; 2] {
        std::array::from_fn(|k| {
            let (frames, unreachable, sum, max) = self.counts[k];
            let any = unreachable > 0;
            HandReach {
                reach_m: self.arms[k].reach,
                frames,
                unreachable_frames: unreachable,
                mean_shortfall_m: any.then(|| sum / unreachable as f64),
                max_shortfall_m: any.then_some(max),
            }
        })
    }
}
