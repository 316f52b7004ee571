//! A phase's task table resolved against the model rooted at its support sole: each task's
//! frame point, axes and rows, each constraint's rows, and the joints the balance may move.

use nalgebra::Vector3;

use crate::human::Side;
use crate::imitation::error::ImitationError;
use crate::imitation::phase::tables::{Axes, Constraint, Task, TaskTable};
use crate::imitation::phase::zmp_balance::SupportZmp;
use crate::model::{Axis, FrameId, Model, ModelData};
use crate::robots::BipedProfile;
use crate::tasks::{CapsuleDistanceTask, FramePoint};

/// A task of a table, resolved against a model: frame, axes, where its rows are.
#[derive(Debug, Clone)]
pub(super) struct ResolvedTask {
    pub(super) task: Task,
    /// The tracked point (the frame's origin for orientation tasks); `None` for the CoM.
    pub(super) point: Option<FramePoint>,
    /// The tracked axes of a point task, in row order (first `rows` entries).
    pub(super) axes: [Axis; 3],
    pub(super) rows: usize,
    pub(super) level: usize,
    pub(super) row: usize,
    /// Height of the point above the ground when its foot is flat (q = 0), m.
    pub(super) rest_height: f64,
    /// Position of the point in the initial posture, root frame (m).
    pub(super) standing: Vector3<f64>,
    /// Held target (the point's position when the step began), m, root frame.
    pub(super) held: Vector3<f64>,
    /// Held heading (yaw of the frame's x axis when the step began), rad, root frame.
    pub(super) held_yaw: f64,
    /// The joints the task may move ([`balance_joints`] for the CoM); `None`: all.
    pub(super) joints: Option<Vec<bool>>,
}

/// A constraint of a table, resolved against a model: its rows and where they are.
#[derive(Debug, Clone)]
pub(super) struct ResolvedConstraint {
    pub(super) rows: ConstraintRows,
    pub(super) level: usize,
    /// First row among the level's inequality rows.
    pub(super) row: usize,
}

/// The rows of a constraint.
#[derive(Debug, Clone)]
pub(super) enum ConstraintRows {
    Distance(CapsuleDistanceTask),
    Zmp(Box<SupportZmp>),
}

/// The tracked axes of `axes` in row order, padded with z.
pub(super) fn axis_list(axes: Axes) -> [Axis; 3] {
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
pub(super) fn resolve_tasks(
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

/// Per variable of `model` (posture in `data`): whether it turns `frame` (its axis shows in the
/// frame's orientation Jacobian).
pub(super) fn turning(
    model: &Model,
    data: &ModelData,
    frame: FrameId,
) -> Result<Vec<bool>, ImitationError> {
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
pub(super) fn balance_joints(
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
pub(super) fn moves_apart(
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
pub(super) fn resolve_constraints(
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
