//! Position-level IK: iterate the velocity solve until position targets are reached.
//!
//! Each iteration asks a [`TaskModel`] for the task errors `e_j = x*_j − x_j(q)` and Jacobians at
//! the current `q`, sets `ẋ_j = K e_j` (each task's error first clipped to a largest norm, so that
//! a far target is approached in steps the linearization can be trusted over), solves the stack (with the clamping loop, so every iterate
//! is within the joint limits) and integrates `q ← q + q̇ Δt`. With `K Δt = 1` (the default) an
//! iteration is a Gauss–Newton step. Inequality rows get their position-level room the same way:
//! `K (l − c(q)) ≤ C q̇ ≤ K (u − c(q))`, a violated side clipped to the largest task error. It
//! stops when every task's error norm and every inequality row's violation is within tolerance,
//! when no task error nor the largest violation changed by more than the stall tolerance in the
//! last iteration, or at the iteration cap — and says which.

use super::SolverError;
use super::bounds::JointBounds;
use super::check::{check_finite_slice, check_len};
use super::householder::norm;
use super::prioritized::Solver;
use super::stack::TaskStack;

/// Something that gives task errors and Jacobians for a configuration: a robot model with its
/// targets, or any other differentiable map.
pub trait TaskModel {
    /// Error type of the evaluation; solver errors must convert into it.
    type Error: From<SolverError>;

    /// For configuration `q`, writes every level's Jacobian and, in place of its desired velocity,
    /// its task **error** `x* − x(q)` (task units) into `stack`; in place of the bounds of its
    /// inequality rows, the change of the row's value the step may make, `l − c(q) ≤ C δq ≤
    /// u − c(q)` (task units; ±∞ for no bound); and the gradient term `Σ κ_k ∇f_k(q)` (or
    /// clears it).
    fn evaluate(&mut self, q: &[f64], stack: &mut TaskStack) -> Result<(), Self::Error>;

    /// For configuration `q` after the last step (no solve follows): writes what the driver
    /// reads then, every task's error and every inequality row's room, as [`Self::evaluate`]
    /// does; the Jacobians and the gradient may be left as they are. A model whose Jacobians
    /// cost most of an evaluation saves them here (one iteration a frame: half its
    /// evaluations). Default: [`Self::evaluate`].
    fn measure(&mut self, q: &[f64], stack: &mut TaskStack) -> Result<(), Self::Error> {
        self.evaluate(q, stack)
    }

    /// Largest error norm task `task` (stack order, from 0) may ask for in one iteration, in
    /// task units, when it differs from [`DriverSettings::max_task_error`]: a task the caller
    /// lets move faster (a hand following a human) or slower than the rest. Default: none; a limit that is not > 0 (NaN, 0) is ignored.
    fn max_task_error(&self, task: usize) -> Option<f64> {
        let _ = task;
        None
    }

    /// Largest violation (task units) of inequality row `row` of level `level` one iteration
    /// is asked to remove, when it differs from [`DriverSettings::max_task_error`]:
    /// `f64::INFINITY` for a row that bounds a rate over the step rather than a position (its
    /// value at the unchanged posture is not a state to recover from, e.g. a ZMP whose motion
    /// stopping at once would throw it out). Default: none.
    fn max_inequality_correction(&self, level: usize, row: usize) -> Option<f64> {
        let _ = (level, row);
        None
    }
}

/// Settings of the position-level iteration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DriverSettings {
    /// Task-space gain `K` (1/s): `ẋ = K e`.
    pub gain: f64,
    /// Integration step `Δt` (s). `K Δt = 1` makes each iteration a full Gauss–Newton step.
    pub dt: f64,
    /// Stop when every task's error norm is at most this (task units, e.g. m). Default 1e-4.
    pub tolerance: f64,
    /// Stop when no task error norm changed by more than this in the last iteration. Default 1e-7.
    pub stall_tolerance: f64,
    /// Largest number of solves. Default 50.
    pub max_iterations: usize,
    /// Largest error norm a task may ask for in one iteration (task units, e.g. m); a larger
    /// error is scaled down to this, keeping its direction. Default 0.05.
    pub max_task_error: f64,
    /// Largest change of any joint in one iteration (rad or m): a velocity limit of
    /// `max_joint_step / dt` added to the joint bounds, so the clamping loop fixes a joint that
    /// would step further and lets the others take over its share of the tasks (a box trust
    /// region). Guards against the overshoot of Gauss–Newton steps near singular configurations.
    /// Default 0.05: on the NAO benchmark's stress files (conflicting levels) larger steps let
    /// the second-order effect of the lower levels' motion push the top level past 1e-4 m.
    pub max_joint_step: f64,
    /// Stop after this many iterations in a row that found no iterate better than the best so
    /// far, and return the best (see [`PositionDriver::run`]); 0 (default): never. For an IK
    /// run to convergence that may circle instead of stalling when it cannot meet a lower task:
    /// the G1's legs in Koenemann et al.'s method went round three iterates, one of them 1.1 mm
    /// off the held sole, until their cap of 200. Not for runs whose higher tasks must give a
    /// little while a lower one makes its way (their iterates are not "better" until the end).
    pub patience: usize,
}

impl DriverSettings {
    fn validate(&self) -> Result<(), SolverError> {
        for (name, value) in [
            ("gain", self.gain),
            ("dt", self.dt),
            ("tolerance", self.tolerance),
            ("stall_tolerance", self.stall_tolerance),
            ("max_task_error", self.max_task_error),
            ("max_joint_step", self.max_joint_step),
        ] {
            let unbounded_ok = matches!(name, "max_task_error" | "max_joint_step");
            let positive = matches!(name, "gain" | "dt") || unbounded_ok;
            let finite = value.is_finite() || unbounded_ok;
            if value.is_nan() || !finite || value < 0.0 || (positive && value == 0.0) {
                return Err(SolverError::InvalidParameter {
                    name,
                    value,
                    reason: "must be >= 0 and finite (gain, dt and the step limits > 0; the step limits may be infinite)",
                });
            }
        }
        Ok(())
    }
}

impl Default for DriverSettings {
    fn default() -> Self {
        Self {
            gain: 1.0,
            dt: 1.0,
            tolerance: 1e-4,
            stall_tolerance: 1e-7,
            max_iterations: 50,
            max_task_error: 0.05,
            max_joint_step: 0.05,
            patience: 0,
        }
    }
}

/// Why the iteration stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StopReason {
    /// Every task error is within tolerance.
    Converged,
    /// No task error changed by more than the stall tolerance in the last iteration, or
    /// [`DriverSettings::patience`] iterations found nothing better than the best iterate.
    Stalled,
    /// The iteration cap was reached.
    IterationLimit,
}

/// Outcome of a position-level solve.
#[derive(Debug, Clone, PartialEq)]
pub struct DriverReport {
    /// Number of velocity solves performed.
    pub iterations: usize,
    /// Why it stopped.
    pub stop: StopReason,
    task_errors: Vec<f64>,
}

impl DriverReport {
    /// Error norm of every task at the final `q`, in the stack's task order (task units).
    pub fn task_errors(&self) -> &[f64] {
        &self.task_errors
    }
}

/// The position-level driver: preallocated buffers for a stack shape.
#[derive(Debug, Clone)]
pub struct PositionDriver {
    settings: DriverSettings,
    /// First stacked row of every task, plus the total at the end.
    task_start: Vec<usize>,
    previous: Vec<f64>,
    /// The inequality violation of the previous iteration (task units).
    previous_violation: f64,
    /// The best iterate of this run so far, its task errors and inequality violation.
    best_q: Vec<f64>,
    best_errors: Vec<f64>,
    best_violation: f64,
    /// The caller's bounds with the per-iteration step limit as a velocity cap.
    step_bounds: JointBounds,
    /// The step of the whole run that damped levels are damped toward
    /// ([`PositionDriver::set_step_reference`]), and `q` at the run's start.
    step_reference: Vec<f64>,
    use_step_reference: bool,
    run_start: Vec<f64>,
    report: DriverReport,
}

impl PositionDriver {
    /// A driver for the stack of `solver`.
    pub fn new(solver: &Solver, settings: DriverSettings) -> Result<Self, SolverError> {
        settings.validate()?;
        let mut task_start = vec![0];
        for level in solver.stack().shape().levels() {
            for task in &level.tasks {
                task_start.push(task_start.last().copied().unwrap_or(0) + task.rows);
            }
        }
        let tasks = task_start.len() - 1;
        Ok(Self {
            settings,
            task_start,
            previous: vec![0.0; tasks],
            previous_violation: 0.0,
            best_q: vec![0.0; solver.stack().dof()],
            best_errors: vec![0.0; tasks],
            best_violation: 0.0,
            step_bounds: JointBounds::unbounded(solver.stack().dof()),
            step_reference: vec![0.0; solver.stack().dof()],
            use_step_reference: false,
            run_start: vec![0.0; solver.stack().dof()],
            report: DriverReport {
                iterations: 0,
                stop: StopReason::Converged,
                task_errors: vec![0.0; tasks],
            },
        })
    }

    /// The settings.
    pub fn settings(&self) -> &DriverSettings {
        &self.settings
    }

    /// The outcome of the last [`PositionDriver::run`].
    pub fn report(&self) -> &DriverReport {
        &self.report
    }

    /// Replaces the settings (e.g. a new `dt` for a frame that came late).
    pub fn set_settings(&mut self, settings: DriverSettings) -> Result<(), SolverError> {
        settings.validate()?;
        self.settings = settings;
        Ok(())
    }

    /// The step `δq` (rad or m, one per joint) the next runs are expected to take as a whole,
    /// e.g. the last frame's: each iteration's damped levels are then damped toward what is
    /// left of it, `(δq_ref − (q − q_start)) / Δt`, instead of toward rest (see
    /// [`TaskStack::damping_reference_mut`]). `None` (the default): toward rest. Either way
    /// [`PositionDriver::run`] writes the stack's damping reference before every solve.
    /// Errors: a wrong length or a non-finite entry.
    pub fn set_step_reference(&mut self, step: Option<&[f64]>) -> Result<(), SolverError> {
        match step {
            Some(step) => {
                check_len("step reference", self.step_reference.len(), step.len())?;
                check_finite_slice("step reference", step)?;
                self.step_reference.copy_from_slice(step);
                self.use_step_reference = true;
            }
            None => self.use_step_reference = false,
        }
        Ok(())
    }

    /// Moves `q` (in place, warm start) toward the model's targets. Every iterate, including the
    /// result, is within the position limits of `bounds`. The result is the last iterate, except
    /// when [`DriverSettings::patience`] stops the run: then it is the best one, comparing task
    /// errors in stack order (the first that differs by more than the stall tolerance decides,
    /// then the inequality violation; an error within the tolerance counts as met), and the
    /// model was evaluated there last; otherwise the stack holds the model's
    /// [`TaskModel::measure`] of the result. Errors: wrong sizes, a non-finite `q`,
    /// a non-finite Jacobian entry, task error or gradient from the model
    /// ([`SolverError::NonFinite`], naming the place), or the model's own error.
    // One function on purpose (~80 lines): the iteration read top to bottom (evaluate, keep
    // the best, the stop tests in their order, one step); split up, the order of the stop tests,
    // which decides the result, would be spread over several functions.
    pub fn run<M: TaskModel>(
        &mut self,
        solver: &mut Solver,
        model: &mut M,
        q: &mut [f64],
        bounds: &JointBounds,
    ) -> Result<&DriverReport, M::Error> {
        check_len("q", solver.stack().dof(), q.len())?;
        check_len("joint bounds", self.step_bounds.dof(), bounds.dof())?;
        check_finite_slice("q", q)?;
        self.step_bounds
            .copy_with_velocity_cap(bounds, self.settings.max_joint_step / self.settings.dt);
        check_len(
            "task rows",
            self.task_start[self.task_start.len() - 1],
            solver.stack().total_rows(),
        )?;
        let s = self.settings;
        let mut iterations = 0;
        let mut since_best = 0;
        self.run_start.copy_from_slice(q);
        let stop = loop {
            if iterations >= s.max_iterations {
                model.measure(q, solver.stack_mut())?;
            } else {
                model.evaluate(q, solver.stack_mut())?;
            }
            // Before measuring: a NaN task error must not pass the tolerance test as converged.
            solver.stack().check_finite()?;
            self.measure_errors(solver.stack());
            let violation = inequality_violation(solver.stack());
            // The best iterate is kept only for the patience rule to return.
            if s.patience > 0 {
                if iterations == 0 || self.beats_best(violation) {
                    self.best_q.copy_from_slice(q);
                    self.best_errors.copy_from_slice(&self.report.task_errors);
                    self.best_violation = violation;
                    since_best = 0;
                } else {
                    since_best += 1;
                }
            }
            let errors = &self.report.task_errors;
            if errors.iter().all(|&e| e <= s.tolerance) && violation <= s.tolerance {
                break StopReason::Converged;
            }
            if iterations > 0
                && errors
                    .iter()
                    .zip(&self.previous)
                    .all(|(e, p)| (e - p).abs() <= s.stall_tolerance)
                && (violation - self.previous_violation).abs() <= s.stall_tolerance
            {
                break StopReason::Stalled;
            }
            if s.patience > 0 && since_best >= s.patience {
                q.copy_from_slice(&self.best_q);
                model.evaluate(q, solver.stack_mut())?;
                self.report.task_errors.copy_from_slice(&self.best_errors);
                break StopReason::Stalled;
            }
            if iterations >= s.max_iterations {
                break StopReason::IterationLimit;
            }
            self.previous.copy_from_slice(errors);
            self.previous_violation = violation;
            self.set_velocities(model, solver.stack_mut());
            self.set_bounds(model, solver.stack_mut());
            self.set_damping_reference(q, solver.stack_mut());
            solver.solve(q, &self.step_bounds, s.dt)?;
            for (qi, v) in q.iter_mut().zip(solver.velocity()) {
                *qi += v * s.dt;
            }
            // The step interval already lands inside; this removes a last-ulp excursion (possible
            // only for a zero-width range entered from outside).
            bounds.clamp_position(q);
            iterations += 1;
        };
        self.report.iterations = iterations;
        self.report.stop = stop;
        Ok(&self.report)
    }

    /// Whether this iterate (task errors measured, inequality violation `violation`) is better
    /// than the best: the first task error, or last the violation, that differs from the best's
    /// by more than the stall tolerance decides, errors within the tolerance counting as met.
    fn beats_best(&self, violation: f64) -> bool {
        let s = &self.settings;
        let pairs = (self.report.task_errors.iter().zip(&self.best_errors))
            .chain([(&violation, &self.best_violation)]);
        for (now, best) in pairs {
            let (now, best) = (now.max(s.tolerance), best.max(s.tolerance));
            if (now - best).abs() > s.stall_tolerance {
                return now < best;
            }
        }
        false
    }

    /// `ẋ = K e`, with each task's error clipped to the model's limit for it or to
    /// `max_task_error`.
    fn set_velocities<M: TaskModel>(&self, model: &M, stack: &mut TaskStack) {
        let gain = self.settings.gain;
        let errors = &self.report.task_errors;
        let mut level = 0;
        for t in 0..errors.len() {
            let (start, end) = (self.task_start[t], self.task_start[t + 1]);
            let limit = model
                .max_task_error(t)
                .filter(|l| *l > 0.0)
                .unwrap_or(self.settings.max_task_error);
            while start >= stack.level_start(level + 1) {
                level += 1;
            }
            let scale = gain
                * if errors[t] > limit {
                    limit / errors[t]
                } else {
                    1.0
                };
            let offset = stack.level_start(level);
            let mut l = stack.level_mut(level);
            for e in &mut l.target_mut()[start - offset..end - offset] {
                *e *= scale;
            }
        }
    }

    /// `K (l − c(q)) ≤ C q̇ ≤ K (u − c(q))`, a violated side (`l − c > 0` or `u − c < 0`) clipped
    /// to `max_task_error` first.
    fn set_bounds<M: TaskModel>(&self, model: &M, stack: &mut TaskStack) {
        let gain = self.settings.gain;
        for level in 0..stack.level_count() {
            let mut l = stack.level_mut(level);
            let (_, lower, upper) = l.inequalities_mut();
            for (row, (lo, hi)) in lower.iter_mut().zip(upper.iter_mut()).enumerate() {
                let limit = (model.max_inequality_correction(level, row))
                    .filter(|l| *l > 0.0)
                    .unwrap_or(self.settings.max_task_error);
                *lo = gain * lo.min(limit);
                *hi = gain * hi.max(-limit);
            }
        }
    }

    /// What is left of the step reference after the iterations so far, per `Δt`; zero without
    /// one.
    fn set_damping_reference(&self, q: &[f64], stack: &mut TaskStack) {
        let reference = stack.damping_reference_mut();
        if !self.use_step_reference {
            reference.fill(0.0);
            return;
        }
        let dt = self.settings.dt;
        let parts = (self.step_reference.iter()).zip(q.iter().zip(&self.run_start));
        for (r, (step, (qi, q0))) in reference.iter_mut().zip(parts) {
            *r = (step - (qi - q0)) / dt;
        }
    }

    fn measure_errors(&mut self, stack: &TaskStack) {
        let errors = stack.stacked_target();
        for (t, e) in self.report.task_errors.iter_mut().enumerate() {
            *e = norm(&errors[self.task_start[t]..self.task_start[t + 1]]);
        }
    }
}

/// The largest position-level violation of an inequality row: `max(0, l − c(q), c(q) − u)`, with
/// the model's bounds written relative to the current value (task units).
fn inequality_violation(stack: &TaskStack) -> f64 {
    (0..stack.level_count())
        .flat_map(|j| {
            let (lower, upper) = stack.bounds(j);
            lower.iter().zip(upper).map(|(l, u)| l.max(-u).max(0.0))
        })
        .fold(0.0, f64::max)
}
