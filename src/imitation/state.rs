//! The robot's state that both methods (Poubel's, Koenemann's) and the dispatcher share:
//! the profile and its models' forward kinematics at the current posture, the root sole and
//! its world placement, the joint bounds, the robot's clock and the output frame; and the
//! helpers both methods build it with. Below both methods, so that neither imports the
//! dispatcher ([`crate::imitation::imitator`]).

use nalgebra::{IsometryMatrix3, Vector2, Vector3};

use crate::human::{HumanFrame, HumanJoint, Side};
use crate::imitation::config::ImitatorConfig;
use crate::imitation::error::ImitationError;
use crate::imitation::output::{RobotFrame, effector_frames};
use crate::imitation::phase::SupportPhase;
use crate::locomotion::GroundPose;
use crate::model::{FrameId, Model, ModelData, ModelError};
use crate::robots::BipedProfile;
use crate::robots::servo::{LoadedSoles, ServoSag, other_sole_load};
use crate::robots::sway::SwayShaper;
use crate::solver::{JointBounds, SolverError};

/// What both methods keep: the robot, its models' forward kinematics, the posture, the root
/// sole and its world placement, the bounds, the output frame.
#[derive(Debug)]
pub(crate) struct Shared {
    pub(crate) profile: BipedProfile,
    /// Forward kinematics of the model rooted at each sole (`[left, right]`).
    pub(crate) data: [ModelData; 2],
    /// The sole frames of each model: `soles[root][foot]`.
    pub(crate) soles: [[FrameId; 2]; 2],
    pub(crate) q: Vec<f64>,
    pub(crate) root: Side,
    pub(crate) world_t_root: IsometryMatrix3<f64>,
    pub(crate) bounds: JointBounds,
    /// Whether each variable is on the sole-to-sole chain (the legs).
    pub(crate) legs: Vec<bool>,
    pub(crate) velocity_fraction: f64,
    pub(crate) nominal_dt: f64,
    pub(crate) previous_time: Option<f64>,
    /// Robot time spent with the human's clock paused (s): the robot's clock is the human
    /// frame's time plus this.
    pub(crate) paused: f64,
    pub(crate) output: RobotFrame,
    /// The servos' static deflection, when the profile states their stiffness.
    servo: Option<ServoSag>,
    /// The servo commands' sway shaper, when the profile states the sway period.
    sway: Option<SwayShaper>,
    /// Whether the root's forward kinematics are known to be at `q` and untouched since
    /// ([`Shared::note_kinematics_current`]): the next [`Shared::refresh`] then skips them.
    kinematics_current: bool,
}

impl Shared {
    /// The shared state at the start, and the position bounds (no velocity limits).
    pub(crate) fn new(
        profile: BipedProfile,
        config: &ImitatorConfig,
    ) -> Result<(Self, JointBounds), ImitationError> {
        let model = profile.model(Side::Right);
        let position_bounds = crate::tasks::joint_bounds(model)?;
        let q = initial_posture(&profile, config, &position_bounds)?;
        let legs = profile.sole_chain_variables(&q)?;
        let upper_body = (config.upper_body_velocity_fraction)
            .unwrap_or(profile.tuning.upper_body_velocity_fraction);
        let velocity_fraction = config.velocity_fraction_for(&profile.tuning);
        let bounds = velocity_bounds(
            model,
            &position_bounds,
            &legs,
            velocity_fraction,
            upper_body,
        )?;
        let mut data = profile.models.each_ref().map(Model::new_data);
        let soles = sole_frames(&profile)?;
        let right = Side::Right.index();
        model.forward_kinematics(&mut data[right], &q)?;
        let left_sole = *data[right].frame_placement(soles[right][Side::Left.index()]);
        let output = RobotFrame::at_start(&q, left_sole, &[0, 0]);
        let servo = ServoSag::new(&profile);
        let sway = profile
            .sway_period
            .map(|period| SwayShaper::new(period, q.len(), config.nominal_dt))
            .transpose()?;
        let shared = Shared {
            profile,
            data,
            soles,
            q,
            root: Side::Right,
            world_t_root: IsometryMatrix3::identity(),
            bounds,
            legs,
            velocity_fraction,
            nominal_dt: config.nominal_dt,
            previous_time: None,
            paused: 0.0,
            output,
            servo,
            sway,
            kinematics_current: false,
        };
        Ok((shared, position_bounds))
    }

    /// Makes room in the output for `[tasks, levels]` task errors and level reports (before
    /// the first step), so that stepping never allocates.
    pub(crate) fn reserve_output(&mut self, sizes: [usize; 2]) {
        let left_sole = self.output.left_sole;
        self.output = RobotFrame::at_start(&self.q, left_sole, &sizes);
    }

    /// The time step ending at `time` (s): the nominal one for the first frame and for a
    /// repeated time, which pauses the human's clock for that long (the robot's runs on).
    pub(crate) fn begin_frame(&mut self, time: f64) -> Result<f64, ImitationError> {
        if !time.is_finite() {
            return Err(
                crate::imitation::reference::scaler::ScaleError::NonFiniteTime(time).into(),
            );
        }
        match self.previous_time {
            None => Ok(self.nominal_dt),
            Some(previous) if time > previous => Ok(time - previous),
            Some(previous) if time == previous => {
                self.paused += self.nominal_dt;
                Ok(self.nominal_dt)
            }
            Some(previous) => Err(ImitationError::TimeGoesBack { time, previous }),
        }
    }

    /// Forward kinematics of the root's model at `q`; none when the last call of
    /// [`Shared::note_kinematics_current`] came after the last refresh.
    pub(crate) fn refresh(&mut self) -> Result<(), ImitationError> {
        if std::mem::take(&mut self.kinematics_current) {
            return Ok(());
        }
        let root = self.root.index();
        self.profile
            .model(self.root)
            .forward_kinematics(&mut self.data[root], &self.q)?;
        Ok(())
    }

    /// Tells the next [`Shared::refresh`] that the root's forward kinematics are at `q`: the
    /// caller has just computed them there, and nothing changes `q`, the root or the
    /// kinematics before that refresh (a frame's solve ends with the kinematics at its final
    /// posture, and the next frame begins by refreshing them).
    pub(crate) fn note_kinematics_current(&mut self) {
        self.kinematics_current = true;
    }

    /// Re-roots the model at `foot` if it is not already, keeping the world placement
    /// (`ʷT_b = ʷT_a · ᵃT_b(q)`): the robot does not move in the world. Leaves the new root's
    /// forward kinematics current.
    pub(crate) fn switch_root(&mut self, foot: Side) -> Result<(), ImitationError> {
        self.refresh()?;
        if foot != self.root {
            let from = self.root.index();
            let model = self.profile.model(self.root);
            let sole = self.soles[from][foot.index()];
            self.world_t_root =
                model.placement_in_world(&self.data[from], &self.world_t_root, sole)?;
            self.root = foot;
            self.refresh()?;
        }
        Ok(())
    }

    /// The world-frame part of the output from the root's current forward kinematics: soles,
    /// CoM, time, posture, phase, effectors (`effectors`: their frames in the root's model).
    pub(crate) fn write_output(
        &mut self,
        time: f64,
        phase: SupportPhase,
        effectors: &[FrameId; 4],
    ) -> Result<(), ImitationError> {
        let root = self.root.index();
        let (model, data) = (self.profile.model(self.root), &self.data[root]);
        let world_t_root = self.world_t_root;
        let placement = |foot: Side| -> Result<IsometryMatrix3<f64>, ModelError> {
            model.placement_in_world(data, &world_t_root, self.soles[root][foot.index()])
        };
        let out = &mut self.output;
        out.right_sole = placement(Side::Right)?;
        out.left_sole = placement(Side::Left)?;
        out.com = world_t_root
            .transform_point(&model.com(data)?.into())
            .coords;
        out.time = time + self.paused;
        out.human_time = time;
        out.q.copy_from_slice(&self.q);
        match &mut self.servo {
            Some(servo) => {
                let other = self.root.other();
                let soles = [self.soles[root][root], self.soles[root][other.index()]];
                let loaded = match phase.airborne_foot() {
                    Some(foot) if foot == other => LoadedSoles::Root,
                    Some(_) => LoadedSoles::Other,
                    None => LoadedSoles::Both,
                };
                let load = other_sole_load(model, data, soles, loaded)?;
                servo.targets(
                    model,
                    data,
                    load.as_slice(),
                    &self.q,
                    &mut out.servo_targets,
                )?;
            }
            None => out.servo_targets.copy_from_slice(&self.q),
        }
        if let Some(sway) = &mut self.sway {
            sway.shape(out.time, &mut out.servo_targets)?;
        }
        for (position, &id) in out.effectors.iter_mut().zip(effectors) {
            *position = data.frame_placement(id).translation.vector;
        }
        out.phase = phase;
        out.root = self.root;
        out.world_t_root = world_t_root;
        Ok(())
    }
}

/// The starting posture: `config.initial_q` or the profile's standing posture, inside the limits.
pub(crate) fn initial_posture(
    profile: &BipedProfile,
    config: &ImitatorConfig,
    bounds: &JointBounds,
) -> Result<Vec<f64>, ImitationError> {
    let nv = profile.model(Side::Right).nv();
    let mut q = match &config.initial_q {
        Some(q) if q.len() == nv => q.clone(),
        Some(q) => {
            return Err(SolverError::DimensionMismatch {
                what: "initial_q".into(),
                expected: nv,
                got: q.len(),
            }
            .into());
        }
        None => profile.stand.clone(),
    };
    bounds.clamp_position(&mut q);
    Ok(q)
}

/// `position` with velocity limits: the model's rated velocities times `leg_fraction` on the
/// legs (`legs[k]`), times the `upper_body` fraction elsewhere.
pub(crate) fn velocity_bounds(
    model: &Model,
    position: &JointBounds,
    legs: &[bool],
    leg_fraction: f64,
    upper_body: f64,
) -> Result<JointBounds, SolverError> {
    let velocity: Vec<f64> = model
        .variables()
        .iter()
        .zip(legs)
        .map(|(v, &leg)| match leg {
            true => v.velocity * leg_fraction,
            false => v.velocity * upper_body,
        })
        .collect();
    JointBounds::with_velocity(position.lower(), position.upper(), &velocity)
}

/// The sole frames of the model rooted at each sole: `[root][foot]`.
pub(crate) fn sole_frames(profile: &BipedProfile) -> Result<[[FrameId; 2]; 2], ModelError> {
    let sole_ids = |root: Side| -> Result<[FrameId; 2], ModelError> {
        let model = profile.model(root);
        let [left, right] = Side::BOTH.map(|foot| model.frame_id(&profile.foot(foot).sole));
        Ok([left?, right?])
    };
    Ok([sole_ids(Side::Left)?, sole_ids(Side::Right)?])
}

/// The frames of [`EFFECTORS`] (hands, ankles) in the model rooted at each sole: `[root]`.
pub(crate) fn effector_ids(profile: &BipedProfile) -> Result<[[FrameId; 4]; 2], ModelError> {
    let names = effector_frames(profile);
    let ids = |root: Side| -> Result<[FrameId; 4], ModelError> {
        let model = profile.model(root);
        let [a, b, c, d] = names.map(|name| model.frame_id(name));
        Ok([a?, b?, c?, d?])
    };
    Ok([ids(Side::Left)?, ids(Side::Right)?])
}

/// The ground pose (sole point, heading) of a sole placement.
pub(crate) fn ground_pose(sole: &IsometryMatrix3<f64>) -> GroundPose {
    let x = sole.rotation * Vector3::x();
    GroundPose {
        xy: sole.translation.vector.xy(),
        yaw: x.y.atan2(x.x),
    }
}

/// The human's mid-ankle ground point (xy, m) and hip heading (rad) in `frame`
/// ([`HumanFrame::pelvis_heading`]; `None` with the hips on one vertical).
pub(crate) fn human_stance(frame: &HumanFrame) -> Option<(Vector2<f64>, f64)> {
    let (l, r) = (
        frame.get(HumanJoint::LAnkle)?,
        frame.get(HumanJoint::RAnkle)?,
    );
    Some(((l + r).xy() * 0.5, frame.pelvis_heading(0.0)?))
}
