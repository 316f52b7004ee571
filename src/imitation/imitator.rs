//! The online imitator (Poubel §III–IV): one human frame in, one robot posture out.
//!
//! Per frame:
//!
//! 1. **Support detection** ([`SupportDetector`]) tells which of the human's feet are on the ground.
//! 2. **Phase machine** ([`PhaseMachine`]) decides the robot's support phase or transition step from
//!    the human support and what the robot achieved at the previous frame ([`Measurements`]).
//! 3. **Model switch**: the phase's table names the sole the model is rooted at (`RFoot` or
//!    `LFoot`). On a switch the new root's world placement is computed from the old model's forward
//!    kinematics at the current `q` (`ʷT_b = ʷT_a · ᵃT_b(q)`), so the robot does not move in the
//!    world: the support foot does not slip. Both models share the variables, so `q` carries over.
//! 4. **Scaling** ([`Scaler`], eq. 1) of the human frame into the support-sole frame, re-expressed in
//!    the model root's frame when the two differ (during a take-off toward the foot that is not
//!    the root yet); human joint angles (the profile's [`HumanJointAngles`]) for the joint-tracking task.
//! 5. **IK**: the phase's [`TaskTable`] is turned into the stack of a solver prepared for it: CoM
//!    xy first, then the Cartesian tasks, then the gradient tasks (joint limits, human joints) in
//!    the remaining null space, with the clamping loop. One Gauss–Newton step per frame
//!    (configurable) with the joint velocities limited to a fraction of the robot's rated
//!    velocities (the paper ran at 10 %), so the output trajectory is executable as it is: a
//!    transition takes the time it needs and the robot catches up afterwards.
//!
//! Everything is allocated in [`Imitator::new`]; [`Imitator::step`] allocates nothing.
//!
//! World frame: the right sole's frame at the first frame (x forward, y left, z up, metres).

use std::time::Instant;

use faer::Mat;
use nalgebra::{IsometryMatrix3, Vector2, Vector3};

use super::footsteps::{FootstepPlanner, GroundPose};
use super::phase::{Measurements, PhaseMachine, Settling, SupportPhase, TakeOff};
use super::phase_solver::{Criteria, FrameTargets, PhaseSolver};
use super::scaler::{RobotSkeleton, ScaleConfig, ScaleError, Scaler};
use super::shaping::{ComReference, MotionLimits, SwingHeight};
use super::support::{HumanSupport, SupportDetector};
use super::tables::{TaskTable, TaskTables};
use crate::human::{HumanFrame, HumanJoint, Side};
use crate::model::{FrameId, Model, ModelData, ModelError};
use crate::robots::{BipedProfile, HumanJointAngles};
use crate::solver::driver::DriverSettings;
use crate::solver::{JointBounds, JointLimitAvoidance, JointTracking, Settings, SolverError};

pub use super::config::ImitatorConfig;
pub use super::error::ImitationError;
use super::output::effector_frames;
pub use super::output::{EFFECTORS, RobotFrame};

/// The online imitator.
pub struct Imitator {
    profile: BipedProfile,
    /// Forward kinematics of the model rooted at each sole (`[left, right]`).
    data: [ModelData; 2],
    /// The sole frames of each model, resolved once: `soles[root][foot]`.
    soles: [[FrameId; 2]; 2],
    /// The frames of [`EFFECTORS`] in each model: `effectors[root]`.
    effectors: [[FrameId; 4]; 2],
    phases: Vec<PhaseSolver>,
    detector: SupportDetector,
    scaler: Scaler,
    /// The profile's human joint-angle map, if it has one.
    angles: Option<Box<dyn HumanJointAngles>>,
    machine: PhaseMachine,
    bounds: JointBounds,
    velocity_fraction: f64,
    iterations: usize,
    max_task_speed: f64,
    max_tracking_speed: f64,
    nominal_dt: f64,
    limits: JointLimitAvoidance,
    tracking: JointTracking,
    human_q: Vec<f64>,
    /// The standing posture of each leg joint (`None` off the legs): the joint-tracking
    /// reference of the legs.
    stance: Vec<Option<f64>>,
    q: Vec<f64>,
    root: Side,
    world_t_root: IsometryMatrix3<f64>,
    phase: SupportPhase,
    measurements: Measurements,
    /// Whether the torso has stopped approaching its target in this step.
    posture_settling: Settling,
    previous_time: Option<f64>,
    footsteps: FootstepPlanner,
    motion: MotionLimits,
    /// The shaped CoM ground projection (world frame); `None` before the first frame.
    com_reference: Option<ComReference>,
    /// The shaped height of the swing foot above the ground.
    swing: SwingHeight,
    output: RobotFrame,
}

impl std::fmt::Debug for Imitator {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Imitator")
            .field("robot", &self.profile.name)
            .field("phase", &self.phase)
            .field("root", &self.root)
            .field("time", &self.previous_time)
            .finish_non_exhaustive()
    }
}

/// The starting posture: `config.initial_q` or the profile's standing posture, inside the limits.
fn initial_posture(
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

/// `position` with the velocity limits of `config`: the model's rated velocities times the
/// velocity fraction on the legs (`legs[k]`), times the `upper_body` fraction elsewhere.
fn velocity_bounds(
    model: &Model,
    position: &JointBounds,
    legs: &[bool],
    config: &ImitatorConfig,
    upper_body: f64,
) -> Result<JointBounds, SolverError> {
    let velocity: Vec<f64> = model
        .variables()
        .iter()
        .zip(legs)
        .map(|(v, &leg)| match leg {
            true => v.velocity * config.velocity_fraction,
            false => v.velocity * upper_body,
        })
        .collect();
    JointBounds::with_velocity(position.lower(), position.upper(), &velocity)
}

/// The sole frames of the model rooted at each sole: `[root][foot]`.
fn sole_frames(profile: &BipedProfile) -> Result<[[FrameId; 2]; 2], ModelError> {
    let sole_ids = |root: Side| -> Result<[FrameId; 2], ModelError> {
        let model = profile.model(root);
        let [left, right] = Side::BOTH.map(|foot| model.frame_id(&profile.foot(foot).sole));
        Ok([left?, right?])
    };
    Ok([sole_ids(Side::Left)?, sole_ids(Side::Right)?])
}

/// The frames of [`EFFECTORS`] (hands, ankles) in the model rooted at each sole: `[root]`.
fn effector_ids(profile: &BipedProfile) -> Result<[[FrameId; 4]; 2], ModelError> {
    let names = effector_frames(profile);
    let ids = |root: Side| -> Result<[FrameId; 4], ModelError> {
        let model = profile.model(root);
        let [a, b, c, d] = names.map(|name| model.frame_id(name));
        Ok([a?, b?, c?, d?])
    };
    Ok([ids(Side::Left)?, ids(Side::Right)?])
}

/// A solver per phase (in [`SupportPhase::ALL`] order) for `tables`.
fn phase_solvers(
    tables: &TaskTables,
    profile: &BipedProfile,
    q: &[f64],
    solver: Settings,
) -> Result<Vec<PhaseSolver>, ImitationError> {
    // Scale to fit: when the velocity limits bind, the whole step slows down uniformly instead
    // of the clamping loop pinning joints the balance level needs.
    let settings = Settings {
        scale_to_fit: true,
        ..solver
    };
    SupportPhase::ALL
        .iter()
        .map(|&phase| PhaseSolver::new(tables.table(phase), profile, q, settings))
        .collect()
}

impl Imitator {
    /// An imitator for the biped described by `profile` (checked with
    /// [`BipedProfile::validate`]).
    ///
    /// # Errors
    /// [`ImitationError`] naming the faulty setting, profile field or table.
    pub fn new(profile: BipedProfile, mut config: ImitatorConfig) -> Result<Self, ImitationError> {
        config.validate()?;
        profile.validate()?;
        let model = profile.model(Side::Right);
        // Position limits only matter to the limit-avoidance gradient and the start clamp.
        let position_bounds = crate::tasks::joint_bounds(model)?;
        let q = initial_posture(&profile, &config, &position_bounds)?;
        let legs = sole_chain_variables(&profile, &q)?;
        let tuning = profile.tuning;
        let upper_body =
            (config.upper_body_velocity_fraction).unwrap_or(tuning.upper_body_velocity_fraction);
        let bounds = velocity_bounds(model, &position_bounds, &legs, &config, upper_body)?;
        // The legs are pulled toward the standing posture, not the human's leg angles: those
        // would only drive the closed chain of double support against itself, and with no pull
        // at all the free height of the pelvis drifts until the knees are straight (singular).
        let stance = legs.iter().zip(&q).map(|(&l, &v)| l.then_some(v)).collect();
        let tables = match config.tables.take() {
            Some(tables) => tables,
            None => TaskTables::executable(&config.phase, &profile),
        };
        let phases = phase_solvers(&tables, &profile, &q, config.solver)?;
        let angles = profile.joint_angles.map(|build| build(model)).transpose()?;
        let mut data = profile.models.each_ref().map(Model::new_data);
        let soles = sole_frames(&profile)?;
        let effectors = effector_ids(&profile)?;
        let right = Side::Right.index();
        model.forward_kinematics(&mut data[right], &q)?;
        let left_sole = *data[right].frame_placement(soles[right][Side::Left.index()]);
        let area = config.step_envelope.unwrap_or(profile.step_envelope);
        let scale = ScaleConfig {
            min_segment: config.min_segment,
            ..ScaleConfig::new(area)
        };
        let output = RobotFrame::at_start(&q, left_sole, &phases_sizes(&phases));
        Ok(Self {
            detector: SupportDetector::new(config.support)?,
            scaler: Scaler::new(RobotSkeleton::of(&profile)?, scale)?,
            angles,
            machine: PhaseMachine::new(config.phase)?,
            limits: JointLimitAvoidance::new(&position_bounds),
            tracking: JointTracking::new(&q)?,
            stance,
            human_q: q.clone(),
            bounds,
            velocity_fraction: config.velocity_fraction,
            iterations: config.iterations_per_frame,
            max_task_speed: config.max_task_speed.unwrap_or(tuning.task_speed),
            max_tracking_speed: config.max_tracking_speed.unwrap_or(tuning.tracking_speed),
            nominal_dt: config.nominal_dt,
            phases,
            data,
            soles,
            effectors,
            q,
            root: Side::Right,
            world_t_root: IsometryMatrix3::identity(),
            phase: SupportPhase::Double,
            measurements: Measurements {
                com_error: f64::INFINITY,
                posture_error: 0.0,
                posture_settled: false,
                swing_toe_height: 0.0,
                swing_heel_height: 0.0,
            },
            posture_settling: Settling::new(),
            previous_time: None,
            footsteps: FootstepPlanner::new(config.footsteps, area),
            motion: config.motion,
            com_reference: None,
            swing: SwingHeight::at(0.0),
            output,
            profile,
        })
    }

    /// Names of the joint angles of [`RobotFrame::q`] (the model's variable names).
    pub fn variable_names(&self) -> impl Iterator<Item = &str> {
        self.profile
            .model(Side::Right)
            .variables()
            .iter()
            .map(|v| v.name.as_str())
    }

    /// The current phase.
    pub fn phase(&self) -> SupportPhase {
        self.phase
    }

    /// The task table of `phase`.
    pub fn table(&self, phase: SupportPhase) -> &TaskTable {
        &self.phases[phase.index()].table
    }

    /// The task names of `phase`'s table, in stack order.
    pub fn task_names(&self, phase: SupportPhase) -> impl Iterator<Item = String> + '_ {
        self.phases[phase.index()].task_names()
    }

    /// The robot profile (models rooted at either sole, frames, feet).
    pub fn profile(&self) -> &BipedProfile {
        &self.profile
    }

    /// The joint bounds the output respects: position limits, and the rated velocities times
    /// the velocity fraction (legs) or the upper-body velocity fraction (the other joints).
    pub fn bounds(&self) -> &JointBounds {
        &self.bounds
    }

    /// Feet not on their targets (the scaled human footprints) after the last frame: the steps
    /// the robot still has to take (0, 1 or 2).
    pub fn pending_steps(&self) -> usize {
        self.footsteps.steps_pending()
    }

    /// The velocity fraction in use.
    pub fn velocity_fraction(&self) -> f64 {
        self.velocity_fraction
    }

    /// Imitates one human frame: returns the robot's posture for it.
    ///
    /// # Errors
    /// [`ImitationError::TimeGoesBack`] when `frame.time` is below the previous frame's, a
    /// scaler error for a non-finite time or joint, and solver or model errors (never expected
    /// from valid input; the imitator is then in an unspecified but safe state).
    pub fn step(&mut self, frame: &HumanFrame) -> Result<&RobotFrame, ImitationError> {
        let start = Instant::now();
        let dt = self.frame_dt(frame.time)?;
        let human = self.detector.update(frame);
        let feet = [
            ground_pose(&self.output.left_sole),
            ground_pose(&self.output.right_sole),
        ];
        let leg_ratio = self.scaler.leg_ratio();
        let wanted = (self.footsteps).update(frame, human, leg_ratio, feet, self.phase, dt);
        let phase = self.machine.update(wanted, &self.measurements);
        let changed = phase != self.phase || self.previous_time.is_none();
        self.switch_root(self.phases[phase.index()].table.model_root)?;
        self.scale(frame, human)?;
        if changed {
            self.hold_targets(phase);
        }
        let (com_target, goal_distance) = self.shape_references(phase, dt)?;
        self.solve(phase, com_target, dt)?;
        self.measure(phase, changed, goal_distance, dt);
        self.write_output(frame, human, phase)?;
        self.phase = phase;
        self.previous_time = Some(frame.time);
        self.output.micros = start.elapsed().as_secs_f64() * 1e6;
        Ok(&self.output)
    }

    /// The time step ending at `time` (s).
    fn frame_dt(&self, time: f64) -> Result<f64, ImitationError> {
        if !time.is_finite() {
            return Err(ScaleError::NonFiniteTime(time).into());
        }
        match self.previous_time {
            None => Ok(self.nominal_dt),
            Some(previous) if time > previous => Ok(time - previous),
            Some(previous) if time == previous => Ok(self.nominal_dt),
            Some(previous) => Err(ImitationError::TimeGoesBack { time, previous }),
        }
    }

    /// Scales the human frame into the root frame (`output.reference`) and sets the
    /// joint-tracking reference from its joint angles, the legs at their standing posture.
    fn scale(&mut self, frame: &HumanFrame, human: HumanSupport) -> Result<(), ImitationError> {
        let scaled = self.scaler.scale(frame, human)?;
        if let Some(angles) = &mut self.angles {
            angles.compute(scaled.directions(), &mut self.human_q)?;
        }
        for (human, stance) in self.human_q.iter_mut().zip(&self.stance) {
            if let Some(stance) = stance {
                *human = *stance;
            }
        }
        self.tracking.set_reference(&self.human_q)?;
        // The scaler's output frame is the sole of its stance; the model's is the root sole.
        let root = self.root.index();
        let root_t_base = if scaled.base() == self.root {
            IsometryMatrix3::identity()
        } else {
            *self.data[root].frame_placement(self.soles[root][scaled.base().index()])
        };
        for (out, (_, p)) in self.output.reference.iter_mut().zip(scaled.points()) {
            *out = p.map(|p| root_t_base.transform_point(&p.into()).coords);
        }
        Ok(())
    }

    /// The target footprint of the step being taken, in the root frame.
    fn footstep_in_root(&self) -> Option<GroundPose> {
        let (_, world) = self.footsteps.target()?;
        let ground = Vector3::new(world.xy.x, world.xy.y, 0.0);
        let xy = (self.world_t_root.inverse_transform_point(&ground.into()))
            .coords
            .xy();
        Some(GroundPose {
            xy,
            yaw: world.yaw - ground_pose(&self.world_t_root).yaw,
        })
    }

    /// One frame of IK for `phase`: the driver's iterations from the current `q` toward the
    /// frame's targets, with the frame's velocity budget; task errors and the solve report go
    /// into the output.
    fn solve(
        &mut self,
        phase: SupportPhase,
        com_target: Vector2<f64>,
        dt: f64,
    ) -> Result<(), ImitationError> {
        // The velocity budget of the frame, split over its iterations.
        let step_dt = dt / self.iterations as f64;
        let settings = DriverSettings {
            gain: 1.0 / step_dt,
            dt: step_dt,
            max_iterations: self.iterations,
            tolerance: 0.0,
            stall_tolerance: 0.0,
            max_task_error: self.max_task_speed * step_dt,
            max_joint_step: f64::INFINITY,
        };
        let targets = FrameTargets {
            reference: &self.output.reference,
            com: com_target,
            swing_lift: self.swing.height(),
            footstep: self.footstep_in_root(),
            tracking_step: self.max_tracking_speed * step_dt,
        };
        let criteria = Criteria {
            limits: &self.limits,
            tracking: &self.tracking,
        };
        let model = self.profile.model(self.root);
        let data = &mut self.data[self.root.index()];
        let ps = &mut self.phases[phase.index()];
        let report = ps.run(
            model,
            data,
            targets,
            criteria,
            &mut self.q,
            &self.bounds,
            settings,
        )?;
        let out = &mut self.output;
        out.stop = report.stop;
        let errors = report.task_errors();
        out.task_count = errors.len().min(out.task_errors.len());
        out.task_errors[..out.task_count].copy_from_slice(&errors[..out.task_count]);
        out.record_solve(ps.report());
        Ok(())
    }

    /// Measurements for the phase machine after the solve: the CoM's distance to the phase's
    /// goal, the torso's posture error and whether it has settled, the swing foot's heights.
    fn measure(&mut self, phase: SupportPhase, changed: bool, goal_distance: f64, dt: f64) {
        let ps = &self.phases[phase.index()];
        let errors = &self.output.task_errors[..self.output.task_count];
        let posture_error = ps.posture_error(errors);
        if changed {
            self.posture_settling = Settling::new();
        }
        let swing = phase.swing_foot().unwrap_or(self.root.other());
        let [toe, heel] = self.swing_heights(swing, phase);
        self.measurements = Measurements {
            com_error: ps.com_error(errors) + goal_distance,
            posture_error,
            posture_settled: self.posture_settling.update(posture_error, dt),
            swing_toe_height: toe,
            swing_heel_height: heel,
        };
    }

    /// Heights above the ground (m) of the `swing` sole's outline corners, front then rear: the
    /// lowest of each while lifting, else the one farthest from the ground, above or below. A
    /// lift is done when the lowest corner is at ρ, a landing when every corner is on the
    /// ground (flat, so that the foot can become the support without tilting or sinking the
    /// world).
    fn swing_heights(&self, swing: Side, phase: SupportPhase) -> [f64; 2] {
        let root = self.root.index();
        let sole = self.data[root].frame_placement(self.soles[root][swing.index()]);
        let [centre_x, _] = self.profile.sole_centre(swing);
        let lifting = matches!(
            phase,
            SupportPhase::DoubleToRight(TakeOff::LiftFoot)
                | SupportPhase::DoubleToLeft(TakeOff::LiftFoot)
        );
        let pick = |a: f64, b: f64| match lifting {
            true => a.min(b),
            false if a.abs() >= b.abs() => a,
            false => b,
        };
        let outline = &self.profile.foot(swing).outline;
        let height = |front: bool| {
            outline
                .iter()
                .filter(|[x, _]| (*x >= centre_x) == front)
                .map(|&[x, y]| sole.transform_point(&Vector3::new(x, y, 0.0).into()).z)
                .reduce(pick)
                .unwrap_or(0.0)
        };
        [height(true), height(false)]
    }

    /// The world-frame part of the output: soles, CoM, time, posture, phase.
    fn write_output(
        &mut self,
        frame: &HumanFrame,
        human: HumanSupport,
        phase: SupportPhase,
    ) -> Result<(), ImitationError> {
        let root = self.root.index();
        let (model, data) = (self.profile.model(self.root), &self.data[root]);
        let world_t_root = self.world_t_root;
        let placement = |foot: Side| -> Result<IsometryMatrix3<f64>, ModelError> {
            model.placement_in_world(data, &world_t_root, self.soles[root][foot.index()])
        };
        let out = &mut self.output;
        // The driver's last evaluation is at the final q: the forward kinematics are current.
        out.right_sole = placement(Side::Right)?;
        out.left_sole = placement(Side::Left)?;
        out.com = world_t_root
            .transform_point(&model.com(data)?.into())
            .coords;
        out.time = frame.time;
        out.q.copy_from_slice(&self.q);
        out.human_support = human;
        out.human_stance = human_stance(frame);
        out.leg_ratio = self.scaler.leg_ratio();
        for (position, &id) in out.effectors.iter_mut().zip(&self.effectors[root]) {
            *position = data.frame_placement(id).translation.vector;
        }
        out.pending_steps = self.footsteps.steps_pending();
        out.phase = phase;
        out.root = self.root;
        out.world_t_root = world_t_root;
        Ok(())
    }

    /// At the start of a step: the held targets of `phase`'s tasks become the frames' current
    /// positions and headings, and the swing height the swing sole's current height.
    fn hold_targets(&mut self, phase: SupportPhase) {
        let root = self.root.index();
        let data = &self.data[root];
        self.phases[phase.index()].hold(data);
        let swing = phase.swing_foot().unwrap_or(self.root.other());
        let sole = data.frame_placement(self.soles[root][swing.index()]);
        self.swing = SwingHeight::at(sole.translation.vector.z);
    }

    /// Advances the shaped CoM reference toward `phase`'s CoM goal and the swing height toward
    /// its lift. Returns the CoM target for the balance task in the root frame and the distance
    /// (m) the reference still has to go to the goal.
    fn shape_references(
        &mut self,
        phase: SupportPhase,
        dt: f64,
    ) -> Result<(Vector2<f64>, f64), ImitationError> {
        let root = self.root.index();
        let model = self.profile.model(self.root);
        let data = &self.data[root];
        let ps = &self.phases[phase.index()];
        if let Some(lift) = ps.lift() {
            self.swing.advance(lift, dt, &self.motion);
        }
        let Some(goal) = ps.com_goal(data) else {
            return Ok((Vector2::zeros(), 0.0));
        };
        let to_world = |p: Vector2<f64>| {
            self.world_t_root
                .transform_point(&Vector3::new(p.x, p.y, 0.0).into())
                .coords
                .xy()
        };
        let goal_world = to_world(goal);
        let com = to_world(model.com(data)?.xy());
        let reference = self
            .com_reference
            .get_or_insert_with(|| ComReference::at_rest(com));
        reference.advance(goal_world, dt, &self.motion);
        let r = reference.position();
        let target = self
            .world_t_root
            .inverse_transform_point(&Vector3::new(r.x, r.y, 0.0).into())
            .coords
            .xy();
        Ok((target, (goal_world - r).norm()))
    }

    /// Re-roots the model at `foot` if it is not already, keeping the world placement.
    fn switch_root(&mut self, foot: Side) -> Result<(), ImitationError> {
        let from = self.root.index();
        let model = self.profile.model(self.root);
        model.forward_kinematics(&mut self.data[from], &self.q)?;
        if foot != self.root {
            // ʷT_b = ʷT_a · ᵃT_b(q): the new root sole's world placement from the old model.
            let sole = self.soles[from][foot.index()];
            self.world_t_root =
                model.placement_in_world(&self.data[from], &self.world_t_root, sole)?;
            self.root = foot;
        }
        let to = self.root.index();
        self.profile
            .model(self.root)
            .forward_kinematics(&mut self.data[to], &self.q)?;
        Ok(())
    }
}

/// The largest task and level counts over the phases: the output's capacity.
fn phases_sizes(phases: &[PhaseSolver]) -> [usize; 2] {
    let tasks = phases.iter().map(PhaseSolver::task_count).max();
    let levels = phases.iter().map(|p| p.table.levels.len()).max();
    [tasks.unwrap_or(0), levels.unwrap_or(0)]
}

/// The ground pose (sole point, heading) of a sole placement.
fn ground_pose(sole: &IsometryMatrix3<f64>) -> GroundPose {
    let x = sole.rotation * Vector3::x();
    GroundPose {
        xy: sole.translation.vector.xy(),
        yaw: x.y.atan2(x.x),
    }
}

/// Which variables move the left sole relative to the right one (the legs, closing a loop in
/// double support): the columns of the left sole's 6 × n Jacobian in the right-rooted model that
/// are not zero at `q`.
fn sole_chain_variables(profile: &BipedProfile, q: &[f64]) -> Result<Vec<bool>, ImitationError> {
    let model = profile.model(Side::Right);
    let mut data = model.new_data();
    model.forward_kinematics(&mut data, q)?;
    let sole = model.frame_id(&profile.foot(Side::Left).sole)?;
    let mut jac = Mat::zeros(6, model.nv());
    model.point_jacobian(
        &data,
        sole,
        &Vector3::zeros(),
        jac.as_mut().subrows_mut(0, 3),
    )?;
    model.orientation_jacobian(&data, sole, jac.as_mut().subrows_mut(3, 3))?;
    Ok((0..model.nv())
        .map(|k| (0..6).any(|r| jac[(r, k)] != 0.0))
        .collect())
}

/// The human's mid-ankle ground point (xy, m) and hip heading (rad) in `frame`.
fn human_stance(frame: &HumanFrame) -> Option<(Vector2<f64>, f64)> {
    let (l, r) = (
        frame.get(HumanJoint::LAnkle)?,
        frame.get(HumanJoint::RAnkle)?,
    );
    let left = frame.get(HumanJoint::LHip)? - frame.get(HumanJoint::RHip)?;
    Some(((l + r).xy() * 0.5, (-left.x).atan2(left.y)))
}
