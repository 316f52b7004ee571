//! The prioritized solve (eq. 4–6) with the clamping loop.
//!
//! # Method
//!
//! The textbook recursion is `q̇_j = q̇_{j−1} + (J_j P^a_{j−1})⁺ (ẋ_j − J_j q̇_{j−1})` with
//! `P^a_j = I − (J^a_j)⁺ J^a_j`. Instead of forming `n × n` projectors we carry an orthonormal basis
//! `Z_j` of the null space of levels `1..j`, so that `P^a_j = Z_j Z_jᵀ` and
//! `(J_j P^a_{j−1})⁺ = Z_{j−1} (J_j Z_{j−1})⁺` (valid because `Z_{j−1}` has orthonormal columns).
//!
//! * `Z_0` selects the joints that are not clamped; clamped joints move at their fixed velocity,
//!   whose effect `J_j q̇_clamped` is moved to the right-hand side of every level.
//! * Level `j`: `A_j = J_j Z_{j−1}` (`m_j × r_{j−1}`). A Householder QR with column pivoting of
//!   `A_jᵀ = Q_j [R_j; 0] Πᵀ`, truncated where the remaining row norm falls to
//!   [`Settings::rank_tolerance`], gives the rank `k_j`. The level's minimum-norm (damped)
//!   least-squares step is `Z_{j−1} Q_j[:, ..k_j] w_j` with
//!   `w_j = argmin ‖R_jᵀ w − Πᵀ b_j‖² + μ_j² ‖w‖²`, and the next basis is
//!   `Z_j = Z_{j−1} Q_j[:, k_j..]`.
//! * `Z_j` is never formed: it is the product of the stored reflectors, applied to each new task row
//!   (`Z_{j−1}ᵀ J_jᵀ`), to the gradient (`Z_Nᵀ g`), and once, back, to assemble `q̇`.
//! * Damping: when the smallest kept pivot `σ` of a level is below
//!   [`Settings::damping_threshold`] `ε`, `μ² = μ_max² (1 − (σ/ε)²)` (Nakamura–Hanafusa style,
//!   continuous in `σ`); otherwise `μ = 0` and the level is solved exactly. A damped level is
//!   damped toward the stack's damping reference `q̇_ref`
//!   ([`TaskStack::damping_reference_mut`](super::TaskStack::damping_reference_mut), zero by
//!   default): `w_j = argmin ‖R_jᵀ w − Πᵀ b_j‖² + μ_j² ‖w − U_jᵀ q̇_ref‖²`, `U_j` the level's
//!   range basis, so that its poorly conditioned directions keep the reference's motion rather
//!   than come to rest (over the level's range this is `(JᵀJ + μ²I)⁻¹(Jᵀẋ + μ² P q̇_ref)`). A
//!   level holding inequality rows at a bound is damped toward rest: a bound never gives way
//!   to the reference.
//!
//! Lower levels act only in `Z_j`, so they cannot disturb a higher level: its residual is the same
//! with or without them (strict priority), up to rounding and the truncated directions whose
//! singular values are below the rank tolerance.
//!
//! The gradient term is added as `Z_N Z_Nᵀ Σ κ_k ∇f_k` (eq. 6).
//!
//! The clamping loop (Baerlocher & Boulic 2004): after a solve, the free joint whose velocity
//! leaves the interval allowed for this step (position limits over `Δt`, and velocity limits) by
//! the most is fixed at the violated bound and removed from `Z_0`; the stack is solved again, until
//! no free joint violates its interval. (The paper clamps every violator at once; one at a time, like
//! an active-set method, keeps joints free that a near-singular first solution would have pinned.)
//! Each pass clamps one joint, so at most `n + 1` passes run, and the result never violates a
//! limit.
//!
//! # Layout
//!
//! [`Solver`] (`solver.rs`) holds the stack, the workspace every solve reuses and the last
//! result; `clamping.rs` has [`Solver::solve`] and [`Solver::solve_unbounded`], the clamping
//! loop and the scales that fit a step ([`Settings::scale_to_fit`]); `pass.rs` one pass of the
//! recursion above and the report; `rows.rs` what a pass keeps per level and row;
//! [`active_set`] the inequality rows and the joint intervals as an active set;
//! `weighted_dls.rs` [`Method::WeightedDls`]; `settings.rs` [`Settings`] and [`Method`].

pub mod active_set;
mod clamping;
mod pass;
mod rows;
mod settings;
mod solver;
mod weighted_dls;

pub use settings::{Method, Settings};
pub use solver::Solver;
pub use weighted_dls::{limit_criterion_gradient, limit_weight};
