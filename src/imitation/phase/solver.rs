//! The per-phase solver of the imitator: a phase's task table resolved against the model rooted
//! at its support sole ([`PhaseSolver`]), and the task model the position-level driver evaluates
//! at each iteration: the table's rows, written with the ready-made rows of [`crate::tasks`]
//! toward the frame's shaped references ([`FrameTargets`]), then the gradient tasks.

use faer::MatMut;
use nalgebra::{Rotation3, Vector2, Vector3};

use crate::human::{HumanJoint, Side};
use crate::imitation::error::ImitationError;
use crate::imitation::phase::tables::{
    Axes, ComGoal, Constraint, Gradient, GradientKind, OrientationTarget, PointTarget, Task,
    TaskTable,
};
use crate::imitation::phase::zmp_balance::SupportZmp;
use crate::imitation::walking::footsteps::GroundPose;
use crate::model::{Axis, FrameId, Model, ModelData};
use crate::robots::BipedProfile;
use crate::solver::driver::{DriverReport, DriverSettings, PositionDriver, TaskModel};
use crate::solver::{
    JointBounds, JointLimitAvoidance, JointTracking, Settings, SolveReport, Solver, SolverError,
    StackShape, TaskStack,
};
use crate::tasks::{
    CapsuleDistanceTask, FramePoint, InequalityTask, com_error, com_rows, orientation_error,
    orientation_rows, point_error, point_rows, upright_error, upright_rows,
};

/// Residual of the contact step's linear system (m and rad, the rows' units) above which a
/// second step over both legs takes the rest.
const CONTACT_RESIDUAL: f64 = 1e-9;

/// Contact error (m and rad) left after the contact step above which another step follows.
const SETTLED_CONTACT: f64 = 1e-7;

/// Most contact steps after the first in one frame (each a solve of the contact level and
/// forward kinematics): a bound on the frame's time.
const CONTACT_STEPS: usize = 3;

/// A task of a table, resolved against a model: frame, axes, where its rows are.
#[derive(Debug, Clone)]
struct ResolvedTask {
    task: Task,
    /// The tracked point (the frame's origin for orientation tasks); `None` for the CoM.
    point: Option<FramePoint>,
    /// The tracked axes of a point task, in row order (first `rows` entries).
    axes: [Axis; 3],
    rows: usize,
    level: usize,
    row: usize,
    /// Height of the point above the ground when its foot is flat (q = 0), m.
    rest_height: f64,
    /// Position of the point in the initial posture, root frame (m).
    standing: Vector3<f64>,
    /// Held target (the point's position when the step began), m, root frame.
    held: Vector3<f64>,
    /// Held heading (yaw of the frame's x axis when the step began), rad, root frame.
    held_yaw: f64,
    /// The joints the task may move ([`balance_joints`] for the CoM); `None`: all.
    joints: Option<Vec<bool>>,
}

/// A constraint of a table, resolved against a model: its rows and where they are.
#[derive(Debug, Clone)]
struct ResolvedConstraint {
    rows: ConstraintRows,
    level: usize,
    /// First row among the level's inequality rows.
    row: usize,
}

/// The rows of a constraint.
#[derive(Debug, Clone)]
enum ConstraintRows {
    Distance(CapsuleDistanceTask),
    Zmp(Box<SupportZmp>),
}

/// What the tasks of a phase aim at in one frame, in the model root's frame.
#[derive(Debug, Clone, Copy)]
pub(crate) struct FrameTargets<'a> {
    /// The scaled human (m): the targets of the `Scaled` points.
    pub(crate) reference: &'a [Option<Vector3<f64>>; HumanJoint::COUNT],
    /// The shaped CoM ground projection (m).
    pub(crate) com: Vector2<f64>,
    /// The shaped swing height (m) that replaces the lift of `Held` targets.
    pub(crate) swing_lift: f64,
    /// The swing foot's target footprint, while the robot steps.
    pub(crate) footstep: Option<GroundPose>,
    /// The hands' targets (`[left, right]`, m): the scaled human's hands within the arms'
    /// reach ([`crate::imitation::reach::Arm::within_reach`]); the targets of the `Scaled` hand points.
    pub(crate) hands: [Option<Vector3<f64>>; 2],
    /// Largest error (m) a task following the scaled human asks for in one iteration, the
    /// hands' excepted.
    pub(crate) tracking_step: f64,
    /// The same for each hand's task (`[left, right]`) following the human (m). A hand placed
    /// on a surface moves at the task speed, as the feet do.
    pub(crate) hand_steps: [f64; 2],
    /// The hands' contact points (`[left, right]`) while they are placed or held as supports.
    pub(crate) hand_contacts: [Option<Vector3<f64>>; 2],
    /// The walk's up direction of the torso (unit): the target of
    /// [`OrientationTarget::Leaning`].
    pub(crate) up: Vector3<f64>,
    /// The CoM's height above the root sole (m): the target of [`Task::ComHeight`].
    pub(crate) com_height: f64,
    /// The share of [`PointTarget::Standing`]'s lowering asked for, in [0, 1]: below 1 at the
    /// start ([`crate::imitation::shaping::StartRamp`]).
    pub(crate) lowering_share: f64,
    /// The joints' velocity over the frame before (per second, one per model variable): the
    /// start of the frame's acceleration for a [`Constraint::Zmp`]; empty when the table has
    /// none.
    pub(crate) joint_velocity: &'a [f64],
}

/// The gradient criteria of the imitator, shared by every phase.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Criteria<'a> {
    pub(crate) limits: &'a JointLimitAvoidance,
    pub(crate) tracking: &'a JointTracking,
}

/// Everything one phase needs: its table resolved, a solver and a driver sized for it.
#[derive(Debug)]
pub(crate) struct PhaseSolver {
    pub(crate) table: TaskTable,
    tasks: Vec<ResolvedTask>,
    constraints: Vec<ResolvedConstraint>,
    solver: Solver,
    driver: PositionDriver,
    /// The "contact" level alone (the standing foot), when the table has one: its Newton step
    /// ends every frame ([`PhaseSolver::settle_contact`]).
    contact: Option<Solver>,
    /// The posture at the start of the frame, and the joint bounds within the frame's reach of
    /// it: the contact step stays inside the frame's velocity budget.
    frame_start: Vec<f64>,
    reach: JointBounds,
    /// The joints the contact step may move: those that turn the other sole but not the torso
    /// (the other leg's own), so that the body, the CoM and the hands stay where the frame put
    /// them (moved by the whole body's least-norm step, a hand resting on a stool sank 4 mm
    /// into it, and a CoM came 1.4 mm nearer the edge of the support).
    movable: Vec<bool>,
    /// The joints between the two soles (both legs,
    /// [`BipedProfile::sole_chain_variables`]): a second contact step may move them when the
    /// other leg alone cannot finish (a joint of it at a limit).
    legs: Vec<bool>,
    /// A contact row with only the movable joints' entries.
    row: Vec<f64>,
    /// The first contact step (rad).
    step: Vec<f64>,
    other_ankle: FrameId,
    other_sole: FrameId,
    /// The joints the solve may move ([`PhaseSolver::restricted`]); `None`: all.
    joints: Option<Vec<bool>>,
    /// [`ImitatorConfig::damping_momentum`](super::ImitatorConfig::damping_momentum), and the
    /// frame's step reference it gives (rad).
    damping_momentum: f64,
    momentum_step: Vec<f64>,
    reach_per_step: StepReach,
}

/// How far each variable can move in one step of a solve: a distance row that no such step
/// brings to its margin is written without its Jacobian
/// ([`CapsuleDistanceTask::write_for_step`]): the same solution, and on the NAO, whose nine
/// self-collision pairs are mostly far apart, 1–1.7 µs less of a 15–17 µs frame. (A row the
/// phase's last solve ended holding at its bound and written open now leaves the warm start,
/// whose infinite bounds the solver drops: where that happened on the bundled clips, once in
/// 56 runs, the solve took another path.)
#[derive(Debug, Clone)]
struct StepReach {
    lo: Vec<f64>,
    hi: Vec<f64>,
    /// The largest `|δq_v|` of a step (rad or m).
    step: Vec<f64>,
}

impl StepReach {
    fn new(nv: usize) -> Self {
        Self {
            lo: vec![0.0; nv],
            hi: vec![0.0; nv],
            step: vec![0.0; nv],
        }
    }

    /// For steps of `dt` (s) from `q` within `bounds` (the solver's own interval), moving
    /// only `joints` (`None`: all).
    fn update(&mut self, bounds: &JointBounds, q: &[f64], dt: f64, joints: Option<&[bool]>) {
        bounds.step_interval(q, dt, &mut self.lo, &mut self.hi);
        for (v, step) in self.step.iter_mut().enumerate() {
            let moves = joints.is_none_or(|j| j[v]);
            *step = match moves {
                true => self.hi[v].max(-self.lo[v]).max(0.0) * dt,
                false => 0.0,
            };
        }
    }
}

/// The tracked axes of `axes` in row order, padded with z.
fn axis_list(axes: Axes) -> [Axis; 3] {
    let picked = [(axes.x, Axis::X), (axes.y, Axis::Y), (axes.z, Axis::Z)];
    let mut out = [Axis::Z; 3];
    for (slot, (_, a)) in out.iter_mut().zip(picked.iter().filter(|(on, _)| *on)) {
        *slot = *a;
    }
    out
}

/// `table`'s tasks resolved against `model`: each task's frame point, axes and rows, its
/// height at the zero posture (`rest`) and its place at the standing one (`initial`); the CoM
/// tasks move the `balance` joints alone.
fn resolve_tasks(
    table: &TaskTable,
    model: &Model,
    rest: &ModelData,
    initial: &ModelData,
    balance: &[bool],
) -> Result<Vec<ResolvedTask>, ImitationError> {
    let mut tasks = Vec::new();
    for (level, l) in table.levels.iter().enumerate() {
        let mut row = 0;
        for task in &l.tasks {
            let (point, axes) = match task {
                Task::ComXY(_) => (None, Axes::XY),
                Task::ComHeight => (None, Axes::Z),
                Task::Point {
                    frame,
                    offset,
                    axes,
                    ..
                } => (Some((frame, Vector3::from(*offset))), *axes),
                Task::Orientation { frame, .. } => (Some((frame, Vector3::zeros())), Axes::XY),
            };
            let point = point
                .map(|(frame, offset)| {
                    model
                        .frame_id(frame)
                        .map(|frame| FramePoint { frame, offset })
                })
                .transpose()?;
            let (rest_height, standing) = match &point {
                Some(p) => (
                    model.point_position(rest, p.frame, &p.offset)?.z,
                    model.point_position(initial, p.frame, &p.offset)?,
                ),
                None => (0.0, Vector3::zeros()),
            };
            tasks.push(ResolvedTask {
                axes: axis_list(axes),
                rows: task.rows(),
                task: task.clone(),
                point,
                level,
                row,
                rest_height,
                standing,
                held: Vector3::zeros(),
                held_yaw: 0.0,
                joints: matches!(task, Task::ComXY(_) | Task::ComHeight).then(|| balance.to_vec()),
            });
            row += task.rows();
        }
    }
    Ok(tasks)
}

impl PhaseSolver {
    /// `table` resolved against the profile's model rooted at its support sole; standing targets
    /// from `initial_q`.
    pub(crate) fn new(
        table: &TaskTable,
        profile: &BipedProfile,
        initial_q: &[f64],
        settings: Settings,
    ) -> Result<Self, ImitationError> {
        table.validate()?;
        let model = profile.model(table.model_root);
        let mut rest = model.new_data();
        model.forward_kinematics(&mut rest, &vec![0.0; model.nv()])?;
        let mut initial = model.new_data();
        model.forward_kinematics(&mut initial, initial_q)?;
        let balance = balance_joints(profile, model, &initial)?;
        let tasks = resolve_tasks(table, model, &rest, &initial, &balance)?;
        let constraints = resolve_constraints(table, profile, model, &initial)?;
        let solver = Solver::with_settings(&table.shape(model.nv()), settings)?;
        let driver = PositionDriver::new(&solver, DriverSettings::default())?;
        // The contact step's bounds are the frame's reach, position bounds far inside its
        // velocity limits over its 1 s step, which scaling never scales: the clamping loop
        // alone gives the same step in one pass instead of one per part.
        let contact_settings = Settings {
            scale_to_fit: false,
            ..settings
        };
        let contact = (table.levels.first())
            .filter(|level| level.name == "contact")
            .map(|level| {
                let rows: usize = level.tasks.iter().map(Task::rows).sum();
                let shape = StackShape::new(model.nv()).with_level("contact", &[("contact", rows)]);
                Solver::with_settings(&shape, contact_settings)
            })
            .transpose()?;
        let other = profile.foot(table.model_root.other());
        Ok(Self {
            table: table.clone(),
            tasks,
            constraints,
            solver,
            driver,
            contact,
            frame_start: vec![0.0; model.nv()],
            reach: JointBounds::unbounded(model.nv()),
            movable: own_joints(
                model,
                &initial,
                &profile.foot(table.model_root.other()).sole,
                &profile.torso,
            )?,
            legs: profile.sole_chain_variables(initial_q)?,
            row: vec![0.0; model.nv()],
            step: vec![0.0; model.nv()],
            other_ankle: model.frame_id(&other.ankle)?,
            other_sole: model.frame_id(&other.sole)?,
            joints: None,
            damping_momentum: 0.0,
            momentum_step: vec![0.0; model.nv()],
            reach_per_step: StepReach::new(model.nv()),
        })
    }

    /// `table` resolved as [`PhaseSolver::new`] does, for a solve that moves only `joints` (per
    /// model variable): the other columns of every row, and the gradient's entries, are zero
    /// ([`PhaseTasks::evaluate`]), and a constraint between bodies those joints do not move
    /// relative to each other is left out (its rows would be zero).
    pub(crate) fn restricted(
        table: &TaskTable,
        profile: &BipedProfile,
        initial_q: &[f64],
        settings: Settings,
        joints: Vec<bool>,
    ) -> Result<Self, ImitationError> {
        let model = profile.model(table.model_root);
        let mut data = model.new_data();
        model.forward_kinematics(&mut data, initial_q)?;
        let mut table = table.clone();
        for level in &mut table.levels {
            let mut kept = Vec::new();
            for c in level.constraints.drain(..) {
                if moves_apart(&c, profile, model, &data, &joints)? {
                    kept.push(c);
                }
            }
            level.constraints = kept;
        }
        table.levels.retain(|level| level.rows() > 0);
        let mut solver = Self::new(&table, profile, initial_q, settings)?;
        solver.joints = Some(joints);
        Ok(solver)
    }

    /// Damped levels keep `share` of the last frame's step ([`PhaseSolver::run`]'s step
    /// reference, [`ImitatorConfig::damping_momentum`](super::ImitatorConfig::damping_momentum)).
    pub(crate) fn with_damping_momentum(mut self, share: f64) -> Self {
        self.damping_momentum = share;
        self
    }

    /// Number of tasks (entries of the driver's task errors).
    pub(crate) fn task_count(&self) -> usize {
        self.tasks.len()
    }

    /// The task names, in stack order.
    pub(crate) fn task_names(&self) -> impl Iterator<Item = String> + '_ {
        self.tasks.iter().map(|t| t.task.name())
    }

    /// The last solve's report (levels, clamped joints).
    pub(crate) fn solve_report(&self) -> &SolveReport {
        self.solver.report()
    }

    /// At the start of a step: the held targets become the points' current positions and the
    /// frames' current headings, from the forward kinematics in `data`.
    pub(crate) fn hold(&mut self, data: &ModelData) {
        for task in &mut self.tasks {
            if let Some(p) = &task.point {
                let placement = data.frame_placement(p.frame);
                task.held = placement.transform_point(&p.offset.into()).coords;
                let x = placement.rotation * Vector3::x();
                task.held_yaw = x.y.atan2(x.x);
            }
        }
    }

    /// The lift (m) of the table's held point, the swing foot's, if it has one.
    pub(crate) fn lift(&self) -> Option<f64> {
        self.tasks.iter().find_map(|t| match t.task {
            Task::Point {
                target: PointTarget::Held { lift },
                ..
            } => Some(lift),
            _ => None,
        })
    }

    /// The table's CoM goal in the root frame (m), from the forward kinematics in `data`; `None`
    /// when the table has no CoM task.
    pub(crate) fn com_goal(&self, data: &ModelData) -> Option<Vector2<f64>> {
        self.tasks.iter().find_map(|t| match t.task {
            Task::ComXY(goal) => Some(com_goal(goal, data, self.other_ankle, self.other_sole)),
            _ => None,
        })
    }

    /// The CoM task's error in `errors` (stack order, m), 0 without a CoM task.
    pub(crate) fn com_error(&self, errors: &[f64]) -> f64 {
        let com = self
            .tasks
            .iter()
            .position(|t| matches!(t.task, Task::ComXY(_)));
        com.and_then(|i| errors.get(i)).copied().unwrap_or(0.0)
    }

    /// The largest error of an upright-posture task in `errors` (stack order, rad), 0 without one.
    pub(crate) fn posture_error(&self, errors: &[f64]) -> f64 {
        let upright = |t: &ResolvedTask| {
            matches!(
                t.task,
                Task::Orientation {
                    target: OrientationTarget::Upright { .. } | OrientationTarget::Facing { .. },
                    ..
                }
            )
        };
        self.tasks
            .iter()
            .zip(errors)
            .filter(|(t, _)| upright(t))
            .fold(0.0, |worst: f64, (_, e)| worst.max(*e))
    }

    /// Runs the driver from `q` (updated in place) with `settings`, the model's forward
    /// kinematics kept in `data`, which must hold `q`'s on entry (the frame's first evaluation
    /// does not compute them again): after the call `data` holds the final `q`'s.
    #[allow(clippy::too_many_arguments)] // the frame's inputs, each from a different owner
    pub(crate) fn run(
        &mut self,
        model: &Model,
        data: &mut ModelData,
        targets: FrameTargets<'_>,
        criteria: Criteria<'_>,
        q: &mut [f64],
        bounds: &JointBounds,
        settings: DriverSettings,
    ) -> Result<(), ImitationError> {
        self.driver.set_settings(settings)?;
        self.frame_start.copy_from_slice(q);
        let frame_dt = settings.dt * settings.max_iterations as f64;
        self.set_step_reference(targets.joint_velocity, frame_dt)?;
        for c in &mut self.constraints {
            if let ConstraintRows::Zmp(zmp) = &mut c.rows {
                zmp.begin_frame(data, q, targets.joint_velocity, frame_dt)?;
            }
        }
        // A hand placed on a support moves with the pelvis: then only the other leg settles.
        let legs_may_settle = targets.hand_contacts.iter().all(Option::is_none);
        let resolved = (&self.tasks[..], &self.constraints[..], self.other_sole);
        let table = &self.table;
        let reach = (&mut self.reach_per_step, bounds, settings.dt);
        let mut tasks = PhaseTasks::new(model, data, resolved, table, targets, criteria)
            .moving(self.joints.as_deref())
            .reaching(reach);
        self.driver.run(&mut self.solver, &mut tasks, q, bounds)?;
        self.settle_contact(model, data, q, bounds, frame_dt, legs_may_settle)?;
        // A large frame's step leaves the contact second order in it, and a step the frame's
        // reach cut short leaves more: the G1's held foot was up to 22 µm off over its full
        // soak, where the human jumps between clips and the whole body moves at its speed
        // limits. Newton steps from the error at the settled posture follow until it is
        // below `SETTLED_CONTACT` (G1 full soak: 92 nm; the NAO's feet never need one).
        for _ in 0..CONTACT_STEPS {
            if self.contact_error(model, data, targets, criteria)? <= SETTLED_CONTACT {
                break;
            }
            self.settle_contact(model, data, q, bounds, frame_dt, legs_may_settle)?;
        }
        Ok(())
    }

    /// The driver's step reference: `damping_momentum` of the last frame's joint velocity over
    /// this frame's `frame_dt` (s); none when the share is 0 or the velocity is not known.
    fn set_step_reference(&mut self, velocity: &[f64], frame_dt: f64) -> Result<(), SolverError> {
        if self.damping_momentum == 0.0 || velocity.len() != self.momentum_step.len() {
            return self.driver.set_step_reference(None);
        }
        for (s, v) in self.momentum_step.iter_mut().zip(velocity) {
            *s = self.damping_momentum * v * frame_dt;
        }
        self.driver.set_step_reference(Some(&self.momentum_step))
    }

    /// Writes the contact level's rows at the posture in `data` (its forward kinematics
    /// current) into the stack and returns its error norm (m and rad); 0 without a contact
    /// level.
    fn contact_error(
        &mut self,
        model: &Model,
        data: &mut ModelData,
        targets: FrameTargets<'_>,
        criteria: Criteria<'_>,
    ) -> Result<f64, ImitationError> {
        if self.contact.is_none() {
            return Ok(0.0);
        }
        let resolved = (&self.tasks[..], &self.constraints[..], self.other_sole);
        let table = &self.table;
        let mut tasks = PhaseTasks::new(model, data, resolved, table, targets, criteria);
        let stack = self.solver.stack_mut();
        for task in self.tasks.iter().filter(|t| t.level == 0) {
            let mut level = stack.level_mut(0);
            let (jacobian, error) = level.rows_mut(task.row, task.rows);
            tasks.write(task, Some(jacobian), error)?;
        }
        let stack = self.solver.stack();
        let errors = &stack.stacked_target()[..stack.level_start(1)];
        Ok(errors.iter().map(|e| e * e).sum::<f64>().sqrt())
    }

    /// One Newton step of the contact level alone, from its rows at the final `q` (the driver
    /// evaluates the stack there before it stops): `δq = J_c⁺ e` over the other leg's own joints
    /// ([`PhaseSolver::movable`]), least norm, within the position limits and the reach of the
    /// frame's velocity budget (`frame_dt`, s, from the frame's start). The frame's steps meet
    /// the contact level to first order only, and on the G1 the lower levels' large steps (a
    /// near-singular hand level) left a standing foot up to 0.19 mm off its place (the NAO's
    /// up to 1.8 µm); after this step the error is second order in that one (G1 under 3 µm,
    /// NAO 1e-11 m on the bundled clips). When a joint of that leg is at a limit and the step
    /// leaves a residual (a leg of six joints with one clamped cannot place a foot in six
    /// coordinates), a second step over both legs takes the rest unless a hand is placed on a
    /// support (`legs_may_settle`: a placed hand moves with the pelvis, and sank 4.5 mm into
    /// its stool): the pelvis moves by that residual and the foot stays put (the G1's held foot
    /// had crept 17 µm with its ankle roll at its limit). The task errors of the frame's report
    /// are those before this step.
    fn settle_contact(
        &mut self,
        model: &Model,
        data: &mut ModelData,
        q: &mut [f64],
        bounds: &JointBounds,
        frame_dt: f64,
        legs_may_settle: bool,
    ) -> Result<(), ImitationError> {
        let Some(contact) = &mut self.contact else {
            return Ok(());
        };
        self.reach
            .copy_within_reach(bounds, &self.frame_start, frame_dt);
        let stack = self.solver.stack();
        let errors = &stack.stacked_target()[..stack.level_start(1)];
        self.step.fill(0.0);
        for movable in [&self.movable, &self.legs] {
            let mut level = contact.stack_mut().level_mut(0);
            for (r, &error) in errors.iter().enumerate() {
                // The other joints' columns are zero: the least-norm step leaves them where
                // they are (pinning them instead cost the clamping loop a solve per joint).
                // What the steps so far left of the error is this step's target.
                let mut left = error;
                for (((entry, &row), &moves), &done) in
                    (self.row.iter_mut().zip(stack.row(r)).zip(movable)).zip(&self.step)
                {
                    *entry = if moves { row } else { 0.0 };
                    left -= row * done;
                }
                level.set_row(r, &self.row, left)?;
            }
            contact.stack_mut().clear_gradient();
            let solution = contact.solve(q, &self.reach, 1.0)?;
            for ((qi, total), &d) in q.iter_mut().zip(&mut self.step).zip(solution.velocity) {
                *qi += d;
                *total += d;
            }
            self.reach.clamp_position(q);
            let residual = solution.report.levels()[0].residual;
            if !legs_may_settle || residual <= CONTACT_RESIDUAL {
                break;
            }
        }
        model.forward_kinematics(data, q)?;
        Ok(())
    }

    /// The last run's driver outcome (iterations, stop reason, task errors).
    pub(crate) fn driver_report(&self) -> &DriverReport {
        self.driver.report()
    }
}

/// Per variable of `model` (posture in `data`): whether it turns `frame` (its axis shows in the
/// frame's orientation Jacobian).
fn turning(model: &Model, data: &ModelData, frame: FrameId) -> Result<Vec<bool>, ImitationError> {
    let mut jacobian = faer::Mat::<f64>::zeros(3, model.nv());
    model.orientation_jacobian(data, frame, jacobian.as_mut())?;
    Ok((0..model.nv())
        .map(|i| (0..3).any(|r| jacobian[(r, i)] != 0.0))
        .collect())
}

/// The joints the CoM tasks of `profile` may move in `model` (at the posture in `data`): those
/// that turn the torso, a sole or a hand. A joint that turns none of them (the NAO's head)
/// moves the CoM by millimetres per radian, so a balance level the legs could not meet (their
/// joints at their limits) drove it at its speed limit: the NAO's head swept its whole
/// yaw range, ±2.09 rad, back and forth while the human washed (17 rad of travel over CMU
/// 02_10) and on every walking clip with `--walk`. Such joints follow the posture gradient.
fn balance_joints(
    profile: &BipedProfile,
    model: &Model,
    data: &ModelData,
) -> Result<Vec<bool>, ImitationError> {
    let soles = Side::BOTH.map(|side| profile.foot(side).sole.as_str());
    let frames = (soles.into_iter())
        .chain(profile.hands.iter().map(String::as_str))
        .chain([profile.torso.as_str()]);
    let mut joints = vec![false; model.nv()];
    for frame in frames {
        let turns = turning(model, data, model.frame_id(frame)?)?;
        for (joint, turns) in joints.iter_mut().zip(turns) {
            *joint |= turns;
        }
    }
    Ok(joints)
}

/// The joints that turn `frame` but not `torso` in `model` (at the posture in `data`): a
/// foot's own leg joints, a hand's own arm joints.
pub(crate) fn own_joints(
    model: &Model,
    data: &ModelData,
    frame: &str,
    torso: &str,
) -> Result<Vec<bool>, ImitationError> {
    let own = turning(model, data, model.frame_id(frame)?)?;
    let torso = turning(model, data, model.frame_id(torso)?)?;
    Ok(own.iter().zip(torso).map(|(&o, t)| o && !t).collect())
}

/// Whether any of `joints` moves the bodies of `constraint` relative to each other in `model`
/// (at the posture in `data`): a joint that turns one body's frame but not the other's.
fn moves_apart(
    constraint: &Constraint,
    profile: &BipedProfile,
    model: &Model,
    data: &ModelData,
    joints: &[bool],
) -> Result<bool, ImitationError> {
    let Constraint::Distance { first, second, .. } = constraint else {
        // The whole body's ZMP moves with any joint.
        return Ok(joints.iter().any(|&j| j));
    };
    let body = |name: &str| -> Result<Vec<bool>, ImitationError> {
        let frame = (profile.self_collision.body(name)?).capsule(model, &profile.stand)?;
        turning(model, data, frame.frame)
    };
    let (first, second) = (body(first)?, body(second)?);
    Ok((first.iter().zip(&second).zip(joints)).any(|((&a, &b), &j)| j && a != b))
}

/// The table's constraints as inequality tasks on `model`, the bodies from the profile's
/// self-collision model.
fn resolve_constraints(
    table: &TaskTable,
    profile: &BipedProfile,
    model: &Model,
    data: &ModelData,
) -> Result<Vec<ResolvedConstraint>, ImitationError> {
    let bodies = &profile.self_collision;
    let mut out = Vec::new();
    for (level, l) in table.levels.iter().enumerate() {
        let mut row = 0;
        for constraint in &l.constraints {
            let rows = match constraint {
                Constraint::Distance {
                    first,
                    second,
                    margin,
                } => {
                    let [first, second] = [first, second]
                        .map(|name| bodies.body(name)?.capsule(model, &profile.stand));
                    let name = constraint.name();
                    let task = CapsuleDistanceTask::new(model, &name, first?, second?, *margin)?;
                    ConstraintRows::Distance(task)
                }
                Constraint::Zmp {
                    margin,
                    max_yaw_moment,
                    vertices,
                } => {
                    let [left, right] = (profile.hands.each_ref())
                        .map(|hand| own_joints(model, data, hand, &profile.torso));
                    let arms = (left?.iter().zip(right?)).map(|(l, r)| *l || r).collect();
                    let bounds = [*margin, *max_yaw_moment];
                    let zmp = SupportZmp::new(table, profile, model, arms, bounds, *vertices)?;
                    ConstraintRows::Zmp(Box::new(zmp))
                }
            };
            out.push(ResolvedConstraint { rows, level, row });
            row += constraint.rows();
        }
    }
    Ok(out)
}

/// The `TaskModel` of one phase at one frame.
struct PhaseTasks<'a> {
    model: &'a Model,
    data: &'a mut ModelData,
    tasks: &'a [ResolvedTask],
    constraints: &'a [ResolvedConstraint],
    /// The other sole's frame (the target of [`OrientationTarget::Facing`]).
    other_sole: FrameId,
    targets: FrameTargets<'a>,
    gradients: &'a [Gradient],
    criteria: Criteria<'a>,
    /// Whether `data` holds the kinematics at the `q` of the next evaluation: the first
    /// evaluation of a run is at the run's starting posture, whose kinematics the caller
    /// provides.
    fresh: bool,
    /// The joints the solve may move; `None`: all.
    joints: Option<&'a [bool]>,
    /// The steps of the solve: the joint bounds and step (s) they are taken within, and their
    /// reach per variable at the evaluated posture; `None`: distance rows always in full.
    reach: Option<(&'a mut StepReach, &'a JointBounds, f64)>,
}

impl<'a> PhaseTasks<'a> {
    /// The `tasks` and `constraints` of `table` (resolved against `model`, the other sole at
    /// `other_sole`) aiming at `targets`, from the posture in `data`, whose kinematics are
    /// current.
    fn new(
        model: &'a Model,
        data: &'a mut ModelData,
        (tasks, constraints, other_sole): (&'a [ResolvedTask], &'a [ResolvedConstraint], FrameId),
        table: &'a TaskTable,
        targets: FrameTargets<'a>,
        criteria: Criteria<'a>,
    ) -> Self {
        Self {
            model,
            data,
            tasks,
            constraints,
            other_sole,
            targets,
            gradients: &table.gradients,
            criteria,
            fresh: true,
            joints: None,
            reach: None,
        }
    }

    /// The same, for a solve that moves only `joints` (`None`: all).
    fn moving(self, joints: Option<&'a [bool]>) -> Self {
        Self { joints, ..self }
    }

    /// The same, for a solve whose steps of `dt` (s) stay within `bounds`, measured in `reach`
    /// when the table has distance rows.
    fn reaching(self, (reach, bounds, dt): (&'a mut StepReach, &'a JointBounds, f64)) -> Self {
        let distances =
            (self.constraints.iter()).any(|c| matches!(c.rows, ConstraintRows::Distance(_)));
        let reach = distances.then_some((reach, bounds, dt));
        Self { reach, ..self }
    }
}

/// Zeroes the columns of `jacobian` whose joint is not in `joints` (`None`: none).
fn keep_columns(mut jacobian: MatMut<'_, f64>, joints: Option<&[bool]>) {
    for (c, _) in (joints.unwrap_or_default().iter().enumerate()).filter(|(_, moves)| !**moves) {
        jacobian.as_mut().col_mut(c).fill(0.0);
    }
}

/// `goal` in the root frame (m), from the current forward kinematics in `data`.
fn com_goal(
    goal: ComGoal,
    data: &ModelData,
    other_ankle: FrameId,
    other_sole: FrameId,
) -> Vector2<f64> {
    let other = data.frame_placement(other_ankle).translation.vector;
    let sole = data.frame_placement(other_sole);
    let on_other = |[x, y]: [f64; 2]| {
        sole.transform_point(&Vector3::new(x, y, 0.0).into())
            .coords
            .xy()
    };
    match goal {
        ComGoal::SupportAnkle => Vector2::zeros(),
        ComGoal::SupportFootCentre { lambda } => Vector2::new(lambda, 0.0),
        ComGoal::MidAnkles => other.xy() * 0.5,
        ComGoal::OtherFootCentre { lambda } => {
            let forward = sole.rotation * Vector3::x();
            other.xy() + lambda * forward.xy()
        }
        ComGoal::SupportPoint(p) => Vector2::from(p),
        ComGoal::OtherPoint(p) => on_other(p),
        ComGoal::BetweenPoints { support, other } => {
            (Vector2::from(support) + on_other(other)) * 0.5
        }
    }
}

/// Heading `yaw` (rad about z), then leaning `lean` rad about x (z toward +y for lean > 0):
/// the target of [`OrientationTarget::Facing`].
fn facing(lean: f64, yaw: f64) -> Rotation3<f64> {
    Rotation3::from_axis_angle(&Vector3::x_axis(), -lean) * flat(yaw)
}

/// Flat (z up) with heading `yaw` (rad about z).
fn flat(yaw: f64) -> Rotation3<f64> {
    Rotation3::from_axis_angle(&Vector3::z_axis(), yaw)
}

/// The goal of an orientation task: a whole orientation (three rows) or the direction its
/// frame's z axis points (two rows, yaw free).
enum Attitude {
    Rotation(Rotation3<f64>),
    Up(Vector3<f64>),
}

impl TaskModel for PhaseTasks<'_> {
    type Error = ImitationError;

    fn max_task_error(&self, task: usize) -> Option<f64> {
        let Task::Point { target, .. } = self.tasks.get(task)?.task else {
            return None;
        };
        match target {
            PointTarget::Scaled(HumanJoint::LHand) => Some(self.targets.hand_steps[0]),
            PointTarget::Scaled(HumanJoint::RHand) => Some(self.targets.hand_steps[1]),
            PointTarget::Scaled(_) => Some(self.targets.tracking_step),
            _ => None,
        }
    }

    fn max_inequality_correction(&self, level: usize, row: usize) -> Option<f64> {
        // A ZMP row bounds the frame's acceleration: its value if the joints stopped at once
        // is no violation to recover from slowly (clipped, it let a swinging arm stop dead).
        let zmp = |c: &ResolvedConstraint| match &c.rows {
            ConstraintRows::Zmp(z) => {
                c.level == level && (c.row..c.row + z.task.rows()).contains(&row)
            }
            ConstraintRows::Distance(_) => false,
        };
        self.constraints.iter().any(zmp).then_some(f64::INFINITY)
    }

    fn evaluate(&mut self, q: &[f64], stack: &mut TaskStack) -> Result<(), ImitationError> {
        if !std::mem::take(&mut self.fresh) {
            self.model.forward_kinematics(self.data, q)?;
        }
        for task in self.tasks {
            self.write_rows(task, stack)?;
        }
        if let Some((reach, bounds, dt)) = &mut self.reach {
            reach.update(bounds, q, *dt, self.joints);
        }
        for c in self.constraints {
            self.write_constraint(c, q, stack)?;
        }
        self.write_gradient(q, stack)
    }

    /// The errors and rooms at the frame's final `q`; the Jacobians of the contact level too,
    /// which [`PhaseSolver::settle_contact`] steps from.
    fn measure(&mut self, q: &[f64], stack: &mut TaskStack) -> Result<(), ImitationError> {
        if !std::mem::take(&mut self.fresh) {
            self.model.forward_kinematics(self.data, q)?;
        }
        for task in self.tasks {
            if task.level == 0 {
                self.write_rows(task, stack)?;
            } else {
                let mut level = stack.level_mut(task.level);
                let (_, error) = level.rows_mut(task.row, task.rows);
                self.write(task, None, error)?;
            }
        }
        for c in self.constraints {
            let ConstraintRows::Distance(d) = &c.rows else {
                // A ZMP row's room comes with its Jacobian.
                self.write_constraint(c, q, stack)?;
                continue;
            };
            let mut level = stack.level_mut(c.level);
            let (_, lower, upper) = level.inequalities_mut();
            let (lower, upper) = (&mut lower[c.row..c.row + 1], &mut upper[c.row..c.row + 1]);
            d.write_room(self.model, self.data, lower, upper)?;
        }
        Ok(())
    }
}

impl PhaseTasks<'_> {
    /// The Jacobian rows (over the moving joints) and error of `task` into `stack`.
    fn write_rows(
        &mut self,
        task: &ResolvedTask,
        stack: &mut TaskStack,
    ) -> Result<(), ImitationError> {
        let mut level = stack.level_mut(task.level);
        let (mut jacobian, target) = level.rows_mut(task.row, task.rows);
        self.write(task, Some(jacobian.as_mut()), target)?;
        keep_columns(jacobian.as_mut(), task.joints.as_deref());
        keep_columns(jacobian, self.joints);
        Ok(())
    }

    /// The rows (Jacobian over the moving joints, room) of constraint `c` at `q` into `stack`.
    fn write_constraint(
        &self,
        c: &ResolvedConstraint,
        q: &[f64],
        stack: &mut TaskStack,
    ) -> Result<(), ImitationError> {
        let mut level = stack.level_mut(c.level);
        let (mut jacobian, lower, upper) = level.inequalities_mut();
        let count = match &c.rows {
            ConstraintRows::Distance(d) => d.rows(),
            ConstraintRows::Zmp(z) => z.task.rows(),
        };
        let (rows, (model, data)) = (c.row..c.row + count, (self.model, &*self.data));
        let mut jacobian = jacobian.as_mut().subrows_mut(c.row, count);
        let (lower, upper) = (&mut lower[rows.clone()], &mut upper[rows]);
        match &c.rows {
            ConstraintRows::Distance(d) => match &self.reach {
                Some((reach, ..)) => {
                    d.write_for_step(model, data, &reach.step, jacobian.as_mut(), lower, upper)?;
                }
                None => d.write(model, data, jacobian.as_mut(), lower, upper)?,
            },
            ConstraintRows::Zmp(z) => {
                z.task
                    .write(model, data, q, jacobian.as_mut(), lower, upper)?
            }
        }
        keep_columns(jacobian, self.joints);
        Ok(())
    }

    /// The gradient term of the table's criteria at `q` into `stack`, over the moving joints.
    fn write_gradient(&mut self, q: &[f64], stack: &mut TaskStack) -> Result<(), ImitationError> {
        stack.clear_gradient();
        for g in self.gradients {
            match g.kind {
                GradientKind::JointLimits => {
                    stack.add_gradient(g.kappa, self.criteria.limits, q)?
                }
                GradientKind::HumanJoints => {
                    stack.add_gradient(g.kappa, self.criteria.tracking, q)?
                }
            }
        }
        let gradient = stack.gradient_mut();
        for (g, _) in
            (gradient.iter_mut().zip(self.joints.unwrap_or_default())).filter(|(_, m)| !**m)
        {
            *g = 0.0;
        }
        Ok(())
    }

    /// The error of `task` and, when `jacobian` is given, its Jacobian rows.
    fn write(
        &mut self,
        task: &ResolvedTask,
        jacobian: Option<MatMut<'_, f64>>,
        error: &mut [f64],
    ) -> Result<(), ImitationError> {
        let (model, data) = (self.model, &*self.data);
        let Some(point) = &task.point else {
            let com = self.targets.com;
            match (&task.task, jacobian) {
                (Task::ComHeight, jacobian) => {
                    if let Some(jacobian) = jacobian {
                        model.com_jacobian_axes(data, &[Axis::Z], jacobian)?;
                    }
                    error[0] = self.targets.com_height - model.com(data)?.z;
                }
                (_, Some(jacobian)) => com_rows(model, data, &[com.x, com.y], jacobian, error)?,
                (_, None) => com_error(model, data, &[com.x, com.y], error)?,
            }
            return Ok(());
        };
        let frame = point.frame;
        match task.task {
            // A free hand's support task: no rows.
            Task::Point {
                target: PointTarget::HandContact(side),
                ..
            } if self.targets.hand_contacts[side.index()].is_none() => {
                if let Some(mut jacobian) = jacobian {
                    jacobian.fill(0.0);
                }
                error.fill(0.0);
            }
            Task::Point { target, .. } => {
                let goal = self.point_goal(task, target, point)?;
                let axes = &task.axes[..task.rows];
                match jacobian {
                    Some(j) => point_rows(model, data, point, axes, &goal, j, error)?,
                    None => point_error(model, data, point, axes, &goal, error)?,
                }
            }
            Task::Orientation { target, .. } => match (self.attitude(task, target), jacobian) {
                (Attitude::Rotation(r), Some(j)) => {
                    orientation_rows(model, data, frame, &r, j, error)?
                }
                (Attitude::Rotation(r), None) => orientation_error(model, data, frame, &r, error)?,
                (Attitude::Up(up), Some(j)) => upright_rows(model, data, frame, &up, j, error)?,
                (Attitude::Up(up), None) => upright_error(model, data, frame, &up, error)?,
            },
            Task::ComXY(_) | Task::ComHeight => unreachable!("a CoM task has no point"),
        }
        Ok(())
    }

    /// What an orientation task asks of its frame this frame.
    fn attitude(&self, task: &ResolvedTask, target: OrientationTarget) -> Attitude {
        match target {
            OrientationTarget::HeldFlat => Attitude::Rotation(flat(task.held_yaw)),
            OrientationTarget::Footstep => {
                let yaw = self.targets.footstep.map_or(task.held_yaw, |f| f.yaw);
                Attitude::Rotation(flat(yaw))
            }
            // The vertical leaned by `lean` rad about x (toward +y for lean > 0).
            OrientationTarget::Upright { lean } => {
                Attitude::Up(Vector3::new(0.0, lean.sin(), lean.cos()))
            }
            OrientationTarget::Facing { lean } => {
                let x = self.data.frame_placement(self.other_sole).rotation * Vector3::x();
                Attitude::Rotation(facing(lean, 0.5 * x.y.atan2(x.x)))
            }
            OrientationTarget::Leaning => Attitude::Up(self.targets.up),
        }
    }

    /// Where a point task's point goes this frame (root frame, m).
    fn point_goal(
        &self,
        task: &ResolvedTask,
        target: PointTarget,
        point: &FramePoint,
    ) -> Result<Vector3<f64>, ImitationError> {
        let targets = &self.targets;
        let or_current = |p: Option<Vector3<f64>>| {
            p.map_or_else(
                || (self.model).point_position(self.data, point.frame, &point.offset),
                Ok,
            )
        };
        Ok(match target {
            // Missing references (never after the scaler) hold the current position.
            PointTarget::Scaled(HumanJoint::LHand) => or_current(targets.hands[0])?,
            PointTarget::Scaled(HumanJoint::RHand) => or_current(targets.hands[1])?,
            PointTarget::Scaled(joint) => or_current(targets.reference[joint.index()])?,
            // A lifted or lowered foot follows the shaped swing height; a foot on the ground
            // (lift 0 outside a landing) has swing height 0.
            PointTarget::Held { .. } => Vector3::new(
                task.held.x,
                task.held.y,
                task.rest_height + targets.swing_lift,
            ),
            PointTarget::Standing { lower } => {
                task.standing - Vector3::z() * (lower * targets.lowering_share)
            }
            PointTarget::Footstep { lift } => {
                let xy = targets.footstep.map_or(task.held.xy(), |f| f.xy);
                Vector3::new(xy.x, xy.y, task.rest_height + lift)
            }
            PointTarget::HandContact(side) => or_current(targets.hand_contacts[side.index()])?,
            PointTarget::Planned => {
                let xy = targets.footstep.map_or(task.held.xy(), |f| f.xy);
                Vector3::new(xy.x, xy.y, task.rest_height + targets.swing_lift)
            }
        })
    }
}
