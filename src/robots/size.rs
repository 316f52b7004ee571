//! A biped's sizes read off its profile ([`BipedProfile::size`]): what the scaling rules of
//! [`super::tuning`] scale by. A file of its own so that `tuning`, which the profile holds,
//! does not import the profile back.

use nalgebra::Vector3;

use super::error::ProfileError;
use super::profile::{BipedProfile, outline_bounds};
use super::tuning::BipedSize;
use crate::human::{HumanJoint, Side};

impl BipedProfile {
    /// This robot's sizes in its standing posture, in the model rooted at the left sole: what
    /// the scaling rules of [`super::tuning`] scale by.
    ///
    /// # Errors
    /// [`ProfileError::Invalid`] when a size is not finite and > 0 (e.g. hip points at one
    /// place, a massless model); [`ProfileError::Model`] for a frame the model lacks.
    pub fn size(&self) -> Result<BipedSize, ProfileError> {
        let profile = self;
        let model = profile.model(Side::Left);
        let mut data = model.new_data();
        model.forward_kinematics(&mut data, &profile.stand)?;
        let frame = |name: &str| -> Result<Vector3<f64>, ProfileError> {
            Ok(data
                .frame_placement(model.frame_id(name)?)
                .translation
                .vector)
        };
        let point = |joint: HumanJoint| -> Result<Option<Vector3<f64>>, ProfileError> {
            let Some((_, p)) = profile.points.iter().find(|(h, _)| *h == joint) else {
                return Ok(None);
            };
            let frames = p.frames().map(frame).collect::<Result<Vec<_>, _>>()?;
            Ok(Some(
                frames.iter().sum::<Vector3<f64>>() / frames.len() as f64,
            ))
        };
        let missing = |joint: HumanJoint| ProfileError::Invalid {
            field: format!("points.{}", joint.name()),
            reason: "required".into(),
        };
        let hip = |joint| point(joint)?.ok_or_else(|| missing(joint));
        let (left_hip, right_hip) = (hip(HumanJoint::LHip)?, hip(HumanJoint::RHip)?);
        let hand = frame(&profile.hands[0])?;
        let shoulder = match point(HumanJoint::LShoulder)? {
            Some(p) => p,
            None => frame(&profile.torso)?,
        };
        let widths = Side::BOTH.map(|side| {
            let [lo, hi] = outline_bounds(&profile.foot(side).outline);
            hi[1] - lo[1]
        });
        let size = BipedSize {
            com_height: model.com(&data)?.z,
            half_stance: 0.5 * (left_hip - right_hip).norm(),
            hip_height: 0.5 * (left_hip.z + right_hip.z),
            sole_width: 0.5 * (widths[0] + widths[1]),
            arm_length: (hand - shoulder).norm(),
            upper_body_speed: mean_speed(profile, false)?,
            leg_speed: mean_speed(profile, true)?,
        };
        checked(size)
    }
}

/// `size` when every size is finite and > 0.
fn checked(size: BipedSize) -> Result<BipedSize, ProfileError> {
    let sizes = [
        ("com_height", size.com_height),
        ("half_stance", size.half_stance),
        ("hip_height", size.hip_height),
        ("sole_width", size.sole_width),
        ("arm_length", size.arm_length),
        ("upper_body_speed", size.upper_body_speed),
        ("leg_speed", size.leg_speed),
    ];
    match sizes
        .into_iter()
        .find(|(_, v)| !(v.is_finite() && *v > 0.0))
    {
        Some((name, v)) => Err(ProfileError::Invalid {
            field: format!("size.{name}"),
            reason: format!("{v} read off the standing posture is not finite and > 0"),
        }),
        None => Ok(size),
    }
}

/// Mean rated speed (rad/s) of the variables on the sole-to-sole chain (`legs`) or off it, or
/// of all of them when none is on that side.
fn mean_speed(profile: &BipedProfile, legs: bool) -> Result<f64, ProfileError> {
    let chain = profile.sole_chain_variables(&profile.stand)?;
    let variables = profile.model(Side::Left).variables();
    let mean = |pick: &dyn Fn(usize) -> bool| {
        let speeds: Vec<f64> = (0..variables.len())
            .filter(|&i| pick(i))
            .map(|i| variables[i].velocity)
            .collect();
        (!speeds.is_empty()).then(|| speeds.iter().sum::<f64>() / speeds.len() as f64)
    };
    Ok(mean(&|i| chain[i] == legs)
        .or_else(|| mean(&|_| true))
        .unwrap_or(0.0))
}
