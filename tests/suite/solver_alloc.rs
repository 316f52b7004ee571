//! A warmed-up solve allocates nothing on the heap: a counting global allocator in its own test
//! binary (so no other test's allocations interfere) counts allocations during the solves.

use taskstack::solver::driver::{DriverSettings, PositionDriver, TaskModel};
use taskstack::solver::{
    JointBounds, JointLimitAvoidance, JointTracking, Method, Settings, Solver, SolverError,
    StackShape, TaskStack,
};

use crate::alloc_counter;
use alloc_counter::allocations;

const N: usize = 23;

/// A deterministic pseudo-random entry in [-1, 1).
fn entry(i: usize, j: usize, salt: usize) -> f64 {
    let x = ((i * 7919 + j * 104_729 + salt * 1_299_709) % 2003) as f64;
    x / 1001.5 - 1.0
}

fn fill(solver: &mut Solver, salt: usize) {
    let stack = solver.stack_mut();
    for level in 0..stack.level_count() {
        let mut l = stack.level_mut(level);
        let rows = l.rows();
        let mut jac = l.jacobian_mut();
        for i in 0..rows {
            for j in 0..N {
                jac[(i, j)] = entry(i + 10 * level, j, salt);
            }
        }
        for (i, t) in l.target_mut().iter_mut().enumerate() {
            *t = 5.0 * entry(i, level, salt + 1);
        }
        let rows = l.inequality_rows();
        let (mut jac, lower, upper) = l.inequalities_mut();
        for i in 0..rows {
            for j in 0..N {
                jac[(i, j)] = entry(i + 10 * level + 5, j, salt);
            }
            lower[i] = -0.5 + 0.2 * entry(i, level, salt + 2);
            upper[i] = 0.5 + 0.2 * entry(i, level, salt + 3);
        }
    }
}

/// A linear "model" x = A q, for the driver.
struct Linear;

impl TaskModel for Linear {
    type Error = SolverError;
    fn evaluate(&mut self, q: &[f64], stack: &mut TaskStack) -> Result<(), SolverError> {
        for level in 0..stack.level_count() {
            let mut l = stack.level_mut(level);
            let rows = l.rows();
            for i in 0..rows {
                let row: [f64; N] = std::array::from_fn(|j| entry(i + 10 * level, j, 3));
                let x: f64 = row.iter().zip(q).map(|(a, b)| a * b).sum();
                l.set_row(i, &row, 0.2 * (i as f64) - x)?;
            }
        }
        Ok(())
    }
}

/// Both methods, and the active-set method with inequality rows, in one test: the allocation
/// counter is global, a second test thread would count into it.
#[test]
fn warmed_up_solves_do_not_allocate() {
    // The paper's RS stack shape: CoM (2 rows), then hands + free ankle (9 rows).
    let equality = StackShape::new(N)
        .with_level("balance", &[("com_xy", 2)])
        .with_level("tracking", &[("l_hand", 3), ("r_hand", 3), ("l_ankle", 3)]);
    warmed_up_solves_do_not_allocate_with(&equality, Method::Prioritized);
    warmed_up_solves_do_not_allocate_with(&equality, Method::WeightedDls { damping: 0.05 });
    // The CoM inside a polygon (6 edges) at the top; hands and ankle, and two distances, below.
    let inequality = StackShape::new(N)
        .with_inequality_level("balance", &[("com_in_polygon", 6)])
        .with_mixed_level(
            "tracking",
            &[("l_hand", 3), ("r_hand", 3), ("l_ankle", 3)],
            &[("distances", 2)],
        );
    warmed_up_solves_do_not_allocate_with(&inequality, Method::Prioritized);
}

fn warmed_up_solves_do_not_allocate_with(shape: &StackShape, method: Method) {
    let settings = Settings {
        method,
        ..Settings::default()
    };
    let mut solver = Solver::with_settings(shape, settings).unwrap();
    let lower = [-0.3; N];
    let upper = [0.3; N];
    let bounds = JointBounds::with_velocity(&lower, &upper, &[2.0; N]).unwrap();
    let limits = JointLimitAvoidance::new(&bounds);
    let mut tracking = JointTracking::new(&[0.1; N]).unwrap();
    let reference = [0.05; N];
    let q = [0.25; N];
    let mut driver = PositionDriver::new(&solver, DriverSettings::default()).unwrap();
    let mut model = Linear;
    let mut q_driver = [0.0; N];

    // Warm-up.
    fill(&mut solver, 0);
    solver.solve(&q, &bounds, 0.01).unwrap();

    let before = allocations();
    let (mut clamped, mut active) = (0, 0);
    for salt in 0..50 {
        fill(&mut solver, salt);
        let stack = solver.stack_mut();
        stack.clear_gradient();
        stack.add_gradient(-0.10, &limits, &q).unwrap();
        tracking.set_reference(&reference).unwrap();
        stack.add_gradient(-0.02, &tracking, &q).unwrap();
        let report = solver.solve(&q, &bounds, 0.01).unwrap().report;
        clamped += report.clamped_joints().len();
        active += report.active_inequalities().len();
        solver.solve_unbounded().unwrap();
    }
    driver
        .run(&mut solver, &mut model, &mut q_driver, &bounds)
        .unwrap();
    let after = allocations();
    assert!(clamped > 0, "the clamping loop was exercised");
    let inequalities = solver.stack().total_inequality_rows();
    assert!(
        inequalities == 0 || active > 0,
        "inequality rows became active"
    );
    assert_eq!(
        after - before,
        0,
        "heap allocations during warmed-up solves"
    );
}
