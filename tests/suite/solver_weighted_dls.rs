//! The weighted damped least-squares method (Chan & Dubey 1995): the closed form, the weight's
//! growth toward a limit (hand-computed), the step bound near singularities, the limits kept.

use nalgebra::{DMatrix, DVector};
use proptest::prelude::*;
use taskstack::solver::{
    JointBounds, Method, Settings, Solver, StackShape, limit_criterion_gradient, limit_weight,
};

fn dls_solver(rows: &[usize], n: usize, damping: f64) -> Solver {
    let shape = StackShape::from_level_rows(n, rows);
    let settings = Settings {
        method: Method::WeightedDls { damping },
        ..Settings::default()
    };
    Solver::with_settings(&shape, settings).unwrap()
}

#[test]
fn the_weight_is_one_at_mid_range_and_grows_to_infinity_at_the_limits() {
    // Range [−1, 1], q = 0.5: ∂H/∂q = 2² (2·0.5 − 0) / (4 · 0.5² · 1.5²) = 4 / 2.25.
    assert!((limit_criterion_gradient(0.5, -1.0, 1.0) - 4.0 / 2.25).abs() < 1e-12);
    assert!((limit_weight(0.5, -1.0, 1.0) - (1.0 + 4.0 / 2.25)).abs() < 1e-12);
    assert_eq!(limit_weight(0.0, -1.0, 1.0), 1.0);
    // Symmetric, and growing monotonically toward either limit.
    let mut previous = 1.0;
    for k in 1..100 {
        let q = k as f64 / 100.0;
        let w = limit_weight(q, -1.0, 1.0);
        assert!(w > previous, "q = {q}");
        assert!((w - limit_weight(-q, -1.0, 1.0)).abs() < 1e-9 * w);
        previous = w;
    }
    assert_eq!(limit_weight(1.0, -1.0, 1.0), f64::INFINITY);
    // No limit, no weight.
    assert_eq!(limit_weight(3.0, f64::NEG_INFINITY, f64::INFINITY), 1.0);
}

#[test]
fn without_limits_the_step_is_the_closed_form_damped_least_squares() {
    // Two levels stacked into one damped problem: Jᵀ (J Jᵀ + λ² I)⁻¹ ẋ, computed by nalgebra.
    let (n, lambda) = (4, 0.3);
    let rows = [
        [1.0, 0.5, -0.2, 0.0],
        [0.0, 1.0, 0.3, 0.7],
        [0.2, 0.0, 1.0, -0.4],
    ];
    let x = [0.3, -0.1, 0.25];
    let mut solver = dls_solver(&[2, 1], n, lambda);
    for (r, (row, &xr)) in rows.iter().zip(&x).enumerate() {
        let (level, row_in_level) = if r < 2 { (0, r) } else { (1, 0) };
        solver
            .stack_mut()
            .level_mut(level)
            .set_row(row_in_level, row, xr)
            .unwrap();
    }
    let v = solver.solve_unbounded().unwrap().velocity.to_vec();
    let j = DMatrix::from_fn(3, n, |r, c| rows[r][c]);
    let gram = &j * j.transpose() + DMatrix::identity(3, 3) * lambda * lambda;
    let expected = j.transpose() * gram.try_inverse().unwrap() * DVector::from_row_slice(&x);
    for i in 0..n {
        assert!(
            (v[i] - expected[i]).abs() < 1e-12,
            "joint {i}: {} vs {}",
            v[i],
            expected[i]
        );
    }
}

#[test]
fn a_joint_near_its_limit_moves_less_than_an_identical_one_at_mid_range() {
    // q̇0 + q̇1 = 1; joint 0 at 0.8 of a [−1, 1] range, joint 1 at 0.
    let mut solver = dls_solver(&[1], 2, 0.01);
    solver
        .stack_mut()
        .level_mut(0)
        .set_row(0, &[1.0, 1.0], 1.0)
        .unwrap();
    let bounds = JointBounds::new(&[-1.0, -1.0], &[1.0, 1.0]).unwrap();
    let v = solver
        .solve(&[0.8, 0.0], &bounds, 0.01)
        .unwrap()
        .velocity
        .to_vec();
    // Weighted least norm: q̇_i ∝ 1 / w_i.
    let ratio = limit_weight(0.8, -1.0, 1.0);
    assert!((v[1] / v[0] - ratio).abs() < 1e-6 * ratio, "{v:?}");
    // Moving away from the limit is not penalized: the same joint asked to go down.
    solver
        .stack_mut()
        .level_mut(0)
        .set_row(0, &[1.0, 1.0], -1.0)
        .unwrap();
    let v = solver
        .solve(&[0.79, 0.0], &bounds, 0.01)
        .unwrap()
        .velocity
        .to_vec();
    assert!((v[0] - v[1]).abs() < 1e-6, "{v:?}");
}

proptest! {
    /// Damping bounds the step: ‖q̇‖ ≤ ‖ẋ‖ / (2λ) for any Jacobian, singular or not.
    #[test]
    fn damping_bounds_the_step_near_singularities(
        scale in 1e-9f64..1.0,
        a in -1.0f64..1.0, b in -1.0f64..1.0, c in -1.0f64..1.0,
        x in -1.0f64..1.0, y in -1.0f64..1.0,
        lambda in 0.01f64..1.0,
    ) {
        let mut solver = dls_solver(&[2], 3, lambda);
        // Two nearly parallel rows: singular as scale → 0.
        solver.stack_mut().level_mut(0).set_row(0, &[a, b, c], x).unwrap();
        solver.stack_mut().level_mut(0).set_row(1, &[a, b + scale, c], y).unwrap();
        let v = solver.solve_unbounded().unwrap().velocity.to_vec();
        let norm = v.iter().map(|v| v * v).sum::<f64>().sqrt();
        let bound = (x * x + y * y).sqrt() / (2.0 * lambda);
        prop_assert!(norm <= bound * (1.0 + 1e-9) + 1e-15, "{norm} > {bound}");
    }

    /// The clamping loop still applies: no step leaves the position or velocity limits.
    #[test]
    fn the_step_never_leaves_the_limits(
        q in proptest::collection::vec(-0.99f64..0.99, 3),
        x in -50.0f64..50.0,
        a in -1.0f64..1.0, b in -1.0f64..1.0,
    ) {
        let mut solver = dls_solver(&[1], 3, 0.05);
        solver.stack_mut().level_mut(0).set_row(0, &[1.0, a, b], x).unwrap();
        let bounds = JointBounds::with_velocity(&[-1.0; 3], &[1.0; 3], &[2.0; 3]).unwrap();
        let dt = 0.1;
        let v = solver.solve(&q, &bounds, dt).unwrap().velocity.to_vec();
        for i in 0..3 {
            prop_assert!(v[i].abs() <= 2.0 + 1e-12);
            let next = q[i] + v[i] * dt;
            prop_assert!((-1.0..=1.0).contains(&next), "joint {i} to {next}");
        }
    }
}

#[test]
fn a_non_positive_damping_is_refused_by_name() {
    let shape = StackShape::from_level_rows(2, &[1]);
    for damping in [0.0, -1.0, f64::NAN] {
        let settings = Settings {
            method: Method::WeightedDls { damping },
            ..Settings::default()
        };
        let error = Solver::with_settings(&shape, settings).unwrap_err();
        assert!(error.to_string().contains("damping"), "{error}");
    }
}
