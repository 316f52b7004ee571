//! Servo targets: the posture to command so that stiff position servos settle at the planned one.
//!
//! A position servo of stiffness `k` (N·m/rad) that holds a torque `τ` settles `τ / k` short of
//! its target. A standing robot's joints hold its weight, so every loaded joint sags: on the G1's
//! physics model (stiffness = effort / 35 mrad) the stance hip and ankle rolls gave 10–30 mrad,
//! which put the centre of mass 13–27 mm outward of the plan on one foot, at the edge of a sole
//! 50–60 mm wide. Commanding
//!
//! ```text
//! target = q + τ(q) / k,        τ = Model::static_torques(q, loads)
//! ```
//!
//! removes the static part of that error. `k = effort / servo_saturation` per variable
//! ([`BipedProfile::servo_saturation`], [`Variable::effort`](crate::model::Variable::effort);
//! a variable without an effort limit is taken as rigid). The loads are the model's: rooted at
//! its root sole, which takes what the other sole does not ([`other_sole_load`]). The other sole
//! carries nothing while it is in the air, the whole weight (under the CoM) while the root sole
//! is, and with both down the share of the weight that the lever rule gives for the centre of
//! mass between the two soles,
//!
//! ```text
//! w = clamp(((c − p_root) · (p_other − p_root)) / |p_other − p_root|², 0, 1)   (ground plane)
//! ```
//!
//! at the point of its sole as far beside the line between the soles as the CoM (so both soles'
//! centres of pressure lie under the CoM along the feet, and the ankles share the moment of a CoM
//! ahead of them as the soles share the weight). The two legs of a double support form a closed
//! chain whose load split statics alone does not fix; this split leaves no moment about either
//! sole's centre of pressure. Targets stay inside the joint limits.

use faer::Mat;
use nalgebra::{Vector2, Vector3};

use super::BipedProfile;
use crate::human::Side;
use crate::model::{FrameId, Model, ModelData, ModelError, PointLoad};

/// Standard gravity (m/s²).
const GRAVITY: f64 = 9.81;

/// The servo stiffness of each variable and a row of scratch: [`ServoSag::targets`] allocates
/// nothing.
#[derive(Debug, Clone)]
pub struct ServoSag {
    /// N·m/rad (or N/m) per variable; infinite for a variable without an effort limit.
    stiffness: Vec<f64>,
    /// The static torques, 1×n.
    torques: Mat<f64>,
}

impl ServoSag {
    /// The sag model of `profile`'s servos; `None` when the profile states no servo stiffness.
    pub fn new(profile: &BipedProfile) -> Option<Self> {
        let saturation = profile.servo_saturation?;
        let model = profile.model(Side::Right);
        let stiffness = model
            .variables()
            .iter()
            .map(|v| v.effort / saturation)
            .collect();
        Some(Self {
            stiffness,
            torques: Mat::zeros(1, model.nv()),
        })
    }

    /// Writes into `out` the servo targets (rad, model variable order) of the posture `q` whose
    /// forward kinematics `data` holds in `model` (one of the profile's), its root sole fixed and
    /// `loads` pushing up (see [`other_sole_load`]).
    ///
    /// # Errors
    /// `q` or `out` not one entry per variable, or the errors of [`Model::static_torques`].
    pub fn targets(
        &mut self,
        model: &Model,
        data: &ModelData,
        loads: &[PointLoad],
        q: &[f64],
        out: &mut [f64],
    ) -> Result<(), ModelError> {
        for len in [q.len(), out.len()] {
            if len != self.stiffness.len() {
                return Err(ModelError::WrongQLength {
                    expected: self.stiffness.len(),
                    got: len,
                });
            }
        }
        model.static_torques(data, GRAVITY, loads, self.torques.as_mut())?;
        let variables = model.variables();
        for (k, (target, &angle)) in out.iter_mut().zip(q).enumerate() {
            let sag = self.torques[(0, k)] / self.stiffness[k];
            let sag = if sag.is_finite() { sag } else { 0.0 };
            *target = (angle + sag).clamp(variables[k].lower, variables[k].upper);
        }
        Ok(())
    }
}

/// Which soles carry the robot.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LoadedSoles {
    /// The model's root sole alone (the other is in the air).
    Root,
    /// The other sole alone (the root sole is in the air).
    Other,
    /// Both.
    Both,
}

/// What the sole that is not the root carries: nothing, the whole weight under the CoM, or
/// the lever rule's share (module docs); `soles` are `[root, other]` in `model`, whose forward
/// kinematics `data` holds.
///
/// # Errors
/// Frames of another model, kinematics not computed, a model without mass.
pub fn other_sole_load(
    model: &Model,
    data: &ModelData,
    [root_sole, other_sole]: [FrameId; 2],
    loaded: LoadedSoles,
) -> Result<Option<PointLoad>, ModelError> {
    Ok(match loaded {
        LoadedSoles::Root => None,
        LoadedSoles::Other => Some(whole_weight_on(model, data, other_sole)?),
        LoadedSoles::Both => Some(lever_load(model, data, root_sole, other_sole)?),
    })
}

/// The load on the sole `other` with both soles down: the lever rule's share of the weight
/// (module docs), at the point of that sole as far beside the line between the soles as the
/// CoM.
fn lever_load(
    model: &Model,
    data: &ModelData,
    root: FrameId,
    other: FrameId,
) -> Result<PointLoad, ModelError> {
    let at = |frame: FrameId| data.frame_placement(frame).translation.vector.xy();
    let (from, span) = (at(root), at(other) - at(root));
    let beside = model.com(data)?.xy() - from;
    let along = beside.dot(&span) / span.norm_squared();
    if !along.is_finite() {
        // The soles on top of each other: each takes half, under the CoM.
        return Ok(weight_on(data, other, beside + from, 0.5 * weight(model)));
    }
    let across = beside - span * along;
    let share = along.clamp(0.0, 1.0);
    Ok(weight_on(
        data,
        other,
        at(other) + across,
        share * weight(model),
    ))
}

/// The whole weight on the sole `sole`, under the centre of mass.
fn whole_weight_on(
    model: &Model,
    data: &ModelData,
    sole: FrameId,
) -> Result<PointLoad, ModelError> {
    Ok(weight_on(data, sole, model.com(data)?.xy(), weight(model)))
}

/// `force` (N) pushing up on the sole `sole` at the floor point `point` (base frame x, y).
fn weight_on(data: &ModelData, sole: FrameId, point: Vector2<f64>, force: f64) -> PointLoad {
    let placement = data.frame_placement(sole);
    let point = Vector3::new(point.x, point.y, placement.translation.z);
    PointLoad {
        frame: sole,
        offset: placement.inverse_transform_point(&point.into()).coords,
        force,
    }
}

/// The model's weight (N).
fn weight(model: &Model) -> f64 {
    model.total_mass() * GRAVITY
}
