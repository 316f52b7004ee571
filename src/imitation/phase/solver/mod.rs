//! The per-phase solver of the imitator: a phase's task table resolved against the model rooted
//! at its support sole ([`PhaseSolver`]), and the task model the position-level driver evaluates
//! at each iteration: the table's rows, written with the ready-made rows of [`crate::tasks`]
//! toward the frame's shaped references ([`FrameTargets`]), then the gradient tasks.

use nalgebra::{Vector2, Vector3};

use crate::imitation::error::ImitationError;
use crate::imitation::phase::tables::{OrientationTarget, PointTarget, Task, TaskTable};
use crate::model::{FrameId, Model, ModelData};
use crate::robots::BipedProfile;
use crate::solver::driver::{DriverReport, DriverSettings, PositionDriver};
use crate::solver::{JointBounds, Settings, SolveReport, Solver, SolverError, StackShape};

mod resolve;
mod rows;

pub(crate) use resolve::own_joints;
use resolve::{
    ConstraintRows, ResolvedConstraint, ResolvedTask, balance_joints, moves_apart,
    resolve_constraints, resolve_tasks,
};
pub(crate) use rows::{Criteria, FrameTargets};
use rows::{PhaseTasks, StepReach, com_goal};

/// Residual of the contact step's linear system (m and rad, the rows' units) above which a
/// second step over both legs takes the rest.
const CONTACT_RESIDUAL: f64 = 1e-9;

/// Contact error (m and rad) left after the contact step above which another step follows.
const SETTLED_CONTACT: f64 = 1e-7;

/// Most contact steps after the first in one frame (each a solve of the contact level and
/// forward kinematics): a bound on the frame's time.
const CONTACT_STEPS: usize = 3;

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
    /// [`PoubelConfig::damping_momentum`](crate::imitation::poubel::PoubelConfig::damping_momentum), and the
    /// frame's step reference it gives (rad).
    damping_momentum: f64,
    momentum_step: Vec<f64>,
    reach_per_step: StepReach,
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
    /// reference, [`PoubelConfig::damping_momentum`](crate::imitation::poubel::PoubelConfig::damping_momentum)).
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
