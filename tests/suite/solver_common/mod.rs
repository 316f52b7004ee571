//! Shared test helpers: random stacks and the textbook recursion of eq. 4–6, computed naively with
//! explicit projectors and SVD pseudo-inverses (faer's SVD, nalgebra matrices), as an independent reference.

use nalgebra::{DMatrix, DVector};
use proptest::prelude::*;
use taskstack::solver::{JointBounds, Solver, StackShape};

/// SplitMix64: a tiny deterministic generator, seeded by proptest.
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Self(seed)
    }
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [lo, hi).
    pub fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * ((self.next_u64() >> 11) as f64 / (1u64 << 53) as f64)
    }
    pub fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n as u64) as usize
    }
    pub fn matrix(&mut self, rows: usize, cols: usize) -> DMatrix<f64> {
        DMatrix::from_fn(rows, cols, |_, _| self.uniform(-1.0, 1.0))
    }
    pub fn vector(&mut self, len: usize, scale: f64) -> DVector<f64> {
        DVector::from_fn(len, |_, _| self.uniform(-scale, scale))
    }
}

/// One equality level: Jacobian and desired velocity.
#[derive(Debug, Clone)]
pub struct Level {
    pub jacobian: DMatrix<f64>,
    pub target: DVector<f64>,
}

/// A random stack with gradient term.
#[derive(Debug, Clone)]
pub struct Problem {
    pub n: usize,
    pub levels: Vec<Level>,
    pub gradient: DVector<f64>,
}

/// How a random level is made.
#[derive(Debug, Clone, Copy)]
pub enum LevelKind {
    /// Independent uniform entries.
    Full,
    /// A product of an `m × r` and an `r × n` matrix, `r < m`: exactly rank-deficient.
    LowRank,
    /// Some rows zero.
    ZeroRows,
    /// Some rows copied from higher levels (with other targets): a conflict.
    Conflicting,
}

pub fn random_level(rng: &mut Rng, n: usize, m: usize, kind: LevelKind, above: &[Level]) -> Level {
    let mut jacobian = rng.matrix(m, n);
    match kind {
        LevelKind::Full => {}
        LevelKind::LowRank => {
            let r = rng.below(m.max(1));
            jacobian = rng.matrix(m, r) * rng.matrix(r, n);
        }
        LevelKind::ZeroRows => {
            for i in 0..m {
                if rng.below(2) == 0 {
                    jacobian.row_mut(i).fill(0.0);
                }
            }
        }
        LevelKind::Conflicting => {
            let rows: Vec<_> = above
                .iter()
                .flat_map(|l| l.jacobian.row_iter().map(|r| r.clone_owned()))
                .collect();
            if !rows.is_empty() {
                for i in 0..m {
                    if rng.below(2) == 0 {
                        jacobian.row_mut(i).copy_from(&rows[rng.below(rows.len())]);
                    }
                }
            }
        }
    }
    Level {
        jacobian,
        target: rng.vector(m, 1.0),
    }
}

/// A random problem: `n` joints, the given rows per level and kinds, a random gradient.
pub fn random_problem(rng: &mut Rng, n: usize, rows: &[usize], kinds: &[LevelKind]) -> Problem {
    let mut levels = Vec::new();
    for (&m, &kind) in rows.iter().zip(kinds) {
        let level = random_level(rng, n, m, kind, &levels);
        levels.push(level);
    }
    Problem {
        n,
        levels,
        gradient: rng.vector(n, 1.0),
    }
}

impl Problem {
    pub fn shape(&self) -> StackShape {
        let rows: Vec<usize> = self.levels.iter().map(|l| l.jacobian.nrows()).collect();
        StackShape::from_level_rows(self.n, &rows)
    }

    /// Writes the problem into a solver built for its shape. `with_gradient` selects whether the
    /// gradient term is set or cleared.
    pub fn load(&self, solver: &mut Solver, with_gradient: bool) {
        let stack = solver.stack_mut();
        for (j, level) in self.levels.iter().enumerate() {
            let mut l = stack.level_mut(j);
            for i in 0..level.jacobian.nrows() {
                let row: Vec<f64> = level.jacobian.row(i).iter().copied().collect();
                l.set_row(i, &row, level.target[i]).unwrap();
            }
        }
        if with_gradient {
            stack
                .gradient_mut()
                .copy_from_slice(self.gradient.as_slice());
        } else {
            stack.clear_gradient();
        }
    }

    pub fn solver(&self, with_gradient: bool) -> Solver {
        let mut solver = Solver::new(&self.shape()).unwrap();
        self.load(&mut solver, with_gradient);
        solver
    }

    /// The first `count` levels only.
    pub fn truncated(&self, count: usize) -> Problem {
        Problem {
            n: self.n,
            levels: self.levels[..count].to_vec(),
            gradient: self.gradient.clone(),
        }
    }

    /// Stacked Jacobian of levels `0..count`.
    pub fn augmented(&self, count: usize) -> DMatrix<f64> {
        let rows: usize = self.levels[..count]
            .iter()
            .map(|l| l.jacobian.nrows())
            .sum();
        let mut ja = DMatrix::zeros(rows, self.n);
        let mut r = 0;
        for l in &self.levels[..count] {
            ja.rows_mut(r, l.jacobian.nrows()).copy_from(&l.jacobian);
            r += l.jacobian.nrows();
        }
        ja
    }

    pub fn residual(&self, level: usize, qdot: &[f64]) -> f64 {
        let l = &self.levels[level];
        (&l.jacobian * DVector::from_column_slice(qdot) - &l.target).norm()
    }
}

/// Thin SVD by faer (nalgebra's SVD is not reliable on rank-deficient matrices): `(U, s, V)`.
fn svd(a: &DMatrix<f64>) -> (DMatrix<f64>, Vec<f64>, DMatrix<f64>) {
    let m = faer::Mat::from_fn(a.nrows(), a.ncols(), |i, j| a[(i, j)]);
    let svd = m.thin_svd().expect("SVD converges");
    let (u, v) = (svd.U(), svd.V());
    let s = svd.S().column_vector().iter().copied().collect();
    (
        DMatrix::from_fn(u.nrows(), u.ncols(), |i, j| u[(i, j)]),
        s,
        DMatrix::from_fn(v.nrows(), v.ncols(), |i, j| v[(i, j)]),
    )
}

/// Truncated-SVD pseudo-inverse: singular values `≤ tol` are dropped.
pub fn pinv(a: &DMatrix<f64>, tol: f64) -> DMatrix<f64> {
    if a.nrows() == 0 || a.ncols() == 0 {
        return DMatrix::zeros(a.ncols(), a.nrows());
    }
    let (u, s, v) = svd(a);
    let inv = DMatrix::from_fn(s.len(), s.len(), |i, j| {
        if i == j && s[i] > tol {
            1.0 / s[i]
        } else {
            0.0
        }
    });
    v * inv * u.transpose()
}

pub fn singular_values(a: &DMatrix<f64>) -> Vec<f64> {
    if a.nrows() == 0 || a.ncols() == 0 {
        return Vec::new();
    }
    svd(a).1
}

/// The textbook recursion (eq. 4–6) with explicit `n × n` projectors.
pub fn textbook(problem: &Problem, with_gradient: bool, tol: f64) -> DVector<f64> {
    let n = problem.n;
    let mut qdot = DVector::zeros(n);
    let mut projector = DMatrix::identity(n, n);
    for (j, level) in problem.levels.iter().enumerate() {
        let a = &level.jacobian * &projector;
        qdot += pinv(&a, tol) * (&level.target - &level.jacobian * &qdot);
        let ja = problem.augmented(j + 1);
        projector = DMatrix::identity(n, n) - pinv(&ja, tol) * ja;
    }
    if with_gradient {
        qdot += projector * &problem.gradient;
    }
    qdot
}

/// Whether every projected level and every augmented Jacobian has singular values either clearly
/// zero or clearly away from zero, so that truncation decisions cannot differ between methods.
pub fn well_conditioned(problem: &Problem, gap_low: f64, gap_high: f64) -> bool {
    let n = problem.n;
    let mut projector = DMatrix::identity(n, n);
    for j in 0..problem.levels.len() {
        let a = &problem.levels[j].jacobian * &projector;
        let ja = problem.augmented(j + 1);
        for s in singular_values(&a).into_iter().chain(singular_values(&ja)) {
            if s > gap_low && s < gap_high {
                return false;
            }
        }
        projector = DMatrix::identity(n, n) - pinv(&ja, gap_low) * ja;
    }
    true
}

/// Random position and velocity limits around a random q inside them.
pub fn random_bounds(rng: &mut Rng, n: usize) -> (JointBounds, Vec<f64>) {
    let mut lower = Vec::new();
    let mut upper = Vec::new();
    let mut velocity = Vec::new();
    let mut q = Vec::new();
    for _ in 0..n {
        let lo = rng.uniform(-3.0, 0.5);
        let hi = lo + rng.uniform(0.0, 3.0) * if rng.below(8) == 0 { 0.0 } else { 1.0 };
        lower.push(lo);
        upper.push(hi);
        velocity.push(if rng.below(3) == 0 {
            f64::INFINITY
        } else {
            rng.uniform(0.0, 5.0)
        });
        q.push(rng.uniform(lo, hi).clamp(lo, hi));
    }
    (
        JointBounds::with_velocity(&lower, &upper, &velocity).unwrap(),
        q,
    )
}

const KINDS: [LevelKind; 4] = [
    LevelKind::Full,
    LevelKind::LowRank,
    LevelKind::ZeroRows,
    LevelKind::Conflicting,
];

/// A random level kind by index.
pub fn kind(index: usize) -> LevelKind {
    KINDS[index % KINDS.len()]
}

/// Random problems: n up to 30, 1–5 levels of 1–8 rows, of every kind; and a seed for more
/// random numbers.
pub fn problems() -> impl Strategy<Value = (Problem, u64)> {
    (
        any::<u64>(),
        1usize..=30,
        prop::collection::vec((1usize..=8, 0usize..4), 1..=5),
    )
        .prop_map(|(seed, n, levels)| {
            let rows: Vec<usize> = levels.iter().map(|l| l.0).collect();
            let kinds: Vec<LevelKind> = levels.iter().map(|l| kind(l.1)).collect();
            let mut rng = Rng::new(seed);
            (random_problem(&mut rng, n, &rows, &kinds), rng.next_u64())
        })
}
