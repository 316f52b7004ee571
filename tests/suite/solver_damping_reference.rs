//! Damping toward a reference velocity ([`TaskStack::damping_reference_mut`]): a damped level
//! solves `min ‖J q̇ − ẋ‖² + μ² ‖q̇ − q̇_ref‖²` over its row space, checked against the closed
//! form `(JᵀJ + μ² I)⁻¹ (Jᵀ ẋ + μ² P q̇_ref)` (`P` the projector onto the row space of `J`)
//! computed densely with nalgebra; an undamped level ignores the reference; the driver's step
//! reference is what is left of a frame's step per iteration.

use nalgebra::{DMatrix, DVector};
use taskstack::solver::driver::{DriverSettings, PositionDriver, TaskModel};
use taskstack::solver::{JointBounds, Solver, SolverError, StackShape, TaskStack};

/// Level 0: two rows over four joints, the second nearly dependent on the first (smallest
/// singular value ≈ 4e-3, below the default damping threshold 2e-2). Level 1: one row.
fn near_singular_stack() -> (Vec<[f64; 4]>, Vec<f64>) {
    let rows = vec![
        [1.0, 0.5, -0.2, 0.3],
        [1.0, 0.5, -0.2, 0.3 + 8e-3],
        [0.1, -0.4, 1.0, 0.2],
    ];
    (rows, vec![0.2, -0.1, 0.05])
}

fn solver_for(rows: &[[f64; 4]], targets: &[f64]) -> Solver {
    let mut solver = Solver::new(&StackShape::from_level_rows(4, &[2, 1])).unwrap();
    for (r, (row, &x)) in rows.iter().zip(targets).enumerate() {
        let (level, local) = if r < 2 { (0, r) } else { (1, 0) };
        let stack = solver.stack_mut();
        stack.level_mut(level).set_row(local, row, x).unwrap();
    }
    solver
}

#[test]
fn a_damped_level_is_the_closed_form_minimizer_toward_the_reference() {
    let (rows, targets) = near_singular_stack();
    let reference = [0.4, -0.3, 0.2, 0.9];
    let mut solver = solver_for(&rows, &targets);
    solver
        .stack_mut()
        .damping_reference_mut()
        .copy_from_slice(&reference);
    let solution = solver.solve_unbounded().unwrap();
    let mu = solution.report.levels()[0].damping;
    assert!(mu > 0.0, "level 0 must be damped for this test");
    let velocity = DVector::from_column_slice(solution.velocity);

    let j = DMatrix::from_fn(2, 4, |r, c| rows[r][c]);
    let x = DVector::from_column_slice(&targets[..2]);
    let r = DVector::from_column_slice(&reference);
    // P = Jᵀ (J Jᵀ)⁻¹ J: J has full row rank (its rows differ by 8e-3 in one entry).
    let p = j.transpose() * (&j * j.transpose()).try_inverse().unwrap() * &j;
    // By LU: nalgebra's 4 × 4 `try_inverse` is a cofactor formula, 1e-8 off at this condition.
    let normal = (j.transpose() * &j + DMatrix::identity(4, 4) * mu * mu).lu();
    let expected = (normal.solve(&(j.transpose() * &x + &p * &r * (mu * mu)))).unwrap();
    // Level 1 acts in J's null space only, so the row-space part is level 0's alone.
    let got = &p * &velocity;
    assert!(
        (&got - &expected).norm() < 1e-10,
        "got {got:?}, expected {expected:?}"
    );

    // Toward rest (no reference) the same level gives the plain damped solution, which differs.
    let mut at_rest = solver_for(&rows, &targets);
    let rest = DVector::from_column_slice(at_rest.solve_unbounded().unwrap().velocity);
    let expected_rest = normal.solve(&(j.transpose() * &x)).unwrap();
    assert!((&p * &rest - &expected_rest).norm() < 1e-10);
    assert!((&expected - &expected_rest).norm() > 1e-3);
}

#[test]
fn an_undamped_level_ignores_the_reference() {
    let (mut rows, targets) = near_singular_stack();
    rows[1] = [0.0, 1.0, 0.3, -0.5]; // well conditioned now
    let mut plain = solver_for(&rows, &targets);
    let expected = plain.solve_unbounded().unwrap().velocity.to_vec();
    assert!(plain.report().levels().iter().all(|l| l.damping == 0.0));
    let mut with_reference = solver_for(&rows, &targets);
    (with_reference.stack_mut().damping_reference_mut()).copy_from_slice(&[3.0, -2.0, 1.0, 4.0]);
    let got = with_reference.solve_unbounded().unwrap().velocity;
    for (g, e) in got.iter().zip(&expected) {
        assert!((g - e).abs() < 1e-12, "{got:?} vs {expected:?}");
    }
}

#[test]
fn a_non_finite_reference_is_refused_by_name() {
    let (rows, targets) = near_singular_stack();
    let mut solver = solver_for(&rows, &targets);
    solver.stack_mut().damping_reference_mut()[2] = f64::NAN;
    let error = solver.solve_unbounded().unwrap_err();
    assert!(
        matches!(&error, SolverError::NonFinite { what, .. } if what.contains("damping reference")),
        "{error:?}"
    );
}

/// A linear map `x = J q` with targets: its error is `x* − J q` at any `q`.
struct Linear {
    rows: Vec<[f64; 4]>,
    targets: Vec<f64>,
}

impl TaskModel for Linear {
    type Error = SolverError;

    fn evaluate(&mut self, q: &[f64], stack: &mut TaskStack) -> Result<(), SolverError> {
        for (r, (row, &x)) in self.rows.iter().zip(&self.targets).enumerate() {
            let (level, local) = if r < 2 { (0, r) } else { (1, 0) };
            let value: f64 = row.iter().zip(q).map(|(a, b)| a * b).sum();
            stack.level_mut(level).set_row(local, row, x - value)?;
        }
        stack.clear_gradient();
        Ok(())
    }
}

#[test]
fn the_driver_damps_each_iteration_toward_what_is_left_of_the_step_reference() {
    let (rows, targets) = near_singular_stack();
    let step = [0.04, -0.03, 0.02, 0.09];
    let settings = DriverSettings {
        dt: 0.5,
        gain: 2.0,
        max_iterations: 1,
        max_joint_step: f64::INFINITY,
        max_task_error: f64::INFINITY,
        ..DriverSettings::default()
    };
    let bounds = JointBounds::unbounded(4);
    let run = |reference: Option<&[f64]>| {
        let mut solver = solver_for(&rows, &targets);
        let mut driver = PositionDriver::new(&solver, settings).unwrap();
        driver.set_step_reference(reference).unwrap();
        let mut model = Linear {
            rows: rows.clone(),
            targets: targets.clone(),
        };
        let mut q = [0.0; 4];
        driver
            .run(&mut solver, &mut model, &mut q, &bounds)
            .unwrap();
        (q, solver)
    };
    // One iteration from q = 0: the solve's reference is the whole step per Δt, so the step
    // equals the solver's own answer for that reference (checked against the closed form above).
    let (q, _) = run(Some(&step));
    let mut direct = solver_for(&rows, &targets);
    for (t, g) in [0.2, -0.1, 0.05].iter().zip([0, 1, 2]) {
        let (level, local) = if g < 2 { (0, g) } else { (1, 0) };
        let row = rows[g];
        direct
            .stack_mut()
            .level_mut(level)
            .set_row(local, &row, t * settings.gain)
            .unwrap();
    }
    let per_dt: Vec<f64> = step.iter().map(|s| s / settings.dt).collect();
    direct
        .stack_mut()
        .damping_reference_mut()
        .copy_from_slice(&per_dt);
    let v = direct.solve_unbounded().unwrap().velocity.to_vec();
    for (qi, vi) in q.iter().zip(&v) {
        assert!((qi - vi * settings.dt).abs() < 1e-12, "{q:?} vs {v:?}");
    }
    let (q_rest, _) = run(None);
    assert!(q.iter().zip(&q_rest).any(|(a, b)| (a - b).abs() > 1e-4));
    // Typed errors for a reference of the wrong size or with a NaN.
    let solver = solver_for(&rows, &targets);
    let mut driver = PositionDriver::new(&solver, settings).unwrap();
    assert!(driver.set_step_reference(Some(&[0.0; 3])).is_err());
    assert!(
        driver
            .set_step_reference(Some(&[0.0, f64::NAN, 0.0, 0.0]))
            .is_err()
    );
}
