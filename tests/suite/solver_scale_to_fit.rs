//! `Settings::scale_to_fit` against hand-computed solutions: each level's desired velocity (and
//! the gradient term) is scaled, highest first, by the largest factor in [0, 1] that keeps the
//! running sum inside every joint's step interval; a joint that a position limit blocks is
//! clamped first. The parts are one factorization solved for several right-hand sides.

use approx::assert_relative_eq;
use taskstack::solver::{JointBounds, Settings, Solver, StackShape};

/// A solver over `n` joints with one single-row level per `(row, target)`, scaling to fit.
fn solver(n: usize, levels: &[(&[f64], f64)], gradient: &[f64]) -> Solver {
    let names: Vec<String> = (0..levels.len()).map(|j| format!("t{j}")).collect();
    let shape = names.iter().fold(StackShape::new(n), |s, name| {
        s.with_level(name, &[(name, 1)])
    });
    let settings = Settings {
        scale_to_fit: true,
        ..Settings::default()
    };
    let mut solver = Solver::with_settings(&shape, settings).unwrap();
    for (name, (row, target)) in names.iter().zip(levels) {
        let (mut jacobian, desired) = solver.stack_mut().task_mut(name).unwrap();
        for (i, &v) in row.iter().enumerate() {
            jacobian[(0, i)] = v;
        }
        desired[0] = *target;
    }
    solver.stack_mut().gradient_mut().copy_from_slice(gradient);
    solver
}

/// Wide position limits around q = 0 and the given velocity limits (rad/s).
fn velocity_bounds(velocity: &[f64]) -> JointBounds {
    let wide = vec![100.0; velocity.len()];
    let low: Vec<f64> = wide.iter().map(|w| -w).collect();
    JointBounds::with_velocity(&low, &wide, velocity).unwrap()
}

#[test]
fn each_level_is_scaled_after_the_ones_above() {
    // Level 0: q̇0 + q̇1 = 2, its part (1, 1) fits |q̇| ≤ 1.5: scale 1. Level 1: q̇0 − q̇1 = 2 in
    // the null space of level 0, part (1, −1); (1, 1) + s (1, −1) keeps q̇0 ≤ 1.5 for s ≤ 0.5.
    let mut s = solver(2, &[(&[1.0, 1.0], 2.0), (&[1.0, -1.0], 2.0)], &[0.0, 0.0]);
    let v = s
        .solve(&[0.0, 0.0], &velocity_bounds(&[1.5, 1.5]), 0.01)
        .unwrap()
        .velocity
        .to_vec();
    assert_relative_eq!(v[0], 1.5, epsilon = 1e-12);
    assert_relative_eq!(v[1], 0.5, epsilon = 1e-12);
}

#[test]
fn the_gradient_term_is_scaled_last() {
    // Level 0: q̇0 = 1 (fits). The gradient (0, 4, 0) lies in its null space; with |q̇1| ≤ 2 its
    // scale is 0.5: q̇ = (1, 2, 0).
    let mut s = solver(3, &[(&[1.0, 0.0, 0.0], 1.0)], &[0.0, 4.0, 0.0]);
    let solution = s
        .solve(&[0.0; 3], &velocity_bounds(&[2.0; 3]), 0.01)
        .unwrap();
    let v = solution.velocity.to_vec();
    assert_relative_eq!(solution.report.gradient_scale(), 0.5, epsilon = 1e-12);
    for (got, want) in v.iter().zip([1.0, 2.0, 0.0]) {
        assert_relative_eq!(*got, want, epsilon = 1e-12);
    }
}

#[test]
fn a_joint_at_its_position_limit_is_clamped_and_the_rest_refitted() {
    // q1 sits at its upper limit 0: the level's part (1, 1) would push it through, so q1 is
    // clamped at 0 and the level is solved by q0 alone: q̇0 = 2 (within 3).
    let mut s = solver(2, &[(&[1.0, 1.0], 2.0)], &[0.0, 0.0]);
    let bounds = JointBounds::with_velocity(&[-1.0, -1.0], &[1.0, 0.0], &[3.0, 3.0]).unwrap();
    let solution = s.solve(&[0.0, 0.0], &bounds, 0.01).unwrap();
    assert_eq!(solution.report.clamped_joints(), &[1]);
    let v = solution.velocity.to_vec();
    assert_relative_eq!(v[0], 2.0, epsilon = 1e-12);
    assert_eq!(v[1], 0.0);
}

#[test]
fn a_rank_deficient_level_is_solved_for_every_part_on_one_factorization() {
    // Level 0 asks q̇0 + q̇1 = 2 and = 4 (the same row twice): its least-squares solve (the
    // stacked-matrix branch, rank 1 of 2 rows) gives q̇0 + q̇1 = 3, part (1.5, 1.5), which fits
    // |q̇| ≤ 2. Level 1: q̇0 − q̇1 = 2, part (1, −1); 1.5 + s ≤ 2 gives s = 0.5: q̇ = (2, 1).
    let shape = StackShape::new(2)
        .with_level("pair", &[("pair", 2)])
        .with_level("apart", &[("apart", 1)]);
    let settings = Settings {
        scale_to_fit: true,
        ..Settings::default()
    };
    let mut s = Solver::with_settings(&shape, settings).unwrap();
    let (mut jacobian, desired) = s.stack_mut().task_mut("pair").unwrap();
    for r in 0..2 {
        jacobian[(r, 0)] = 1.0;
        jacobian[(r, 1)] = 1.0;
    }
    desired.copy_from_slice(&[2.0, 4.0]);
    let (mut jacobian, desired) = s.stack_mut().task_mut("apart").unwrap();
    jacobian[(0, 0)] = 1.0;
    jacobian[(0, 1)] = -1.0;
    desired[0] = 2.0;
    let solution = s
        .solve(&[0.0, 0.0], &velocity_bounds(&[2.0, 2.0]), 0.01)
        .unwrap();
    assert_eq!(solution.report.levels()[0].rank, 1);
    let v = solution.velocity.to_vec();
    assert_relative_eq!(v[0], 2.0, epsilon = 1e-12);
    assert_relative_eq!(v[1], 1.0, epsilon = 1e-12);
}

#[test]
fn a_step_that_fits_is_the_unscaled_solve_in_one_pass() {
    // Level 0: q̇0 + q̇1 = 2, level 1: q̇0 − q̇1 = 1, gradient (0, 0, 1): by hand q̇ = (1.5, 0.5,
    // 1), inside |q̇| ≤ 2. Scaling to fit takes it as it is, bit for bit the clamping loop's
    // one pass, and solves nothing more.
    let levels: &[(&[f64], f64)] = &[(&[1.0, 1.0, 0.0], 2.0), (&[1.0, -1.0, 0.0], 1.0)];
    let gradient = [0.0, 0.0, 1.0];
    let bounds = velocity_bounds(&[2.0; 3]);
    let mut fitting = solver(3, levels, &gradient);
    let solution = fitting.solve(&[0.0; 3], &bounds, 0.01).unwrap();
    assert_eq!(solution.report.clamping_iterations(), 1);
    let fitted = solution.velocity.to_vec();
    let mut plain = solver(3, levels, &gradient);
    plain
        .set_settings(Settings {
            scale_to_fit: false,
            ..*plain.settings()
        })
        .unwrap();
    let unscaled = plain
        .solve(&[0.0; 3], &bounds, 0.01)
        .unwrap()
        .velocity
        .to_vec();
    assert_eq!(fitted, unscaled);
    for (v, by_hand) in fitted.iter().zip([1.5, 0.5, 1.0]) {
        assert_relative_eq!(*v, by_hand, epsilon = 1e-12);
    }
}
