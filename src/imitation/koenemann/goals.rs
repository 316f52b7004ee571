//! The IK goals of the method and their rows: points and sole normals in the torso frame (the
//! frame the posture mapping speaks in) or in the root sole's frame (the floor), solved by
//! weighted damped least squares ([`Method::WeightedDls`]) to a tolerance.
//!
//! Rows relative to the torso `(R_t, p_t)` of the root-sole model: for a point `x`,
//! `d/dt Rₜᵀ(x − pₜ) = Rₜᵀ (J_x − J_t + [x − pₜ]× J_ωt) q̇`; for a frame's z axis `z`,
//! `d/dt Rₜᵀ z = Rₜᵀ ((J_ω − J_ωt) q̇ × z)`. A normal goal has two rows: the change of `z`
//! along two directions across it (turning about `z` itself is free: the 5-DoF foot goal of
//! §V.C), weighted by [`NORMAL_WEIGHT`] so that one tolerance reads 1 mm or 0.033 rad. The
//! CoM's ground projection in the root frame, `J_CoM,xy q̇`, is the stability goal: it states
//! eq. 7 on the floor (the CoM above the point at offset `o'`) instead of through the soles'
//! normals in the torso frame, so one strict level meets it exactly.

use faer::Mat;
use nalgebra::{IsometryMatrix3, Rotation3, Vector2, Vector3};

use crate::human::Side;
use crate::imitation::error::ImitationError;
use crate::imitation::state::Shared;
use crate::model::{FrameId, Model, ModelData};
use crate::robots::BipedProfile;
use crate::solver::driver::{DriverReport, DriverSettings, PositionDriver, TaskModel};
use crate::solver::{JointBounds, Method, Settings, Solver, SolverError, StackShape, TaskStack};
use crate::tasks::{CapsuleDistanceTask, InequalityTask};

/// Distance rows of an IK (self-collision pairs kept apart), one set per model root
/// (`[left, right]`: the capsules' frames are the root model's), in a level of their own.
#[derive(Debug, Clone, Default)]
pub(super) struct Distances {
    /// Number of goal levels above the distance level.
    pub(super) below_levels: usize,
    /// The rows on the model rooted at each sole, the same pairs in the same order.
    pub(super) rows: [Vec<CapsuleDistanceTask>; 2],
}

impl Distances {
    /// Whether there are no rows.
    pub(super) fn is_empty(&self) -> bool {
        self.rows[0].is_empty()
    }

    /// The profile's self-collision pairs that only the `moving` joints move apart: those whose
    /// distance has a zero derivative in every other joint at the posture `q` (the pairs of
    /// the upper body for the arms, of the legs for the legs; a leg joint turns the whole upper
    /// body rigidly and leaves its distances unchanged). Below `below_levels` goal levels.
    pub(super) fn moved_by(
        profile: &BipedProfile,
        q: &[f64],
        moving: &[bool],
        below_levels: usize,
    ) -> Result<Self, ImitationError> {
        // Which pairs is decided once, on the right-rooted model: a distance between two bodies
        // does not depend on the root, and both roots must get the same rows.
        let right = distance_tasks(profile, Side::Right)?;
        let model = profile.model(Side::Right);
        let mut data = model.new_data();
        model.forward_kinematics(&mut data, q)?;
        let mut jacobian = Mat::zeros(1, model.nv());
        let (mut lower, mut upper) = ([0.0], [0.0]);
        let mut keep = Vec::with_capacity(right.len());
        for task in &right {
            task.write(model, &data, jacobian.as_mut(), &mut lower, &mut upper)?;
            let column = |k: usize| jacobian[(0, k)].abs() > MOVED;
            let mine = (0..model.nv()).any(column);
            keep.push(mine && (0..model.nv()).all(|k| moving[k] || !column(k)));
        }
        let kept = |tasks: Vec<CapsuleDistanceTask>| -> Vec<CapsuleDistanceTask> {
            (tasks.into_iter().zip(&keep))
                .filter_map(|(task, &k)| k.then_some(task))
                .collect()
        };
        let rows = [kept(distance_tasks(profile, Side::Left)?), kept(right)];
        Ok(Self { below_levels, rows })
    }
}

/// Every self-collision pair of the profile as a distance task on the model rooted at `side`.
fn distance_tasks(
    profile: &BipedProfile,
    side: Side,
) -> Result<Vec<CapsuleDistanceTask>, ImitationError> {
    let collision = &profile.self_collision;
    let model = profile.model(side);
    let pairs = collision.resolve(model, &profile.stand)?;
    (collision.pairs.iter().zip(pairs))
        .map(|([a, b], [first, second])| {
            let name = format!("d({a},{b})");
            Ok(CapsuleDistanceTask::new(
                model,
                &name,
                first,
                second,
                collision.margin,
            )?)
        })
        .collect()
}

/// A distance derivative (m/rad) below this is a joint that does not move the pair.
const MOVED: f64 = 1e-9;
/// Metres per radian of a normal or orientation row: Koenemann et al.'s tolerances, 1 mm and
/// 0.033 rad, become one.
pub(super) const NORMAL_WEIGHT: f64 = 0.001 / 0.033;

/// One goal.
#[derive(Debug, Clone, Copy)]
pub(super) enum Goal {
    /// The point at `offset` (frame axes) from `frame` at `target` in the torso frame (3 rows).
    TorsoPoint {
        frame: FrameId,
        offset: Vector3<f64>,
        target: Vector3<f64>,
    },
    /// `frame`'s z axis along the unit `normal` in the torso frame (2 rows).
    TorsoNormal {
        frame: FrameId,
        normal: Vector3<f64>,
    },
    /// The point at `offset` from `frame` at `target` in the root frame (3 rows).
    RootPoint {
        frame: FrameId,
        offset: Vector3<f64>,
        target: Vector3<f64>,
    },
    /// `frame`'s z axis along the unit `normal` in the root frame (2 rows).
    RootNormal {
        frame: FrameId,
        normal: Vector3<f64>,
    },
    /// `frame`'s orientation at `target` in the root frame (3 rows).
    RootOrientation {
        frame: FrameId,
        target: Rotation3<f64>,
    },
    /// The CoM's ground projection at `target` (x, y in the root frame, m; 2 rows).
    RootCom { target: Vector2<f64> },
}

impl Goal {
    fn rows(&self) -> usize {
        match self {
            Goal::TorsoNormal { .. } | Goal::RootNormal { .. } | Goal::RootCom { .. } => 2,
            _ => 3,
        }
    }
}

/// A fixed list of goals with its solver, driver and scratch: one IK problem of the method.
///
/// The solver sees only the joints the problem may move (its columns are
/// `GoalIk::columns`): the legs' IK solves over 12 of the NAO's 26 joints, not over 26 with
/// 14 zero columns, which costs the prioritized passes about twice as much.
#[derive(Debug)]
pub(super) struct GoalIk {
    pub(super) goals: Vec<Goal>,
    distances: Distances,
    /// The model's indices of the joints the problem may move, ascending; the others keep
    /// their place.
    columns: Vec<usize>,
    /// The moving joints' positions (rad or m), in the order of `columns`.
    q_moving: Vec<f64>,
    /// The caller's position limits on the moving joints.
    bounds_moving: JointBounds,
    /// A posture (every joint's position) the moving joints are drawn toward where the goals
    /// leave them free, and each joint's gain of that pull (1/iteration), or `None`.
    posture: Option<(Vec<f64>, Vec<f64>)>,
    solver: Solver,
    driver: PositionDriver,
    /// Torso point and angular Jacobians, a frame's point and angular Jacobians, and a goal's
    /// rows over every joint before the moving columns are taken from them (3 × n).
    scratch: [Mat<f64>; 5],
}

impl GoalIk {
    /// An IK for goals shaped like `goals` (their kinds fix the rows; targets change per frame)
    /// solved by `method`: the first `levels[0]` goals in the top level, the next `levels[1]`
    /// below them, and so on, the remaining goals (if any) in the last level (`&[]`: one
    /// level); the `distances` in a level of their own below the first
    /// [`Distances::below_levels`] goal levels. Only the joints `moving` marks move (its
    /// length is the model's number of joints).
    pub(super) fn new(
        goals: Vec<Goal>,
        levels: &[usize],
        distances: Distances,
        moving: Vec<bool>,
        method: Method,
        settings: DriverSettings,
    ) -> Result<Self, SolverError> {
        let names: Vec<String> = (0..goals.len()).map(|k| format!("goal {k}")).collect();
        let tasks: Vec<(&str, usize)> = names
            .iter()
            .zip(&goals)
            .map(|(n, g)| (n.as_str(), g.rows()))
            .collect();
        let mut goal_levels = Vec::new();
        let mut first = 0;
        for &count in levels {
            goal_levels.push(&tasks[first..first + count]);
            first += count;
        }
        if first < tasks.len() {
            goal_levels.push(&tasks[first..]);
        }
        let distance_rows: Vec<(&str, usize)> =
            (distances.rows[0].iter()).map(|d| (d.name(), 1)).collect();
        let (above, below) = goal_levels.split_at(distances.below_levels.min(goal_levels.len()));
        let with_goals =
            |shape: StackShape, level: &&[(&str, usize)]| shape.with_level("goals", level);
        let nv = moving.len();
        let columns: Vec<usize> = (0..nv).filter(|&k| moving[k]).collect();
        let mut shape = above
            .iter()
            .fold(StackShape::new(columns.len()), with_goals);
        if !distance_rows.is_empty() {
            shape = shape.with_inequality_level("distances", &distance_rows);
        }
        let shape = below.iter().fold(shape, with_goals);
        let solver = Solver::with_settings(
            &shape,
            Settings {
                method,
                ..Settings::default()
            },
        )?;
        let driver = PositionDriver::new(&solver, settings)?;
        Ok(GoalIk {
            goals,
            distances,
            q_moving: vec![0.0; columns.len()],
            bounds_moving: JointBounds::unbounded(columns.len()),
            posture: None,
            columns,
            solver,
            driver,
            scratch: std::array::from_fn(|_| Mat::zeros(3, nv)),
        })
    }

    /// Draws the moving joints toward `posture` (every joint's position, rad or m), joint `k`
    /// with `gains[k]`: the share of the way it takes in an iteration where no goal needs it,
    /// the gradient term `gains[k] (posture[k] − q[k])` (in the goals' null space with the
    /// prioritized method; traded against the goals by the damping with weighted DLS).
    pub(super) fn with_posture(mut self, posture: Vec<f64>, gains: Vec<f64>) -> Self {
        self.posture = Some((posture, gains));
        self
    }

    /// Moves the shared `q` toward the goals (warm start) in the root's model, whose torso
    /// frame is `torso`, within the position limits of `bounds`. Leaves the root's forward
    /// kinematics current at the final `q`.
    pub(super) fn run(
        &mut self,
        shared: &mut Shared,
        torso: FrameId,
        bounds: &JointBounds,
    ) -> Result<&DriverReport, ImitationError> {
        let root = shared.root;
        for (c, &k) in self.columns.iter().enumerate() {
            self.q_moving[c] = shared.q[k];
        }
        self.bounds_moving.copy_columns(bounds, &self.columns);
        let mut rows = GoalRows {
            model: shared.profile.model(root),
            data: &mut shared.data[root.index()],
            q: &mut shared.q,
            torso,
            goals: &self.goals,
            distances: &self.distances.rows[root.index()],
            distance_level: self.distances.below_levels,
            columns: &self.columns,
            posture: self
                .posture
                .as_ref()
                .map(|(p, g)| (p.as_slice(), g.as_slice())),
            scratch: &mut self.scratch,
        };
        let q_moving = &mut self.q_moving;
        self.driver
            .run(&mut self.solver, &mut rows, q_moving, &self.bounds_moving)
    }
}

/// The goals as a [`TaskModel`] over the moving joints.
struct GoalRows<'a> {
    model: &'a Model,
    data: &'a mut ModelData,
    /// Every joint's position: the moving ones are written from each iterate, so that the
    /// last iterate evaluated (the result) is left here.
    q: &'a mut [f64],
    torso: FrameId,
    goals: &'a [Goal],
    distances: &'a [CapsuleDistanceTask],
    /// The level of the distance rows (when there are any).
    distance_level: usize,
    columns: &'a [usize],
    posture: Option<(&'a [f64], &'a [f64])>,
    scratch: &'a mut [Mat<f64>; 5],
}

impl TaskModel for GoalRows<'_> {
    type Error = ImitationError;

    fn evaluate(&mut self, moving: &[f64], stack: &mut TaskStack) -> Result<(), ImitationError> {
        self.write(moving, stack, true)
    }

    fn measure(&mut self, moving: &[f64], stack: &mut TaskStack) -> Result<(), ImitationError> {
        self.write(moving, stack, false)
    }
}

impl GoalRows<'_> {
    /// The goals' errors, the distance rows' rooms and, with `jacobians`, their Jacobians over
    /// the moving joints and the posture gradient, at the moving joints' positions `moving`.
    fn write(
        &mut self,
        moving: &[f64],
        stack: &mut TaskStack,
        jacobians: bool,
    ) -> Result<(), ImitationError> {
        for (&k, &v) in self.columns.iter().zip(moving) {
            self.q[k] = v;
        }
        let (model, q) = (self.model, &*self.q);
        model.forward_kinematics(self.data, q)?;
        let data = &*self.data;
        let torso = *data.frame_placement(self.torso);
        let [jt, jwt, jx, jw, full] = &mut *self.scratch;
        if jacobians {
            model.point_jacobian(data, self.torso, &Vector3::zeros(), jt.as_mut())?;
            model.orientation_jacobian(data, self.torso, jwt.as_mut())?;
        }
        let (mut level, mut first) = (0, 0);
        for goal in self.goals {
            let rows = goal.rows();
            // Past a full level, and past the distance level (no equality rows).
            while first == stack.level_mut(level).rows() {
                (level, first) = (level + 1, 0);
            }
            let mut rows_of = stack.level_mut(level);
            let (mut jac, error) = rows_of.rows_mut(first, rows);
            first += rows;
            goal_error(goal, model, data, &torso, error)?;
            if jacobians {
                // The goal's rows over every joint; the moving columns are taken here.
                let torso_jacobians = [&*jt, &*jwt];
                goal_jacobian(goal, model, data, &torso, torso_jacobians, [jx, jw], full)?;
                for (c, &k) in self.columns.iter().enumerate() {
                    for r in 0..rows {
                        jac[(r, c)] = full[(r, k)];
                    }
                }
            }
        }
        self.write_distances(stack, jacobians)?;
        if jacobians {
            stack.clear_gradient();
            if let Some((posture, gains)) = self.posture {
                let gradient = stack.gradient_mut();
                for (c, &k) in self.columns.iter().enumerate() {
                    gradient[c] = gains[k] * (posture[k] - self.q[k]);
                }
            }
        }
        Ok(())
    }
}

/// The error of `goal` (m, or [`NORMAL_WEIGHT`]-weighted rad) at the forward kinematics in
/// `data`, the torso at `torso`.
fn goal_error(
    goal: &Goal,
    model: &Model,
    data: &ModelData,
    torso: &IsometryMatrix3<f64>,
    error: &mut [f64],
) -> Result<(), ImitationError> {
    let rt = torso.rotation.inverse();
    match *goal {
        Goal::TorsoPoint {
            frame,
            offset,
            target,
        }
        | Goal::RootPoint {
            frame,
            offset,
            target,
        } => {
            let x = model.point_position(data, frame, &offset)?;
            let current = match goal {
                Goal::TorsoPoint { .. } => rt * (x - torso.translation.vector),
                _ => x,
            };
            for r in 0..3 {
                error[r] = target[r] - current[r];
            }
        }
        Goal::TorsoNormal { frame, normal } | Goal::RootNormal { frame, normal } => {
            let z_root = data.frame_placement(frame).rotation * Vector3::z();
            let z = match goal {
                Goal::TorsoNormal { .. } => rt * z_root,
                _ => z_root,
            };
            for (r, t) in across_basis(&z).iter().enumerate() {
                error[r] = NORMAL_WEIGHT * t.dot(&(normal - z));
            }
        }
        Goal::RootCom { target } => {
            let com = model.com(data)?;
            error[0] = target.x - com.x;
            error[1] = target.y - com.y;
        }
        Goal::RootOrientation { frame, target } => {
            // ½ Σ cᵢ × cᵢ*, the columns of the current and target rotations: the rotation
            // vector for small errors, and never NaN.
            let current = data.frame_placement(frame).rotation;
            let (c, t) = (current.matrix(), target.matrix());
            let e = (0..3).fold(Vector3::zeros(), |e, i| {
                e + c.column(i).cross(&t.column(i)) * 0.5
            });
            for r in 0..3 {
                error[r] = NORMAL_WEIGHT * e[r];
            }
        }
    }
    Ok(())
}

/// The Jacobian rows of `goal` over every joint into `out` (`goal.rows()` rows), from the
/// torso's point and orientation Jacobians `[jt, jwt]` at the forward kinematics in `data`
/// (the torso at `torso`), with `[jx, jw]` as scratch (3 × nv each).
fn goal_jacobian(
    goal: &Goal,
    model: &Model,
    data: &ModelData,
    torso: &IsometryMatrix3<f64>,
    [jt, jwt]: [&Mat<f64>; 2],
    [jx, jw]: [&mut Mat<f64>; 2],
    out: &mut Mat<f64>,
) -> Result<(), ImitationError> {
    let rt = torso.rotation.inverse();
    let nv = model.nv();
    match *goal {
        Goal::TorsoPoint { frame, offset, .. } | Goal::RootPoint { frame, offset, .. } => {
            let x = model.point_position(data, frame, &offset)?;
            model.point_jacobian(data, frame, &offset, jx.as_mut())?;
            let in_torso = matches!(goal, Goal::TorsoPoint { .. });
            let lever = x - torso.translation.vector;
            for k in 0..nv {
                let col = column(jx, k);
                let col = match in_torso {
                    true => rt * (col - column(jt, k) + lever.cross(&column(jwt, k))),
                    false => col,
                };
                for r in 0..3 {
                    out[(r, k)] = col[r];
                }
            }
        }
        Goal::TorsoNormal { frame, .. } | Goal::RootNormal { frame, .. } => {
            let in_torso = matches!(goal, Goal::TorsoNormal { .. });
            let z_root = data.frame_placement(frame).rotation * Vector3::z();
            let z = if in_torso { rt * z_root } else { z_root };
            model.orientation_jacobian(data, frame, jw.as_mut())?;
            let across = across_basis(&z);
            for k in 0..nv {
                let omega = match in_torso {
                    true => column(jw, k) - column(jwt, k),
                    false => column(jw, k),
                };
                let dz = omega.cross(&z_root);
                let dz = if in_torso { rt * dz } else { dz };
                for (r, t) in across.iter().enumerate() {
                    out[(r, k)] = NORMAL_WEIGHT * t.dot(&dz);
                }
            }
        }
        Goal::RootCom { .. } => model.com_jacobian_rows(data, 2, out.as_mut().subrows_mut(0, 2))?,
        Goal::RootOrientation { frame, .. } => {
            model.orientation_jacobian(data, frame, jw.as_mut())?;
            for k in 0..nv {
                for r in 0..3 {
                    out[(r, k)] = NORMAL_WEIGHT * jw[(r, k)];
                }
            }
        }
    }
    Ok(())
}

impl GoalRows<'_> {
    /// The distance rows' rooms and, with `jacobians`, their Jacobians over the moving joints.
    fn write_distances(
        &mut self,
        stack: &mut TaskStack,
        jacobians: bool,
    ) -> Result<(), ImitationError> {
        if self.distances.is_empty() {
            return Ok(());
        }
        let mut level = stack.level_mut(self.distance_level);
        let (mut jac, lower, upper) = level.inequalities_mut();
        let [.., full] = &mut *self.scratch;
        for (r, d) in self.distances.iter().enumerate() {
            if !jacobians {
                let (lower, upper) = (&mut lower[r..r + 1], &mut upper[r..r + 1]);
                d.write_room(self.model, self.data, lower, upper)?;
                continue;
            }
            d.write(
                self.model,
                self.data,
                full.as_mut().subrows_mut(0, 1),
                &mut lower[r..r + 1],
                &mut upper[r..r + 1],
            )?;
            for (c, &k) in self.columns.iter().enumerate() {
                jac[(r, c)] = full[(0, k)];
            }
        }
        Ok(())
    }
}

/// Column `k` of a 3 × n matrix.
fn column(m: &Mat<f64>, k: usize) -> Vector3<f64> {
    Vector3::new(m[(0, k)], m[(1, k)], m[(2, k)])
}

/// Two unit vectors across the unit `z`, orthogonal to each other.
fn across_basis(z: &Vector3<f64>) -> [Vector3<f64>; 2] {
    let helper = if z.x.abs() < 0.9 {
        Vector3::x()
    } else {
        Vector3::y()
    };
    let a = z.cross(&helper).normalize();
    [a, z.cross(&a)]
}

/// The placement of frame `frame` of `data` seen from the torso frame `torso`.
pub(super) fn in_torso(data: &ModelData, torso: FrameId, frame: FrameId) -> IsometryMatrix3<f64> {
    data.frame_placement(torso).inverse() * data.frame_placement(frame)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::imitation::ImitatorConfig;
    use crate::robots::nao;

    fn nao_shared() -> (Shared, JointBounds) {
        Shared::new(nao::profile(), &ImitatorConfig::default()).unwrap()
    }

    /// Runs `ik` with the shared state's torso frame and position bounds.
    fn run(ik: &mut GoalIk, shared: &mut Shared, bounds: &JointBounds) {
        let torso = (shared.profile.model(shared.root))
            .frame_id(&shared.profile.torso)
            .unwrap();
        ik.run(shared, torso, bounds).unwrap();
    }

    /// A problem over the legs solves over their columns alone: it brings the CoM to a goal 1 cm
    /// ahead, every other joint keeps its value to the bit, and the root's kinematics are left
    /// at the result (recomputed here from scratch).
    #[test]
    fn only_the_moving_joints_move_and_the_kinematics_are_left_current() {
        let (mut shared, bounds) = nao_shared();
        let root = shared.root;
        let model = shared.profile.model(root).clone();
        model
            .forward_kinematics(&mut shared.data[root.index()], &shared.q)
            .unwrap();
        let com = model.com(&shared.data[root.index()]).unwrap();
        let target = Vector2::new(com.x + 0.01, com.y);
        let legs = shared.legs.clone();
        let mut ik = GoalIk::new(
            vec![Goal::RootCom { target }],
            &[],
            Distances::default(),
            legs.clone(),
            Method::Prioritized,
            DriverSettings::default(),
        )
        .unwrap();
        let before = shared.q.clone();
        run(&mut ik, &mut shared, &bounds);
        for k in (0..before.len()).filter(|&k| !legs[k]) {
            assert_eq!(shared.q[k].to_bits(), before[k].to_bits(), "joint {k}");
        }
        assert!(
            legs.iter()
                .zip(&before)
                .zip(&shared.q)
                .any(|((&l, a), b)| l && a != b)
        );
        let mut fresh = model.new_data();
        model.forward_kinematics(&mut fresh, &shared.q).unwrap();
        let reached = model.com(&fresh).unwrap();
        assert!((reached.xy() - target).norm() <= 1e-4, "{reached}");
        assert_eq!(model.com(&shared.data[root.index()]).unwrap(), reached);
    }

    /// The posture pull moves an arm toward the standing posture in the directions its hand
    /// goal leaves free: with the hand's goal at its place (±2.5 mm, so the IK iterates), the
    /// left arm started 0.3 rad of elbow yaw and 0.1 rad of shoulder roll from the stand comes
    /// back most of the way while the hand stays on its goal; without the pull it stays off.
    #[test]
    fn the_posture_pull_moves_an_arm_only_where_its_hand_leaves_it_free() {
        let distance_to_stand = |gain: f64| {
            let (mut shared, bounds) = nao_shared();
            let root = shared.root;
            let model = shared.profile.model(root).clone();
            let stand = shared.profile.stand.clone();
            let arm: Vec<usize> = ["LShoulderPitch", "LShoulderRoll", "LElbowYaw", "LElbowRoll"]
                .map(|n| model.variable_index(n).unwrap())
                .to_vec();
            shared.q[arm[2]] += 0.3;
            shared.q[arm[1]] += 0.1;
            model
                .forward_kinematics(&mut shared.data[root.index()], &shared.q)
                .unwrap();
            let torso = model.frame_id(&shared.profile.torso).unwrap();
            let hand = model.frame_id(&shared.profile.hands[0]).unwrap();
            let start = in_torso(&shared.data[root.index()], torso, hand)
                .translation
                .vector;
            let all = vec![true; shared.q.len()];
            let goal = |target| Goal::TorsoPoint {
                frame: hand,
                offset: Vector3::zeros(),
                target,
            };
            let dls = Method::WeightedDls { damping: 0.01 };
            let mut ik = GoalIk::new(
                vec![goal(start)],
                &[],
                Distances::default(),
                all,
                dls,
                DriverSettings::default(),
            )
            .unwrap();
            if gain > 0.0 {
                let gains = (shared.legs.iter()).map(|&l| if l { 0.0 } else { gain });
                ik = ik.with_posture(stand.clone(), gains.collect());
            }
            let off = |q: &[f64]| arm.iter().map(|&k| (q[k] - stand[k]).powi(2)).sum::<f64>();
            let initial = off(&shared.q).sqrt();
            for frame in 0..200 {
                let sign = if frame % 2 == 0 { 1.0 } else { -1.0 };
                ik.goals[0] = goal(start + Vector3::new(0.0, 0.0, 0.0025 * sign));
                run(&mut ik, &mut shared, &bounds);
                let now = in_torso(&shared.data[root.index()], torso, hand)
                    .translation
                    .vector;
                assert!(
                    (now - start).norm() < 0.004,
                    "frame {frame}: hand {now} vs {start}"
                );
            }
            (initial, off(&shared.q).sqrt())
        };
        let (initial, pulled) = distance_to_stand(0.05);
        assert!(pulled < 0.5 * initial, "{pulled} of {initial} rad");
        let (_, free) = distance_to_stand(0.0);
        assert!(free > 0.9 * initial, "{free} of {initial} rad");
    }
}
