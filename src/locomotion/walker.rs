//! A whole robot walking a footstep queue: the pattern generator's CoM and swing sole tracked by
//! the task-stack solver.
//!
//! Each tick the model is rooted at the stance sole (at the sole that last stood alone while both
//! stand), placed where the generator put it in the world, and the driver solves, in priority
//! order: the other sole's pose (held on the floor, or on its swing path), the CoM's ground
//! point, the torso's tilt (upright, leaning over the stance hip) and the chest's on a robot with
//! a waist ([`BipedProfile::chest`]), the CoM's height; the standing posture pulls the remaining
//! freedom (the arms, the torso's heading). A sole on the floor is the model's root or a
//! top-level task, so it does not move in the plan.
//!
//! The chest is held as the imitation's tables hold it: left to the posture pull, the G1's waist
//! carried the CoM sideways (waist roll at its 0.52 rad limit before the first lift with the CoM
//! 10 cm lower, 0.28 rad at the lift at the standing height), and the upper body swung over the
//! stance foot as the swing foot rose.

use nalgebra::{IsometryMatrix3, Rotation3, Translation3, Vector2, Vector3};
use thiserror::Error;

use super::LocomotionError;
use super::footstep::{Footstep, GroundPose};
use super::generator::{PatternGenerator, WalkState};
use super::multibody::MultibodyZmp;
use super::params::{WalkParams, standing_feet};
use super::schedule::Support;
use super::schedule::smooth;
use super::swing::SolePose;
use crate::human::Side;
use crate::model::{FrameId, Model, ModelData, ModelError};
use crate::robots::servo::{LoadedSoles, ServoSag, other_sole_load};
use crate::robots::{BipedProfile, ProfileError};
use crate::solver::SolverError;
use crate::solver::driver::{DriverSettings, PositionDriver};
use crate::solver::{JointBounds, Solver};
use crate::tasks::TaskError;
use crate::tasks::{ComTask, PoseTask, Task, TaskSet, UprightTask};

/// Errors of a [`WholeBodyWalker`]: its pattern generator's, or of the whole-body solve (a
/// non-finite number, a frame or task the robot's profile does not have). Each wraps the error
/// it came from, message unchanged.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum WalkerError {
    /// The pattern generator refused a setting or a step.
    #[error(transparent)]
    Locomotion(#[from] LocomotionError),
    /// The solver refused the stack or its numbers.
    #[error(transparent)]
    Solver(#[from] SolverError),
    /// The kinematic model refused the posture.
    #[error(transparent)]
    Model(#[from] ModelError),
    /// A task could not be built or set.
    #[error(transparent)]
    Task(#[from] TaskError),
    /// The robot's profile lacks what the walker needs.
    #[error(transparent)]
    Profile(#[from] ProfileError),
}

/// Gain of the pull toward the standing posture (per driver iteration).
const POSTURE_GAIN: f64 = 0.05;

/// The solver of one root: its task set and buffers.
#[derive(Debug)]
struct RootedStack<'p> {
    set: TaskSet<'p>,
    solver: Solver,
    driver: PositionDriver,
}

/// One tick of a walk: the generator's state and the joint angles that realise it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WalkerFrame {
    /// The pattern generator's state (world frame).
    pub walk: WalkState,
    /// The sole the model is rooted at.
    pub root: Side,
    /// Error norm of the other sole's pose task after the solve (m and rad stacked).
    pub foot_error: f64,
    /// Error norm of the CoM task after the solve (m).
    pub com_error: f64,
    /// The whole body's ZMP (world, m; [`super::multibody`]) of the tick *before* this one: it
    /// needs the posture after it. `None` on the first two ticks.
    pub previous_zmp: Option<Vector2<f64>>,
}

/// A biped walking footsteps (see the module docs). Borrows its profile.
#[derive(Debug)]
pub struct WholeBodyWalker<'p> {
    profile: &'p BipedProfile,
    params: WalkParams,
    generator: PatternGenerator,
    stacks: [RootedStack<'p>; 2],
    bounds: JointBounds,
    q: Vec<f64>,
    root: Side,
    frame: WalkerFrame,
    /// Half the distance between the soles standing (m).
    half_span: f64,
    /// The servos' static sag, when the profile states their stiffness.
    servo: Option<ServoSag>,
    /// Forward kinematics of each rooted model for the servo targets.
    data: [ModelData; 2],
    /// `[root sole, other sole]` of the model rooted at each side.
    soles: [[FrameId; 2]; 2],
    servo_targets: Vec<f64>,
    zmp: MultibodyZmp,
}

impl<'p> WholeBodyWalker<'p> {
    /// The robot standing in `profile.stand` with its right sole at `right` (world) and the
    /// settings `params` (usually [`WalkParams::for_profile`]). The first steps lower the CoM
    /// from its standing height to the walking height over the start double support.
    ///
    /// # Errors
    /// Model, task, solver and generator errors of the set-up.
    pub fn new(
        profile: &'p BipedProfile,
        params: WalkParams,
        right: GroundPose,
    ) -> Result<Self, WalkerError> {
        let (feet, com_xy) = standing_feet(profile, &right)?;
        let generator =
            PatternGenerator::new(params.settings, params.centres.clone(), feet, com_xy)?;
        let stacks = [
            rooted_stack(profile, Side::Left)?,
            rooted_stack(profile, Side::Right)?,
        ];
        let bounds = crate::tasks::joint_bounds(profile.model(Side::Right))?;
        let state = *generator.state();
        let half_span = (feet[0].xy - feet[1].xy).norm() / 2.0;
        let sole = |root: Side, side: Side| profile.model(root).frame_id(&profile.foot(side).sole);
        let soles = [
            [
                sole(Side::Left, Side::Left)?,
                sole(Side::Left, Side::Right)?,
            ],
            [
                sole(Side::Right, Side::Right)?,
                sole(Side::Right, Side::Left)?,
            ],
        ];
        let zmp = MultibodyZmp::new(profile.model(Side::Right), params.settings.dt)?;
        let mut walker = Self {
            profile,
            params,
            generator,
            stacks,
            bounds,
            q: profile.stand.clone(),
            root: Side::Right,
            frame: WalkerFrame {
                walk: state,
                root: Side::Right,
                foot_error: 0.0,
                com_error: 0.0,
                previous_zmp: None,
            },
            half_span,
            servo: ServoSag::new(profile),
            data: profile.models.each_ref().map(Model::new_data),
            soles,
            servo_targets: profile.stand.clone(),
            zmp,
        };
        walker.update_servo_targets(LoadedSoles::Both)?;
        Ok(walker)
    }

    /// The pattern generator (its queue, settings and state).
    pub fn generator(&self) -> &PatternGenerator {
        &self.generator
    }

    /// The derived parameters it walks with.
    pub fn params(&self) -> &WalkParams {
        &self.params
    }

    /// The joint angles of the last tick (rad, model variable order).
    pub fn q(&self) -> &[f64] {
        &self.q
    }

    /// What to command position servos after the last tick (rad, model variable order): its
    /// joint angles plus their static sag ([`crate::robots::servo`]); the angles themselves
    /// when the profile states no servo stiffness.
    pub fn servo_targets(&self) -> &[f64] {
        &self.servo_targets
    }

    /// Queues a step (see [`PatternGenerator::push`]); returns its landing time (s).
    ///
    /// # Errors
    /// The generator's refusal ([`LocomotionError`]).
    pub fn push(&mut self, step: Footstep) -> Result<f64, LocomotionError> {
        self.generator.push(step)
    }

    /// Advances one tick: the generator, then the IK of the whole body.
    ///
    /// # Errors
    /// Solver and model errors (non-finite numbers).
    pub fn tick(&mut self) -> Result<&WalkerFrame, WalkerError> {
        let walk = *self.generator.tick();
        if let Support::Single { swing, .. } = walk.support {
            self.root = swing.other();
        }
        let root = self.root;
        let root_pose = self.generator.standing_feet()[root.index()];
        let other = walk.feet[root.other().index()];
        let com_height = self.com_height(walk.time);
        let stack = &mut self.stacks[root.index()];
        let other_name = &self.profile.foot(root.other()).sole;
        stack.set.task_mut::<PoseTask>(other_name)?.target = local_pose(&root_pose, &other);
        let com_local = root_pose.to_local(walk.com.xy());
        let com_target = Vector3::new(com_local.x, com_local.y, com_height);
        stack.set.task_mut::<ComTask>("com")?.target = com_target;
        stack.set.task_mut::<ComTask>("com height")?.target = com_target;
        let up = walk.torso_up(self.params.torso_lean, self.half_span, root_pose.yaw);
        stack.set.task_mut::<UprightTask>("torso")?.set_up(up)?;
        if self.profile.chest.is_some() {
            stack.set.task_mut::<UprightTask>("chest")?.set_up(up)?;
        }
        let report =
            stack
                .driver
                .run(&mut stack.solver, &mut stack.set, &mut self.q, &self.bounds)?;
        let errors = report.task_errors();
        let (foot_error, com_error) = (errors[0], errors[1]);
        let loaded = match walk.support {
            Support::Single { .. } => LoadedSoles::Root,
            Support::Double => LoadedSoles::Both,
        };
        self.update_servo_targets(loaded)?;
        let previous_zmp = self.push_zmp(&root_pose)?;
        self.frame = WalkerFrame {
            walk,
            root,
            foot_error,
            com_error,
            previous_zmp,
        };
        Ok(&self.frame)
    }

    /// The whole-body ZMP of the previous tick, `q` standing on the root sole at `root_pose`.
    fn push_zmp(&mut self, root_pose: &GroundPose) -> Result<Option<Vector2<f64>>, WalkerError> {
        let base = IsometryMatrix3::from_parts(
            Translation3::new(root_pose.xy.x, root_pose.xy.y, 0.0),
            Rotation3::from_axis_angle(&Vector3::z_axis(), root_pose.yaw),
        );
        let (model, data) = (self.profile.model(self.root), &self.data[self.root.index()]);
        Ok(self.zmp.push(model, data, &base, &self.q)?)
    }

    /// The servo targets of `q` in the root's model with `loaded` soles (and that model's
    /// forward kinematics at `q`).
    fn update_servo_targets(&mut self, loaded: LoadedSoles) -> Result<(), WalkerError> {
        let (model, data) = (
            self.profile.model(self.root),
            &mut self.data[self.root.index()],
        );
        model.forward_kinematics(data, &self.q)?;
        let Some(servo) = &mut self.servo else {
            self.servo_targets.copy_from_slice(&self.q);
            return Ok(());
        };
        let load = other_sole_load(model, data, self.soles[self.root.index()], loaded)?;
        servo.targets(
            model,
            data,
            load.as_slice(),
            &self.q,
            &mut self.servo_targets,
        )?;
        Ok(())
    }

    /// The CoM height at `time` (m): from standing down to the walking height over the start
    /// time, then constant.
    fn com_height(&self, time: f64) -> f64 {
        let share = smooth(time / self.params.settings.start_duration);
        let (stand, walk) = (
            self.params.standing_com_height,
            self.params.settings.com_height,
        );
        stand + (walk - stand) * share
    }
}

/// The task stack of the model rooted at `root`: the other sole, the CoM's ground point, the
/// torso's tilt (and the chest's, when the profile has one), the CoM's height. The torso's
/// heading is left free: held too, it took a freedom the NAO's coupled hips need, the CoM task
/// then swung the arms, and turning walks fell in physics. The height comes last: the legs
/// alone cannot always keep it.
fn rooted_stack(profile: &BipedProfile, root: Side) -> Result<RootedStack<'_>, WalkerError> {
    let model = profile.model(root);
    let other = PoseTask::new(
        model,
        &profile.foot(root.other()).sole,
        IsometryMatrix3::identity(),
    )?;
    let com = ComTask::ground(model, [0.0, 0.0])?;
    let height = ComTask::new(model, Vector3::zeros())?.named("com height");
    let mut posture: Vec<Box<dyn Task>> = vec![Box::new(
        UprightTask::new(model, &profile.torso)?.named("torso"),
    )];
    if let Some(chest) = &profile.chest {
        posture.push(Box::new(UprightTask::new(model, chest)?.named("chest")));
    }
    let set = TaskSet::new(model)
        .level("foot", vec![Box::new(other)])
        .level("com", vec![Box::new(com)])
        .level("torso", posture)
        .level("com height", vec![Box::new(height)])
        .posture_gradient(POSTURE_GAIN, &profile.stand)?;
    let solver = Solver::new(&set.shape())?;
    let settings = DriverSettings {
        tolerance: 1e-7,
        stall_tolerance: 1e-10,
        max_iterations: 20,
        ..DriverSettings::default()
    };
    let driver = PositionDriver::new(&solver, settings)?;
    Ok(RootedStack {
        set,
        solver,
        driver,
    })
}

/// `sole` (world) in the frame of the root sole standing at `root` (m, rad).
fn local_pose(root: &GroundPose, sole: &SolePose) -> IsometryMatrix3<f64> {
    let xy = root.to_local(Vector2::new(sole.position[0], sole.position[1]));
    IsometryMatrix3::from_parts(
        Translation3::new(xy.x, xy.y, sole.position[2]),
        Rotation3::from_axis_angle(&Vector3::z_axis(), sole.yaw - root.yaw),
    )
}
