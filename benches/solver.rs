//! Prioritized solve on the paper's stack shapes (n = 23): RS (CoM 2 rows, then hands + free
//! ankle 9 rows, two gradient tasks) and DS (2 rows, then 11 rows), with and without an active
//! clamp, against a naive nalgebra implementation of eq. 4–6 (explicit n × n projectors, SVD
//! pseudo-inverses) measured in the same run. Then the RS stack under a top level of 0, 10 or 30
//! inequality rows (`solve_inequalities/…`, the active-set method; the id says how many rows
//! ended active and how many prioritized solves it took).

use criterion::{Criterion, criterion_group, criterion_main};
use nalgebra::{DMatrix, DVector};
use std::hint::black_box;
use taskstack::solver::{
    JointBounds, JointLimitAvoidance, JointTracking, Settings, Solver, StackShape,
};

const N: usize = 23;

/// Deterministic pseudo-random entries in [-0.3, 0.3): the scale of NAO Jacobians (m/rad).
fn entry(i: usize, j: usize, salt: usize) -> f64 {
    let mut z = (i as u64) << 32 ^ (j as u64) << 8 ^ salt as u64;
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    0.6 * ((z >> 11) as f64 / (1u64 << 53) as f64) - 0.3
}

struct Case {
    name: &'static str,
    levels: Vec<(DMatrix<f64>, DVector<f64>)>,
}

impl Case {
    fn new(name: &'static str, rows: &[usize]) -> Self {
        let levels = rows
            .iter()
            .enumerate()
            .map(|(l, &m)| {
                let jac = DMatrix::from_fn(m, N, |i, j| entry(i, j, 17 * l + 1));
                let target = DVector::from_fn(m, |i, _| 0.05 * entry(i, 99, l));
                (jac, target)
            })
            .collect();
        Self { name, levels }
    }

    fn shape(&self) -> StackShape {
        let rows: Vec<usize> = self.levels.iter().map(|l| l.0.nrows()).collect();
        StackShape::from_level_rows(N, &rows)
    }

    /// Writes the case's levels into the solver's levels `first..`, and the two gradient tasks.
    fn fill(
        &self,
        solver: &mut Solver,
        first: usize,
        q: &[f64],
        limits: &JointLimitAvoidance,
        tracking: &JointTracking,
    ) {
        let stack = solver.stack_mut();
        for (l, (jac, target)) in self.levels.iter().enumerate() {
            let mut level = stack.level_mut(first + l);
            let mut view = level.jacobian_mut();
            for i in 0..jac.nrows() {
                for j in 0..N {
                    view[(i, j)] = jac[(i, j)];
                }
            }
            level.target_mut().copy_from_slice(target.as_slice());
        }
        stack.clear_gradient();
        stack.add_gradient(-0.10, limits, q).unwrap();
        stack.add_gradient(-0.02, tracking, q).unwrap();
    }
}

/// The textbook recursion with explicit projectors and nalgebra SVD pseudo-inverses.
fn naive(levels: &[(DMatrix<f64>, DVector<f64>)], gradient: &DVector<f64>) -> DVector<f64> {
    let mut qdot = DVector::zeros(N);
    let mut projector = DMatrix::<f64>::identity(N, N);
    let mut augmented = DMatrix::zeros(0, N);
    for (jac, target) in levels {
        let a = jac * &projector;
        let pinv = a.svd(true, true).pseudo_inverse(1e-9).unwrap();
        qdot += pinv * (target - jac * &qdot);
        let rows = augmented.nrows();
        augmented = augmented.insert_rows(rows, jac.nrows(), 0.0);
        augmented.rows_mut(rows, jac.nrows()).copy_from(jac);
        let pinv_a = augmented
            .clone()
            .svd(true, true)
            .pseudo_inverse(1e-9)
            .unwrap();
        projector = DMatrix::identity(N, N) - pinv_a * &augmented;
    }
    qdot + projector * gradient
}

fn bench(c: &mut Criterion) {
    let lower = vec![-2.0; N];
    let upper = vec![2.0; N];
    let free_bounds = JointBounds::new(&lower, &upper).unwrap();
    let q_mid = vec![0.1; N];
    // A tight velocity limit on a few joints makes the clamping loop run.
    let mut velocity = vec![f64::INFINITY; N];
    for v in velocity.iter_mut().step_by(5) {
        *v = 0.01;
    }
    let clamp_bounds = JointBounds::with_velocity(&lower, &upper, &velocity).unwrap();
    let limits = JointLimitAvoidance::new(&free_bounds);
    let tracking = JointTracking::new(&[0.2; N]).unwrap();
    let dt = 0.01;

    for case in [Case::new("RS", &[2, 9]), Case::new("DS", &[2, 11])] {
        let mut solver = Solver::new(&case.shape()).unwrap();
        case.fill(&mut solver, 0, &q_mid, &limits, &tracking);
        let clamped = solver
            .solve(&q_mid, &clamp_bounds, dt)
            .unwrap()
            .report
            .clamped_joints()
            .len();
        assert!(
            clamped > 0
                && solver
                    .solve(&q_mid, &free_bounds, dt)
                    .unwrap()
                    .report
                    .clamped_joints()
                    .is_empty()
        );
        let mut group = c.benchmark_group(format!("solve_{}", case.name));
        group.bench_function("taskstack_no_clamp", |b| {
            b.iter(|| {
                case.fill(&mut solver, 0, black_box(&q_mid), &limits, &tracking);
                black_box(solver.solve(&q_mid, &free_bounds, dt).unwrap().velocity[0])
            })
        });
        group.bench_function(format!("taskstack_clamp_{clamped}_joints"), |b| {
            b.iter(|| {
                case.fill(&mut solver, 0, black_box(&q_mid), &limits, &tracking);
                black_box(solver.solve(&q_mid, &clamp_bounds, dt).unwrap().velocity[0])
            })
        });
        let gradient = DVector::from_column_slice(solver.stack().gradient());
        group.bench_function("naive_nalgebra_no_clamp", |b| {
            b.iter(|| black_box(naive(black_box(&case.levels), &gradient)[0]))
        });
        group.finish();
    }
}

/// The RS stack (CoM 2 rows, then 9 rows, two gradient tasks) below a level of `rows`
/// inequality rows `|c_i q̇| ≤ b_i`: every third row bounded at half the value it has in the
/// solution without them (so it must become active), the others loosely.
fn bench_inequalities(c: &mut Criterion) {
    let bounds = JointBounds::new(&[-2.0; N], &[2.0; N]).unwrap();
    let q = vec![0.1; N];
    let limits = JointLimitAvoidance::new(&bounds);
    let tracking = JointTracking::new(&[0.2; N]).unwrap();
    let case = Case::new("RS", &[2, 9]);
    let mut group = c.benchmark_group("solve_inequalities");
    for rows in [0, 10, 30] {
        let shape = match rows {
            0 => case.shape(),
            _ => StackShape::new(N)
                .with_inequality_level("limits", &[("rows", rows)])
                .with_level("balance", &[("com_xy", 2)])
                .with_level("tracking", &[("hands_ankle", 9)]),
        };
        let settings = Settings {
            limits_by_active_set: true,
            ..Settings::default()
        };
        let mut solver = Solver::with_settings(&shape, settings).unwrap();
        let mut row_bounds = vec![f64::INFINITY; rows];
        let fill = |solver: &mut Solver, row_bounds: &[f64]| {
            case.fill(solver, usize::from(rows > 0), &q, &limits, &tracking);
            if rows > 0 {
                let mut level = solver.stack_mut().level_mut(0);
                let (mut jac, lower, upper) = level.inequalities_mut();
                for i in 0..rows {
                    for j in 0..N {
                        jac[(i, j)] = entry(i, j, 1234);
                    }
                    (lower[i], upper[i]) = (-row_bounds[i], row_bounds[i]);
                }
            }
        };
        fill(&mut solver, &row_bounds);
        let free = solver.solve(&q, &bounds, 0.01).unwrap().velocity.to_vec();
        for (i, b) in row_bounds.iter_mut().enumerate() {
            let value: f64 = (0..N).map(|j| entry(i, j, 1234) * free[j]).sum();
            *b = if i % 3 == 0 { 0.5 } else { 10.0 } * value.abs() + 1e-6;
        }
        fill(&mut solver, &row_bounds);
        let report = solver.solve(&q, &bounds, 0.01).unwrap().report;
        let (active, iterations) = (
            report.active_inequalities().len(),
            report.active_set_iterations(),
        );
        let id = format!("{rows}_rows_{active}_active_{iterations}_solves");
        group.bench_function(id, |b| {
            b.iter(|| {
                fill(&mut solver, &row_bounds);
                black_box(solver.solve(&q, &bounds, 0.01).unwrap().velocity[0])
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench, bench_inequalities);
criterion_main!(benches);
