//! The task model the position-level driver evaluates at each iteration of a phase's solve: the
//! table's rows, written with the ready-made rows of [`crate::tasks`] toward the frame's shaped
//! references ([`FrameTargets`]), then the gradient tasks ([`Criteria`]).

use faer::MatMut;
use nalgebra::{Rotation3, Vector2, Vector3};

use super::resolve::{ConstraintRows, ResolvedConstraint, ResolvedTask};
use crate::human::HumanJoint;
use crate::imitation::error::ImitationError;
use crate::imitation::phase::tables::{
    ComGoal, Gradient, GradientKind, OrientationTarget, PointTarget, Task, TaskTable,
};
use crate::imitation::walking::footsteps::GroundPose;
use crate::model::{Axis, FrameId, Model, ModelData};
use crate::solver::driver::TaskModel;
use crate::solver::{JointBounds, JointLimitAvoidance, JointTracking, TaskStack};
use crate::tasks::{
    FramePoint, InequalityTask, com_error, com_rows, orientation_error, orientation_rows,
    point_error, point_rows, upright_error, upright_rows,
};

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

/// The `TaskModel` of one phase at one frame.
pub(super) struct PhaseTasks<'a> {
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
    pub(super) fn new(
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
    pub(super) fn moving(self, joints: Option<&'a [bool]>) -> Self {
        Self { joints, ..self }
    }

    /// The same, for a solve whose steps of `dt` (s) stay within `bounds`, measured in `reach`
    /// when the table has distance rows.
    pub(super) fn reaching(
        self,
        (reach, bounds, dt): (&'a mut StepReach, &'a JointBounds, f64),
    ) -> Self {
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
pub(super) fn com_goal(
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
    pub(super) fn write(
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

/// How far each variable can move in one step of a solve: a distance row that no such step
/// brings to its margin is written without its Jacobian
/// ([`CapsuleDistanceTask::write_for_step`]): the same solution, and on the NAO, whose nine
/// self-collision pairs are mostly far apart, 1–1.7 µs less of a 15–17 µs frame. (A row the
/// phase's last solve ended holding at its bound and written open now leaves the warm start,
/// whose infinite bounds the solver drops: where that happened on the bundled clips, once in
/// 56 runs, the solve took another path.)
#[derive(Debug, Clone)]
pub(super) struct StepReach {
    lo: Vec<f64>,
    hi: Vec<f64>,
    /// The largest `|δq_v|` of a step (rad or m).
    step: Vec<f64>,
}

impl StepReach {
    pub(super) fn new(nv: usize) -> Self {
        Self {
            lo: vec![0.0; nv],
            hi: vec![0.0; nv],
            step: vec![0.0; nv],
        }
    }

    /// For steps of `dt` (s) from `q` within `bounds` (the solver's own interval), moving
    /// only `joints` (`None`: all).
    pub(super) fn update(
        &mut self,
        bounds: &JointBounds,
        q: &[f64],
        dt: f64,
        joints: Option<&[bool]>,
    ) {
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
