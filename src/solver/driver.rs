//! Position-level IK: iterate the velocity solve until position targets are reached.
//!
//! Each iteration asks a [`TaskModel`] for the task errors `e_j = x*_j − x_j(q)` and Jacobians at
//! the current `q`, sets `ẋ_j = K e_j`, solves the stack (with the clamping loop, so every iterate
//! is within the joint limits) and integrates `q ← q + q̇ Δt`. With `K Δt = 1` (the default) an
//! iteration is a Gauss–Newton step. It stops when every task's error norm is within tolerance,
//! when no task error changed by more than the stall tolerance in the last iteration, or at the
//! iteration cap — and says which.

use super::SolverError;
use super::bounds::JointBounds;
use super::householder::norm;
use super::prioritized::Solver;
use super::stack::{TaskStack, check_len};

/// Something that gives task errors and Jacobians for a configuration: a robot model with its
/// targets, or any other differentiable map.
pub trait TaskModel {
    /// Error type of the evaluation; solver errors must convert into it.
    type Error: From<SolverError>;

    /// For configuration `q`, writes every level's Jacobian and, in place of its desired velocity,
    /// its task **error** `x* − x(q)` (task units) into `stack`; and the gradient term
    /// `Σ κ_k ∇f_k(q)` (or clears it).
    fn evaluate(&mut self, q: &[f64], stack: &mut TaskStack) -> Result<(), Self::Error>;
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
}

impl Default for DriverSettings {
    fn default() -> Self {
        Self {
            gain: 1.0,
            dt: 1.0,
            tolerance: 1e-4,
            stall_tolerance: 1e-7,
            max_iterations: 50,
        }
    }
}

/// Why the iteration stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StopReason {
    /// Every task error is within tolerance.
    Converged,
    /// No task error changed by more than the stall tolerance in the last iteration.
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
    report: DriverReport,
}

impl PositionDriver {
    /// A driver for the stack of `solver`.
    pub fn new(solver: &Solver, settings: DriverSettings) -> Result<Self, SolverError> {
        for (name, value) in [
            ("gain", settings.gain),
            ("dt", settings.dt),
            ("tolerance", settings.tolerance),
            ("stall_tolerance", settings.stall_tolerance),
        ] {
            if !(value.is_finite() && value >= 0.0)
                || (value == 0.0 && matches!(name, "gain" | "dt"))
            {
                return Err(SolverError::InvalidParameter {
                    name,
                    value,
                    reason: "must be finite and >= 0 (gain and dt > 0)",
                });
            }
        }
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

    /// Moves `q` (in place, warm start) toward the model's targets. Every iterate, including the
    /// result, is within the position limits of `bounds`.
    pub fn run<M: TaskModel>(
        &mut self,
        solver: &mut Solver,
        model: &mut M,
        q: &mut [f64],
        bounds: &JointBounds,
    ) -> Result<&DriverReport, M::Error> {
        check_len("q", solver.stack().dof(), q.len())?;
        check_len(
            "task rows",
            self.task_start[self.task_start.len() - 1],
            solver.stack().total_rows(),
        )?;
        let s = self.settings;
        let mut iterations = 0;
        let stop = loop {
            model.evaluate(q, solver.stack_mut())?;
            self.measure_errors(solver.stack());
            let errors = &self.report.task_errors;
            if errors.iter().all(|&e| e <= s.tolerance) {
                break StopReason::Converged;
            }
            if iterations > 0
                && errors
                    .iter()
                    .zip(&self.previous)
                    .all(|(e, p)| (e - p).abs() <= s.stall_tolerance)
            {
                break StopReason::Stalled;
            }
            if iterations >= s.max_iterations {
                break StopReason::IterationLimit;
            }
            self.previous.copy_from_slice(errors);
            let stack = solver.stack_mut();
            for level in 0..stack.level_count() {
                stack
                    .level_mut(level)
                    .target_mut()
                    .iter_mut()
                    .for_each(|e| *e *= s.gain);
            }
            solver.solve(q, bounds, s.dt)?;
            for (qi, v) in q.iter_mut().zip(solver.velocity()) {
                *qi += v * s.dt;
            }
            // The step interval already lands inside; this only removes a last-ulp excursion.
            bounds.clamp_position(q);
            iterations += 1;
        };
        self.report.iterations = iterations;
        self.report.stop = stop;
        Ok(&self.report)
    }

    fn measure_errors(&mut self, stack: &TaskStack) {
        let errors = stack.stacked_target();
        for (t, e) in self.report.task_errors.iter_mut().enumerate() {
            *e = norm(&errors[self.task_start[t]..self.task_start[t + 1]]);
        }
    }
}
