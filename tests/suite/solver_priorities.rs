//! Property tests of the prioritized solve: strict priorities, agreement with the textbook
//! recursion, gradient tasks in the null space, finite output.

use crate::solver_common;

use nalgebra::DVector;
use proptest::prelude::*;
use solver_common::{
    LevelKind, Problem, Rng, problems, random_problem, textbook, well_conditioned,
};
use taskstack::solver::{Settings, Solver};

fn unbounded_velocity(problem: &Problem, with_gradient: bool) -> (Vec<f64>, Vec<f64>) {
    let mut solver = problem.solver(with_gradient);
    let residuals = solver
        .solve_unbounded()
        .unwrap()
        .report
        .levels()
        .iter()
        .map(|l| l.residual)
        .collect();
    (solver.velocity().to_vec(), residuals)
}

fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * a.abs().max(b.abs()).max(1.0)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, max_global_rejects: 4096, ..ProptestConfig::default() })]

    /// The residual of level j does not depend on the levels below it nor on the gradient term.
    #[test]
    fn lower_levels_and_gradients_do_not_disturb_higher_levels((problem, _) in problems(), seed in any::<u64>()) {
        let (_, full) = unbounded_velocity(&problem, true);
        // The same stack with the lower levels replaced by other random ones.
        let mut rng = Rng::new(seed);
        let mut changed = problem.clone();
        for j in 1..changed.levels.len() {
            let m = changed.levels[j].jacobian.nrows();
            changed.levels[j] = solver_common::random_level(&mut rng, problem.n, m, LevelKind::Full, &[]);
        }
        changed.gradient = rng.vector(problem.n, 10.0);
        let (_, other) = unbounded_velocity(&changed, true);
        for j in 0..problem.levels.len() {
            let (_, alone) = unbounded_velocity(&problem.truncated(j + 1), false);
            prop_assert!(close(full[j], alone[j], 1e-9), "level {j}: {} with lower levels, {} without", full[j], alone[j]);
            if j == 0 {
                prop_assert!(close(full[0], other[0], 1e-9), "level 0: {} vs {} with other lower levels", full[0], other[0]);
            }
        }
    }

    /// A well-conditioned, feasible level 1 is met to 1e-9.
    #[test]
    fn feasible_first_level_is_met(seed in any::<u64>(), n in 1usize..=30, m in 1usize..=8, lower in 0usize..4) {
        prop_assume!(m <= n);
        let mut rng = Rng::new(seed);
        let mut rows = vec![m];
        let mut kinds = vec![LevelKind::Full];
        for _ in 0..lower {
            rows.push(1 + rng.below(8));
            kinds.push(solver_common::kind(rng.below(4)));
        }
        let problem = random_problem(&mut rng, n, &rows, &kinds);
        let sv = solver_common::singular_values(&problem.levels[0].jacobian);
        prop_assume!(sv.iter().cloned().fold(f64::INFINITY, f64::min) > 0.05);
        let (qdot, _) = unbounded_velocity(&problem, true);
        let target_norm = problem.levels[0].target.norm();
        prop_assert!(problem.residual(0, &qdot) <= 1e-9 * (1.0 + target_norm));
    }

    /// On well-conditioned problems the result equals the textbook recursion of eq. 4–6.
    #[test]
    fn equals_textbook_recursion((problem, _) in problems(), with_gradient in any::<bool>()) {
        prop_assume!(well_conditioned(&problem, 1e-10, 1e-2));
        let settings = Settings { damping_threshold: 0.0, ..Settings::default() };
        let mut solver = Solver::with_settings(&problem.shape(), settings).unwrap();
        problem.load(&mut solver, with_gradient);
        solver.solve_unbounded().unwrap();
        let expected = textbook(&problem, with_gradient, 1e-10);
        let got = DVector::from_column_slice(solver.velocity());
        let scale = expected.norm().max(1.0);
        prop_assert!((&got - &expected).norm() <= 1e-9 * scale, "|Δ| = {:e}, |q̇| = {:e}", (&got - &expected).norm(), scale);
    }

    /// The gradient term's contribution lies in the null space of every equality level.
    #[test]
    fn gradient_contribution_is_in_the_null_space((problem, _) in problems()) {
        let (with, _) = unbounded_velocity(&problem, true);
        let (without, _) = unbounded_velocity(&problem, false);
        let delta = DVector::from_column_slice(&with) - DVector::from_column_slice(&without);
        let ja = problem.augmented(problem.levels.len());
        // Directions below the rank tolerance (1e-9) may carry a little of the gradient.
        let bound = 1e-8 * problem.gradient.norm().max(1.0);
        prop_assert!((&ja * &delta).norm() <= bound, "‖J^a Δq̇‖ = {:e}", (&ja * &delta).norm());
    }

    /// Finite input of any scale gives finite output.
    #[test]
    fn output_is_finite((problem, _) in problems(), exponent in -150i32..150, seed in any::<u64>()) {
        let mut scaled = problem.clone();
        let mut rng = Rng::new(seed);
        for level in &mut scaled.levels {
            let s = 10f64.powi(exponent / 2 + rng.below(20) as i32 - 10);
            level.jacobian *= s;
            level.target *= 10f64.powi(exponent / 3);
        }
        scaled.gradient *= 10f64.powi(exponent / 4);
        let (qdot, residuals) = unbounded_velocity(&scaled, true);
        prop_assert!(qdot.iter().all(|v| v.is_finite()), "{qdot:?}");
        prop_assert!(residuals.iter().all(|v| v.is_finite()));
    }
}
