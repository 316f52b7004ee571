//! The position-level driver: per-task error limits ([`TaskModel::max_task_error`]), per-row
//! inequality corrections ([`TaskModel::max_inequality_correction`]) and the patience rule
//! ([`DriverSettings::patience`]).

use taskstack::solver::driver::{
    DriverReport, DriverSettings, PositionDriver, StopReason, TaskModel,
};
use taskstack::solver::{JointBounds, Solver, SolverError, StackShape, TaskStack};

/// Two joints, two tasks of one level, `x_k = q_k` with target 1; task 1's error limit is
/// `limit` when given.
struct Pair {
    limit: Option<f64>,
}

impl TaskModel for Pair {
    type Error = SolverError;
    fn evaluate(&mut self, q: &[f64], stack: &mut TaskStack) -> Result<(), SolverError> {
        let mut level = stack.level_mut(0);
        level.set_row(0, &[1.0, 0.0], 1.0 - q[0])?;
        level.set_row(1, &[0.0, 1.0], 1.0 - q[1])?;
        stack.clear_gradient();
        Ok(())
    }

    fn max_task_error(&self, task: usize) -> Option<f64> {
        if task == 1 { self.limit } else { None }
    }
}

/// One Gauss–Newton step (K Δt = 1) of `model` on a stack of `shape` from `q`, the driver's
/// default error limit 0.05, no joint bounds.
fn one_iteration<M: TaskModel<Error = SolverError>>(
    shape: &StackShape,
    model: &mut M,
    q: &mut [f64],
) {
    let mut solver = Solver::new(shape).unwrap();
    let settings = DriverSettings {
        max_iterations: 1,
        max_joint_step: f64::INFINITY,
        ..DriverSettings::default()
    };
    let mut driver = PositionDriver::new(&solver, settings).unwrap();
    let bounds = JointBounds::unbounded(q.len());
    driver.run(&mut solver, model, q, &bounds).unwrap();
}

/// One step of [`Pair`] from q = 0.
fn one_step(limit: Option<f64>) -> [f64; 2] {
    let shape = StackShape::new(2).with_level("x", &[("a", 1), ("b", 1)]);
    let mut q = [0.0, 0.0];
    one_iteration(&shape, &mut Pair { limit }, &mut q);
    q
}

#[test]
fn a_task_with_its_own_limit_steps_by_that_limit() {
    // Both errors are 1: the first task steps by the driver's 0.05, the second by its own 0.2.
    let q = one_step(Some(0.2));
    assert!(
        (q[0] - 0.05).abs() < 1e-12 && (q[1] - 0.2).abs() < 1e-12,
        "{q:?}"
    );
    // A limit past the error does not clip it: the second task is reached in one step.
    let q = one_step(Some(f64::INFINITY));
    assert!(
        (q[0] - 0.05).abs() < 1e-12 && (q[1] - 1.0).abs() < 1e-12,
        "{q:?}"
    );
}

#[test]
fn a_limit_that_is_not_positive_falls_back_to_the_driver_setting() {
    for limit in [None, Some(f64::NAN), Some(0.0), Some(-1.0)] {
        let q = one_step(limit);
        assert!(
            (q[0] - 0.05).abs() < 1e-12 && (q[1] - 0.05).abs() < 1e-12,
            "{limit:?}: {q:?}"
        );
    }
}

/// One joint, `x(q) = q`, target 0.1, but the model reports the slope as 0.4: each full
/// Gauss–Newton step (errors clipped to 0.05) overshoots. By hand from q = 0: q₁ = 0.05/0.4 =
/// 0.125 (error −0.025, the smallest), q₂ = 0.0625, q₃ = 0.15625, q₄ = 0.03125, then q
/// alternates between 0.15625 and 0.03125 (errors 0.05625 and 0.06875) and never stalls.
struct Overshooting;

impl TaskModel for Overshooting {
    type Error = SolverError;
    fn evaluate(&mut self, q: &[f64], stack: &mut TaskStack) -> Result<(), SolverError> {
        stack.level_mut(0).set_row(0, &[0.4], 0.1 - q[0])?;
        stack.clear_gradient();
        Ok(())
    }
}

fn run_overshooting(patience: usize) -> (f64, DriverReport) {
    let shape = StackShape::new(1).with_level("x", &[("x", 1)]);
    let mut solver = Solver::new(&shape).unwrap();
    let settings = DriverSettings {
        max_joint_step: f64::INFINITY,
        patience,
        ..DriverSettings::default()
    };
    let mut driver = PositionDriver::new(&solver, settings).unwrap();
    let mut q = [0.0];
    let bounds = JointBounds::unbounded(1);
    let report = (driver.run(&mut solver, &mut Overshooting, &mut q, &bounds))
        .unwrap()
        .clone();
    (q[0], report)
}

#[test]
fn patience_ends_a_circling_run_at_its_best_iterate() {
    let (q, report) = run_overshooting(10);
    assert!((q - 0.125).abs() < 1e-12, "{q}");
    assert_eq!(report.stop, StopReason::Stalled);
    assert_eq!(report.iterations, 11);
    assert!((report.task_errors()[0] - 0.025).abs() < 1e-12);
    // Without patience the same run circles to the cap and ends on a worse iterate.
    let (q, report) = run_overshooting(0);
    assert_eq!(report.stop, StopReason::IterationLimit);
    assert!(
        (q - 0.15625).abs() < 1e-12 || (q - 0.03125).abs() < 1e-12,
        "{q}"
    );
}

/// One joint, no task, one inequality row `q ≥ 1` (violated by 1 at q = 0), whose largest
/// correction per iteration is `limit` when given.
struct Floor {
    limit: Option<f64>,
}

impl TaskModel for Floor {
    type Error = SolverError;
    fn evaluate(&mut self, q: &[f64], stack: &mut TaskStack) -> Result<(), SolverError> {
        let mut level = stack.level_mut(0);
        let (mut jacobian, lower, upper) = level.inequalities_mut();
        jacobian[(0, 0)] = 1.0;
        (lower[0], upper[0]) = (1.0 - q[0], f64::INFINITY);
        stack.clear_gradient();
        Ok(())
    }

    fn max_inequality_correction(&self, level: usize, row: usize) -> Option<f64> {
        assert_eq!((level, row), (0, 0));
        self.limit
    }
}

#[test]
fn an_inequality_row_may_take_its_whole_room_in_one_step() {
    let shape = StackShape::new(1).with_mixed_level("floor", &[], &[("q >= 1", 1)]);
    let step = |limit| {
        let mut q = [0.0];
        one_iteration(&shape, &mut Floor { limit }, &mut q);
        q[0]
    };
    // The driver's 0.05 by default (and for a limit that is not > 0); the whole violation
    // with an unbounded correction.
    for (limit, expected) in [(None, 0.05), (Some(0.0), 0.05), (Some(f64::INFINITY), 1.0)] {
        let q = step(limit);
        assert!((q - expected).abs() < 1e-12, "{limit:?}: {q}");
    }
}

/// [`Pair`] counting its calls: the Jacobian writes of `evaluate` and the errors alone of
/// `measure`.
#[derive(Default)]
struct Counted {
    evaluations: usize,
    measures: usize,
}

impl TaskModel for Counted {
    type Error = SolverError;
    fn evaluate(&mut self, q: &[f64], stack: &mut TaskStack) -> Result<(), SolverError> {
        self.evaluations += 1;
        Pair { limit: None }.evaluate(q, stack)
    }

    fn measure(&mut self, q: &[f64], stack: &mut TaskStack) -> Result<(), SolverError> {
        self.measures += 1;
        let mut level = stack.level_mut(0);
        let (_, error) = level.rows_mut(0, 2);
        error.copy_from_slice(&[1.0 - q[0], 1.0 - q[1]]);
        Ok(())
    }
}

#[test]
fn the_iterate_after_the_last_step_is_measured_not_evaluated() {
    // Three steps of 0.05 toward 1 (no tolerance met): three evaluations before the steps, one
    // measure of the result, whose errors the report holds (1 − 0.15 per task).
    let shape = StackShape::new(2).with_level("x", &[("a", 1), ("b", 1)]);
    let mut solver = Solver::new(&shape).unwrap();
    let settings = DriverSettings {
        max_iterations: 3,
        max_joint_step: f64::INFINITY,
        ..DriverSettings::default()
    };
    let mut driver = PositionDriver::new(&solver, settings).unwrap();
    let (mut q, mut model) = ([0.0, 0.0], Counted::default());
    let bounds = JointBounds::unbounded(2);
    let report = driver
        .run(&mut solver, &mut model, &mut q, &bounds)
        .unwrap();
    assert_eq!((model.evaluations, model.measures), (3, 1));
    assert_eq!(report.stop, StopReason::IterationLimit);
    for e in report.task_errors() {
        assert!((e - 0.85).abs() < 1e-12, "{:?}", report.task_errors());
    }
}
