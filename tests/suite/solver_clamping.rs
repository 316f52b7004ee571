//! Property tests of the clamping loop: limits always hold; nothing changes when none binds.

use crate::solver_common;

use proptest::prelude::*;
use solver_common::{Rng, problems, random_bounds};
use taskstack::solver::JointBounds;

proptest! {
    #![proptest_config(ProptestConfig { cases: 512, ..ProptestConfig::default() })]

    /// q + q̇Δt is within the position limits and |q̇| within the velocity limits, in floating point,
    /// for every case.
    #[test]
    fn result_never_violates_a_limit((problem, seed) in problems(), dt_exp in -3i32..=1, scale in 0.1f64..100.0) {
        let mut rng = Rng::new(seed);
        let (bounds, q) = random_bounds(&mut rng, problem.n);
        let mut scaled = problem.clone();
        for level in &mut scaled.levels {
            level.target *= scale;
        }
        let mut solver = scaled.solver(true);
        let dt = 10f64.powi(dt_exp);
        let report = solver.solve(&q, &bounds, dt).unwrap().report;
        prop_assert!(report.clamping_iterations() <= problem.n + 1);
        let v = solver.velocity();
        for i in 0..problem.n {
            let next = q[i] + v[i] * dt;
            prop_assert!(next >= bounds.lower()[i] && next <= bounds.upper()[i],
                "joint {i}: {} + {}·{dt} = {next} outside [{}, {}]", q[i], v[i], bounds.lower()[i], bounds.upper()[i]);
            prop_assert!(v[i].abs() <= bounds.velocity()[i], "joint {i}: |{}| > {}", v[i], bounds.velocity()[i]);
            prop_assert!(v[i].is_finite());
        }
    }

    /// A configuration outside its limits is brought back inside in one step (within a few ulps for
    /// a zero-width range, where an exact landing may not exist in floating point).
    #[test]
    fn start_outside_the_limits_lands_inside((problem, seed) in problems()) {
        let mut rng = Rng::new(seed);
        let (bounds, mut q) = random_bounds(&mut rng, problem.n);
        for (i, qi) in q.iter_mut().enumerate() {
            if rng.below(2) == 0 {
                *qi = if rng.below(2) == 0 { bounds.upper()[i] + rng.uniform(0.0, 2.0) } else { bounds.lower()[i] - rng.uniform(0.0, 2.0) };
            }
        }
        let mut solver = problem.solver(true);
        let dt = 0.05;
        solver.solve(&q, &bounds, dt).unwrap();
        for (i, v) in solver.velocity().iter().enumerate() {
            let next = q[i] + v * dt;
            if bounds.lower()[i] == bounds.upper()[i] {
                prop_assert!((next - bounds.lower()[i]).abs() <= 8.0 * f64::EPSILON * next.abs().max(1.0));
                continue;
            }
            prop_assert!(next >= bounds.lower()[i] && next <= bounds.upper()[i], "joint {i}: {} + {v}·{dt} = {next} outside [{}, {}] vmax {}", q[i], bounds.lower()[i], bounds.upper()[i], bounds.velocity()[i]);
        }
    }

    /// When no limit binds, the clamped solve equals the unbounded one.
    #[test]
    fn no_binding_limit_means_no_change((problem, seed) in problems(), margin in 1e-6f64..1.0) {
        let mut rng = Rng::new(seed);
        let mut solver = problem.solver(true);
        solver.solve_unbounded().unwrap();
        let free = solver.velocity().to_vec();
        let dt = 0.1;
        let q: Vec<f64> = (0..problem.n).map(|_| rng.uniform(-1.0, 1.0)).collect();
        // Limits strictly beyond where the free solution goes.
        let lower: Vec<f64> = (0..problem.n).map(|i| q[i] + (free[i] * dt).min(0.0) - margin).collect();
        let upper: Vec<f64> = (0..problem.n).map(|i| q[i] + (free[i] * dt).max(0.0) + margin).collect();
        let velocity: Vec<f64> = free.iter().map(|v| v.abs() + margin).collect();
        let bounds = JointBounds::with_velocity(&lower, &upper, &velocity).unwrap();
        let report = solver.solve(&q, &bounds, dt).unwrap().report;
        prop_assert!(report.clamped_joints().is_empty());
        prop_assert_eq!(solver.velocity(), &free[..]);
    }

    /// Clamped joints sit exactly on a bound of their step interval.
    #[test]
    fn clamped_joints_move_at_a_bound((problem, seed) in problems()) {
        let mut rng = Rng::new(seed);
        let (bounds, q) = random_bounds(&mut rng, problem.n);
        let mut solver = problem.solver(true);
        let dt = 0.01;
        let clamped = solver.solve(&q, &bounds, dt).unwrap().report.clamped_joints().to_vec();
        let v = solver.velocity();
        for &i in &clamped {
            let at_position = (q[i] + v[i] * dt - bounds.lower()[i]).abs() < 1e-9
                || (q[i] + v[i] * dt - bounds.upper()[i]).abs() < 1e-9;
            let at_velocity = (v[i].abs() - bounds.velocity()[i]).abs() < 1e-12;
            prop_assert!(at_position || at_velocity, "joint {i} clamped but moves at {}", v[i]);
        }
    }
}

/// Hand-checkable: one level asks q̇0 + q̇1 = 2 with joint 0 allowed only 0.5 rad/s; the clamping
/// loop fixes q̇0 = 0.5 and gives joint 1 the rest, 1.5 rad/s.
#[test]
fn clamped_joint_contribution_moves_to_the_right_hand_side() {
    let shape = taskstack::solver::StackShape::from_level_rows(2, &[1]);
    let mut solver = taskstack::solver::Solver::new(&shape).unwrap();
    solver
        .stack_mut()
        .level_mut(0)
        .set_row(0, &[1.0, 1.0], 2.0)
        .unwrap();
    let bounds = JointBounds::with_velocity(&[-10.0, -10.0], &[10.0, 10.0], &[0.5, 5.0]).unwrap();
    let report = solver.solve(&[0.0, 0.0], &bounds, 0.1).unwrap().report;
    assert_eq!(report.clamped_joints(), &[0]);
    assert_eq!(report.clamping_iterations(), 2);
    assert!(report.levels()[0].feasible);
    let v = solver.velocity();
    assert!(
        (v[0] - 0.5).abs() < 1e-15 && (v[1] - 1.5).abs() < 1e-12,
        "{v:?}"
    );
}

/// Regression (found by `hardening_solver`): rows of 1e140 left rounding noise of ~1e124 after the
/// projection, which the absolute rank tolerance counted as a direction; the huge coefficient on
/// it overflowed to NaN in the clamping loop. All joints are locked ([0, 0]), so the only right
/// answer is q̇ = 0.
#[test]
fn rows_of_huge_scale_give_a_finite_step() {
    let shape = taskstack::solver::StackShape::from_level_rows(6, &[2, 1, 1]);
    let mut solver = taskstack::solver::Solver::new(&shape).unwrap();
    let row = |entries: &[(usize, f64)]| {
        let mut r = [0.0; 6];
        for &(i, v) in entries {
            r[i] = v;
        }
        r
    };
    let stack = solver.stack_mut();
    stack
        .level_mut(0)
        .set_row(0, &row(&[(4, 3.3e140)]), 0.0)
        .unwrap();
    stack
        .level_mut(0)
        .set_row(1, &row(&[(4, 7.9e50)]), 2.2e132)
        .unwrap();
    stack
        .level_mut(1)
        .set_row(0, &row(&[(2, -5.8e136), (5, 5.3e64)]), 0.0)
        .unwrap();
    stack
        .level_mut(2)
        .set_row(0, &row(&[(5, 3.2e139)]), 0.0)
        .unwrap();
    let bounds = JointBounds::with_velocity(&[0.0; 6], &[0.0; 6], &[1.0; 6]).unwrap();
    let free = solver.solve_unbounded().unwrap();
    assert_eq!(
        free.report.levels()[0].rank,
        1,
        "two rows along one column have rank 1"
    );
    assert!(
        free.velocity.iter().all(|v| v.is_finite()),
        "{:?}",
        free.velocity
    );
    let solution = solver.solve(&[0.0; 6], &bounds, 1.0).unwrap();
    assert!(
        solution.velocity.iter().all(|v| *v == 0.0),
        "{:?}",
        solution.velocity
    );
}
