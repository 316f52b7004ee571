//! Robot-agnostic prioritized task-stack solver (Poubel et al. §II.B, eq. 2–8; Baerlocher &
//! Boulic 2004).
//!
//! A stack has strict **equality levels** `J_j q̇ = ẋ_j`, highest priority first, and
//! **gradient tasks** `κ_k ∇f_k(q)` that act only in the null space of every level:
//!
//! ```text
//! q̇_0 = 0
//! q̇_j = q̇_{j−1} + (J_j P^a_{j−1})⁺ (ẋ_j − J_j q̇_{j−1}),   P^a_j = I − (J^a_j)⁺ J^a_j
//! q̇   = q̇_N + P^a_N Σ_k κ_k ∇f_k(q)
//! ```
//!
//! A level that conflicts with higher ones gets its least-squares best inside their null space and
//! never disturbs them. The pseudo-inverse is singularity-robust: rank-revealing (truncated at
//! [`Settings::rank_tolerance`]) and damped near singularities ([`Settings::damping_threshold`],
//! [`Settings::max_damping`]). A **clamping loop** fixes joints that would leave their limits at the
//! limit and solves again with fewer degrees of freedom, so a result never violates a limit. Every
//! solve fills a [`SolveReport`]: per level the residual, the rank used and whether it was met; the
//! clamped joints; the clamping iterations. See [`prioritized`] for how it is computed.
//!
//! [`Solver`] owns the stack and a workspace sized once for `(n, rows per level)`; solving
//! allocates nothing. [`driver`] iterates the velocity solve to reach position targets.
//!
//! ```
//! use taskstack::solver::{JointBounds, JointLimitAvoidance, Solver, StackShape};
//!
//! // A 3-joint system: level 1 asks q̇0 + q̇1 + q̇2 = 1, level 2 asks q̇0 = 2, joint 0 is limited.
//! let shape = StackShape::from_level_rows(3, &[1, 1]);
//! let mut solver = Solver::new(&shape).unwrap();
//! solver.stack_mut().level_mut(0).set_row(0, &[1.0, 1.0, 1.0], 1.0).unwrap();
//! solver.stack_mut().level_mut(1).set_row(0, &[1.0, 0.0, 0.0], 2.0).unwrap();
//! let bounds = JointBounds::new(&[-1.0, -1.0, -1.0], &[0.05, 1.0, 1.0]).unwrap();
//! let q = [0.0; 3];
//! let limits = JointLimitAvoidance::new(&bounds);
//! solver.stack_mut().add_gradient(-0.1, &limits, &q).unwrap();
//! let solution = solver.solve(&q, &bounds, 0.1).unwrap();
//! let (v, report) = (solution.velocity, solution.report);
//! // Joint 0 may move 0.05 rad in 0.1 s: it is clamped at 0.5 rad/s, level 1 still holds.
//! assert_eq!(report.clamped_joints(), &[0]);
//! assert!((v[0] - 0.5).abs() < 1e-12 && (v[0] + v[1] + v[2] - 1.0).abs() < 1e-12);
//! assert!(report.levels()[0].feasible && !report.levels()[1].feasible);
//! ```

mod bounds;
pub mod driver;
mod error;
mod gradient;
mod householder;
pub mod prioritized;
mod report;
mod stack;

pub use bounds::JointBounds;
pub use error::SolverError;
pub use gradient::{GradientFunction, JointLimitAvoidance, JointTracking};
pub use prioritized::{Settings, Solver};
pub use report::{LevelReport, Solution, SolveReport};
pub use stack::{LevelMut, LevelSpec, StackShape, TaskSpec, TaskStack};
