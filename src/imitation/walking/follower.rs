//! The walk of the imitation: the human's footprints become footsteps of the pattern generator,
//! and each frame the whole body tracks the generator's CoM and soles ([`super::walking_table`]).

use nalgebra::{IsometryMatrix3, Vector2, Vector3};

use crate::human::Side;
use crate::imitation::error::ImitationError;
use crate::imitation::output::QUEUE_AHEAD;
use crate::imitation::phase::solver::{Criteria, FrameTargets, PhaseSolver, own_joints};
use crate::imitation::phase::{Landing, SupportPhase};
use crate::imitation::walking::footsteps::{FootstepConfig, GroundPose};
use crate::locomotion::footstep::{mean_heading, wrap_angle};
use crate::locomotion::preview::GRAVITY;
use crate::locomotion::schedule::smooth;
use crate::locomotion::{
    Footstep, PatternGenerator, StepPlan, StepTiming, Support, WalkParams, WalkState,
};
use crate::model::{Model, ModelData};
use crate::robots::{BipedProfile, FootArea};
use crate::solver::driver::DriverSettings;
use crate::solver::{JointBounds, Settings};

/// Most solver iterations per frame: the walk's references move smoothly, so a few Gauss–Newton
/// steps meet the feet and the CoM to the solver's precision.
const ITERATIONS: usize = 2;

/// Double support of a step that follows the human, in time constants `1/ω = √(z_c/g)` of the
/// cart-table (NAO: 1.0 s). The generator's own walks take 3/ω; following the human the arms
/// move and the steps turn and side-step, and with 3/ω the judge's NAO let its CoM out of the
/// real contact area 10–17 % of the time on the bundled walks (single-support soles rolling onto
/// an edge) and a loaded foot turned 4–6°; with 6/ω and 4/ω, 0.2–4 % and under 1°.
const FOLLOWING_DOUBLE_SUPPORT: f64 = 6.0;

/// Single support of a step that follows the human, in time constants (NAO: 0.67 s); see
/// [`FOLLOWING_DOUBLE_SUPPORT`].
const FOLLOWING_SINGLE_SUPPORT: f64 = 4.0;

/// Share of a following step's single support at each end in which the swing foot moves only
/// vertically. These steps turn with the human: with the generator's own 5 % (carried over the
/// whole swing, for its straight walks) a loaded NAO foot turned 2.5° on CMU 09_12 as the swing
/// foot turned right after its lift-off; with 15 % the bundled walks pass the judge's both
/// models (turns ≤ 1°).
const FOLLOWING_LIFT_SHARE: f64 = 0.15;

/// A walk's start and stop (the ZMP swinging onto the first stance sole, and back between the
/// feet) when it follows the human, in time constants (NAO: 1.0 s): the generator's own step
/// time before its single support grew to 3.5/ω. With its 6.5/ω the standing foot of a
/// following walk was held to 6e-7 m instead of 6e-10 m (CMU 05_02, 09_12, 131_01).
const FOLLOWING_START_STOP: f64 = 6.0;

/// Sets the timing, swing and start and stop of the steps that follow the human on `params`
/// (the generator's own, derived from the robot).
fn follow_the_human(params: &mut WalkParams) {
    let time_constant = (params.settings.com_height / GRAVITY).sqrt();
    params.timing = StepTiming {
        double_support: FOLLOWING_DOUBLE_SUPPORT * time_constant,
        single_support: FOLLOWING_SINGLE_SUPPORT * time_constant,
    };
    params.settings.swing.lift_share = FOLLOWING_LIFT_SHARE;
    params.settings.start_duration = FOLLOWING_START_STOP * time_constant;
    params.settings.stop_duration = FOLLOWING_START_STOP * time_constant;
}

/// The joints that move the hands of `profile` but not its torso (standing in `q`): the arms.
fn arm_joints(profile: &BipedProfile, q: &[f64]) -> Result<Vec<bool>, ImitationError> {
    let model = profile.model(Side::Right);
    let mut data = model.new_data();
    model.forward_kinematics(&mut data, q)?;
    let [left, right] =
        (profile.hands.clone()).map(|hand| own_joints(model, &data, &hand, &profile.torso));
    Ok((left?.iter().zip(right?)).map(|(&l, r)| l || r).collect())
}

/// The robot's walk toward the scaled human's footprints (see the module docs).
#[derive(Debug)]
pub(in crate::imitation) struct WalkFollower {
    generator: PatternGenerator,
    params: WalkParams,
    /// The walking table's solver of each root, `[left, right]`.
    solvers: [PhaseSolver; 2],
    /// The arm step's solver of each root ([`super::walking_arms_table`], the arm joints
    /// alone), with [`FootstepConfig::walking_arms`].
    arms: Option<[PhaseSolver; 2]>,
    /// The posture at the start of the frame, and the joint bounds within the frame's reach
    /// of it: the arm step uses what the walking solve left of the frame's velocity budget.
    frame_start: Vec<f64>,
    reach: JointBounds,
    /// The joint bounds of a walking frame: the legs at the walking velocity fraction.
    bounds: JointBounds,
    envelope: FootArea,
    /// A foot closer to its goal than this (m, rad) does not step.
    near: (f64, f64),
    /// The robot's time (s) when the walk started; `None` while standing.
    started: Option<f64>,
    /// Walk time (s) of the last touchdown (−∞ before the walk's first).
    landed_at: f64,
    /// Walk time (s) of `state`.
    elapsed: f64,
    /// The CoM's height at the start (m): brought to the walking height over the first double
    /// support.
    start_height: f64,
    root: Side,
    /// The generator's state at the tick before its last.
    previous: WalkState,
    /// The walk at the frame's time, between `previous` and the generator's state.
    state: WalkState,
    /// The posture at the start of the walk: the joint-tracking reference while walking.
    posture: Vec<f64>,
    /// The foot of the last step queued in this walk.
    last_side: Option<Side>,
    /// The steps planned this frame (room for [`QUEUE_AHEAD`]).
    planned: Vec<Footstep>,
    /// The distance between the soles standing in the initial posture (m).
    stance_width: f64,
    /// Half the distance between the soles at the start (m): the torso leans fully when the
    /// CoM is this far from their middle.
    half_span: f64,
}

impl WalkFollower {
    /// A follower for `profile` standing in `q`: the generator's settings from the profile
    /// ([`WalkParams::for_profile`]), steps within `envelope`, a foot within `config`'s
    /// distance and heading of its goal left where it is; `bounds` the walking frames' joint
    /// bounds.
    pub(in crate::imitation) fn new(
        profile: &BipedProfile,
        q: &[f64],
        settings: Settings,
        envelope: FootArea,
        config: &FootstepConfig,
        bounds: JointBounds,
    ) -> Result<Self, ImitationError> {
        let mut params = WalkParams::for_profile(profile)?;
        follow_the_human(&mut params);
        let stance_width = {
            let model = profile.model(Side::Right);
            let mut data = model.new_data();
            model.forward_kinematics(&mut data, q)?;
            let left = model.frame_id(&profile.foot(Side::Left).sole)?;
            data.frame_placement(left).translation.vector.xy().norm()
        };
        let origin = GroundPose::new(0.0, 0.0, 0.0);
        let generator = PatternGenerator::new(
            params.settings,
            params.centres.clone(),
            [origin; 2],
            Vector2::zeros(),
        )?;
        let solver = |root| {
            let table = super::walking_table(root, profile);
            // When a velocity bound binds, the whole step slows down and keeps its priorities
            // (see `walking_table` for what holding the bound joint instead did).
            let settings = Settings {
                scale_to_fit: true,
                ..settings
            };
            PhaseSolver::new(&table, profile, q, settings)
        };
        let arms = match config.walking_arms {
            true => {
                let joints = arm_joints(profile, q)?;
                let arms = |root| {
                    let table = super::walking_arms_table(root, profile);
                    PhaseSolver::restricted(&table, profile, q, settings, joints.clone())
                };
                Some([arms(Side::Left)?, arms(Side::Right)?])
            }
            false => None,
        };
        Ok(Self {
            previous: *generator.state(),
            state: *generator.state(),
            generator,
            params,
            solvers: [solver(Side::Left)?, solver(Side::Right)?],
            arms,
            frame_start: q.to_vec(),
            reach: bounds.clone(),
            bounds,
            envelope,
            near: (config.distance, config.heading),
            started: None,
            landed_at: f64::NEG_INFINITY,
            elapsed: 0.0,
            start_height: 0.0,
            root: Side::Right,
            posture: q.to_vec(),
            last_side: None,
            planned: Vec::with_capacity(QUEUE_AHEAD),
            half_span: 0.0,
            stance_width,
        })
    }

    /// The footsteps not yet landed, the one under way first (world frame).
    pub(in crate::imitation) fn queued_steps(&self) -> impl Iterator<Item = Footstep> + '_ {
        self.generator.queued_steps().map(|(_, _, step)| *step)
    }

    /// Whether the robot is walking.
    pub(in crate::imitation) fn is_walking(&self) -> bool {
        self.started.is_some()
    }

    /// The joint bounds of walking frames.
    pub(in crate::imitation) fn bounds(&self) -> &JointBounds {
        &self.bounds
    }

    /// The sole the model is rooted at: the stance sole.
    pub(in crate::imitation) fn root(&self) -> Side {
        self.root
    }

    /// The walk at the last frame's time.
    pub(in crate::imitation) fn state(&self) -> &WalkState {
        &self.state
    }

    /// The posture the walk started from (rad).
    pub(in crate::imitation) fn start_posture(&self) -> &[f64] {
        &self.posture
    }

    /// The walking table's solver of the current root.
    pub(in crate::imitation) fn solver(&self) -> &PhaseSolver {
        &self.solvers[self.root.index()]
    }

    /// The support phase the walk is in: a sole landed less than
    /// [`WalkParams::landing_preload_time`] ago is still being lowered onto the floor (the
    /// landing clearance), so the phase is the paper's "lower foot" step until then.
    pub(in crate::imitation) fn phase(&self) -> SupportPhase {
        match self.state.support {
            Support::Double if self.is_lowering() => match self.root {
                Side::Right => SupportPhase::RightToDouble(Landing::LowerFoot),
                Side::Left => SupportPhase::LeftToDouble(Landing::LowerFoot),
            },
            Support::Double => SupportPhase::Double,
            Support::Single {
                swing: Side::Left, ..
            } => SupportPhase::Right,
            Support::Single {
                swing: Side::Right, ..
            } => SupportPhase::Left,
        }
    }

    /// Starts a walk at robot time `now` (s) from the soles at `feet` (`[left, right]`, world,
    /// on the floor z = 0) with the CoM at `com` (world), the model rooted at `root`.
    pub(in crate::imitation) fn start(
        &mut self,
        now: f64,
        feet: [GroundPose; 2],
        com: Vector3<f64>,
        root: Side,
        q: &[f64],
    ) -> Result<(), ImitationError> {
        self.generator.restart(feet, com.xy())?;
        self.posture.clear();
        self.posture.extend_from_slice(q);
        self.previous = *self.generator.state();
        self.state = self.previous;
        self.started = Some(now);
        self.root = root;
        self.start_height = com.z;
        self.landed_at = f64::NEG_INFINITY;
        self.elapsed = 0.0;
        self.last_side = None;
        self.half_span = (feet[0].xy - feet[1].xy).norm() / 2.0;
        Ok(())
    }

    /// Whether the soles standing at `feet` (`[left, right]`, world) would step toward `goals`.
    /// Allocates nothing.
    pub(in crate::imitation) fn has_steps(
        &mut self,
        feet: &[GroundPose; 2],
        goals: &[GroundPose; 2],
    ) -> bool {
        self.plan(feet, goals, None, QUEUE_AHEAD);
        !self.planned.is_empty()
    }

    /// How many feet still have to step (0, 1 or 2): those of the queued steps while walking;
    /// standing at `feet` (`[left, right]`, world), those the walk would move toward `goals`
    /// (none without goals). This, not the support phases' distance to the raw footprints, says
    /// whether the robot has arrived: the walk's goals stand at the robot's own width
    /// ([`WalkFollower::at_width`]) and within the step envelope. Allocates nothing.
    pub(in crate::imitation) fn feet_to_step(
        &mut self,
        feet: &[GroundPose; 2],
        goals: Option<&[GroundPose; 2]>,
    ) -> usize {
        let mut moves = [false; 2];
        if self.is_walking() {
            for step in self.generator.queued_steps().map(|(_, _, step)| step) {
                moves[step.side.index()] = true;
            }
        } else if let Some(goals) = goals {
            self.plan(feet, goals, None, QUEUE_AHEAD);
            for step in &self.planned {
                moves[step.side.index()] = true;
            }
            self.planned.clear();
        }
        moves.iter().filter(|&&m| m).count()
    }

    /// Queues the steps toward `goals` (`[left, right]`, world) the generator does not have
    /// yet and runs it to robot time `now` (s). Returns whether the walk is over: every step
    /// landed, the CoM at rest, nothing left to step to. Allocates nothing.
    pub(in crate::imitation) fn advance(
        &mut self,
        now: f64,
        goals: Option<[GroundPose; 2]>,
    ) -> Result<bool, ImitationError> {
        let Some(started) = self.started else {
            return Ok(true);
        };
        if let Some(goals) = goals {
            self.refill(&goals)?;
        }
        let elapsed = now - started;
        while self.generator.state().time < elapsed {
            self.previous = *self.generator.state();
            self.generator.tick();
        }
        let was_single = matches!(self.state.support, Support::Single { .. });
        self.state = between(&self.previous, self.generator.state(), elapsed);
        self.elapsed = elapsed;
        if was_single && matches!(self.state.support, Support::Double) {
            self.landed_at = elapsed;
        }
        if let Support::Single { swing, .. } = self.state.support {
            self.root = swing.other();
        }
        // A walk ends with its last sole on the floor: lowered through the landing clearance.
        let over = self.generator.is_stopped() && self.planned.is_empty() && !self.is_lowering();
        if over {
            self.started = None;
        }
        Ok(over)
    }

    /// Plans up to [`QUEUE_AHEAD`] queued steps from where the queue ends toward `goals`; a
    /// foot near its goal stays. The feet alternate after the last queued step.
    fn refill(&mut self, goals: &[GroundPose; 2]) -> Result<(), ImitationError> {
        self.planned.clear();
        let queued = self.generator.queued();
        if queued >= QUEUE_AHEAD {
            return Ok(());
        }
        let from = *self.generator.planned_feet();
        self.plan(
            &from,
            goals,
            self.last_side.map(Side::other),
            QUEUE_AHEAD - queued,
        );
        for step in &self.planned {
            self.generator.push(*step)?;
            self.last_side = Some(step.side);
        }
        Ok(())
    }

    /// Fills `planned` with up to `max_steps` steps from `from` toward `goals` at the standing
    /// width ([`WalkFollower::at_width`]), `first` moving first (`None`: the leading foot); a
    /// foot near its goal stays.
    fn plan(
        &mut self,
        from: &[GroundPose; 2],
        goals: &[GroundPose; 2],
        first: Option<Side>,
        max_steps: usize,
    ) {
        let goals = &self.at_width(goals);
        let goal = [0, 1].map(|i| match self.is_near(&from[i], &goals[i]) {
            true => from[i],
            false => goals[i],
        });
        let plan = StepPlan {
            envelope: &self.envelope,
            timing: self.params.timing,
            first,
            max_steps,
            min_move: GroundPose::new(self.near.0, 0.0, self.near.1),
            alternate: first.is_some(),
        };
        plan.fill(from, &goal, &mut self.planned);
    }

    /// `goals` with the soles `stance_width` apart across their mean heading, about their
    /// middle; each keeps its place along the heading and its own heading. The human's stance
    /// width changes from step to step, and steps wider than the robot's standing width left
    /// its CoM short of the stance sole (the judge's NAO fell; not at the standing width); a
    /// side step moves the middle and is kept.
    fn at_width(&self, goals: &[GroundPose; 2]) -> [GroundPose; 2] {
        let [l, r] = *goals;
        let mid = GroundPose {
            xy: (l.xy + r.xy) / 2.0,
            yaw: mean_heading(l.yaw, r.yaw),
        };
        let half = self.stance_width / 2.0;
        let place = |g: GroundPose, side: f64| {
            let local = mid.to_local(g.xy);
            GroundPose {
                xy: mid.to_world([local.x, side * half]),
                yaw: g.yaw,
            }
        };
        [place(l, 1.0), place(r, -1.0)]
    }

    fn is_near(&self, a: &GroundPose, b: &GroundPose) -> bool {
        (a.xy - b.xy).norm() <= self.near.0 && wrap_angle(a.yaw - b.yaw).abs() <= self.near.1
    }

    /// The walk's part of a frame's targets in the frame of the root sole placed at
    /// `world_t_root`: the CoM's ground point, the other sole's planned footprint and height,
    /// the torso's up direction, the CoM's height.
    pub(in crate::imitation) fn targets(
        &self,
        world_t_root: &IsometryMatrix3<f64>,
        now: f64,
    ) -> WalkTargets {
        let walk = &self.state;
        let to_root = |p: Vector3<f64>| world_t_root.inverse_transform_point(&p.into()).coords;
        let root_yaw = crate::imitation::state::ground_pose(world_t_root).yaw;
        let sole = walk.feet[self.root.other().index()];
        let [x, y, z] = sole.position;
        let up = walk.torso_up(self.params.torso_lean, self.half_span, root_yaw);
        let elapsed = self.started.map_or(0.0, |s| now - s);
        let share = (elapsed / self.params.settings.start_duration).clamp(0.0, 1.0);
        let z = z + self.landing_clearance();
        WalkTargets {
            com: to_root(Vector3::new(walk.com.x, walk.com.y, 0.0)).xy(),
            footstep: GroundPose {
                xy: to_root(Vector3::new(x, y, 0.0)).xy(),
                yaw: wrap_angle(sole.yaw - root_yaw),
            },
            swing_lift: z,
            up,
            com_height: self.start_height
                + (walk.com.z - self.start_height) * share * share * (3.0 - 2.0 * share),
        }
    }

    /// How far above its plan the moving sole is held at this point of the walk (m): the
    /// landing clearance ([`WalkParams::landing_clearance`]), reached over the second half of a
    /// swing and given up over [`WalkParams::landing_preload_time`] after the touchdown.
    fn landing_clearance(&self) -> f64 {
        let clearance = self.params.landing_clearance;
        match self.state.support {
            Support::Single { phase, .. } => clearance * smooth((phase - 0.5) / 0.5),
            Support::Double => {
                let lowered = (self.elapsed - self.landed_at) / self.params.landing_preload_time;
                clearance * (1.0 - smooth(lowered))
            }
        }
    }

    /// Whether a landed sole is still being lowered through the landing clearance.
    fn is_lowering(&self) -> bool {
        self.elapsed - self.landed_at < self.params.landing_preload_time
    }

    /// The time step (s) of one solver iteration of a frame of `dt` seconds.
    pub(in crate::imitation) fn iteration_dt(&self, dt: f64) -> f64 {
        dt / ITERATIONS as f64
    }

    /// One frame of IK from `q` (updated in place) toward `targets`, within the walking bounds
    /// over the frame's time step `dt` (s).
    #[allow(clippy::too_many_arguments)] // the frame's inputs, each from a different owner
    pub(in crate::imitation) fn solve(
        &mut self,
        model: &Model,
        data: &mut ModelData,
        targets: FrameTargets<'_>,
        criteria: Criteria<'_>,
        q: &mut [f64],
        dt: f64,
    ) -> Result<(), ImitationError> {
        let step_dt = self.iteration_dt(dt);
        let settings = DriverSettings {
            gain: 1.0 / step_dt,
            dt: step_dt,
            max_iterations: ITERATIONS,
            tolerance: 1e-7,
            stall_tolerance: 1e-10,
            max_task_error: f64::INFINITY,
            max_joint_step: f64::INFINITY,
            patience: 0,
        };
        self.frame_start.copy_from_slice(q);
        let solver = &mut self.solvers[self.root.index()];
        solver.run(model, data, targets, criteria, q, &self.bounds, settings)?;
        let Some(arms) = &mut self.arms else {
            return Ok(());
        };
        // The arms, alone, with what the walking solve left of the frame's velocity budget.
        self.reach
            .copy_within_reach(&self.bounds, &self.frame_start, dt);
        let settings = DriverSettings {
            gain: 1.0 / dt,
            dt,
            max_iterations: 1,
            tolerance: 0.0,
            stall_tolerance: 0.0,
            ..settings
        };
        let arms = &mut arms[self.root.index()];
        arms.run(model, data, targets, criteria, q, &self.reach, settings)
    }
}

/// What the walk asks of a frame, in the root sole's frame (m, rad).
#[derive(Debug, Clone, Copy)]
pub(in crate::imitation) struct WalkTargets {
    /// The CoM's ground point.
    pub(in crate::imitation) com: Vector2<f64>,
    /// The other sole's ground point and heading.
    pub(in crate::imitation) footstep: GroundPose,
    /// The other sole's height above the floor.
    pub(in crate::imitation) swing_lift: f64,
    /// The torso's up direction.
    pub(in crate::imitation) up: Vector3<f64>,
    /// The CoM's height above the floor.
    pub(in crate::imitation) com_height: f64,
}

/// The walk at `time` (s), linearly between the states `a` and `b` of two successive ticks
/// (`a` itself before the first tick): the generator's 10 ms ticks sampled at any frame rate
/// without a staircase.
fn between(a: &WalkState, b: &WalkState, time: f64) -> WalkState {
    let span = b.time - a.time;
    if span <= 0.0 {
        return *b;
    }
    let s = ((time - a.time) / span).clamp(0.0, 1.0);
    let lerp = |x: f64, y: f64| x + (y - x) * s;
    let mut out = *b;
    out.time = lerp(a.time, b.time);
    out.com = a.com.lerp(&b.com, s);
    out.com_velocity = a.com_velocity.lerp(&b.com_velocity, s);
    out.com_acceleration = a.com_acceleration.lerp(&b.com_acceleration, s);
    out.zmp = a.zmp.lerp(&b.zmp, s);
    out.zmp_reference = a.zmp_reference.lerp(&b.zmp_reference, s);
    for (o, (p, q)) in out.feet.iter_mut().zip(a.feet.iter().zip(&b.feet)) {
        o.position = [0, 1, 2].map(|k| lerp(p.position[k], q.position[k]));
        o.yaw = p.yaw + wrap_angle(q.yaw - p.yaw) * s;
    }
    if s < 0.5 {
        out.support = a.support;
    }
    out
}
