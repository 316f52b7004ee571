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
//! A level may also hold **inequality rows** `l_j ≤ C_j q̇ ≤ u_j` beside its equality rows
//! ([`StackShape::with_inequality_level`], [`StackShape::with_mixed_level`]): the stack is then
//! solved lexicographically by an active-set method on the same null-space machinery, with the
//! joint intervals as inequalities above every level (see [`prioritized::active_set`]); the
//! report lists the active rows ([`SolveReport::active_inequalities`]) and the level that gave
//! way ([`SolveReport::first_infeasible_level`]).
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
//!
//! # Bad input
//!
//! No entry point panics on bad numbers or returns NaN: each either refuses the input with a
//! typed [`SolverError`] (whose message names the level, row, column, joint or parameter) and
//! changes nothing, or handles it in the documented way below. The last column names the test
//! (`tests/<file>.rs`, function) that shows it.
//!
//! | Entry point | Bad input | What happens | Test |
//! |---|---|---|---|
//! | [`StackShape`] → [`Solver::new`], [`Solver::with_settings`] | `dof = 0`; no level; a level with 0 rows | `NoDegreesOfFreedom`; `EmptyStack`; `EmptyLevel { level, name }` (the shape itself is plain data, checked when a solver is built) | `solver_errors`, `empty_stack_and_zero_dof_are_rejected` |
//! | [`Solver::with_settings`], [`Solver::set_settings`] | `scale_to_fit` or weighted DLS with inequality rows (or `limits_by_active_set`) | `InvalidParameter { name: "scale_to_fit" }` / `"method (weighted DLS damping)"`; `set_settings` keeps the previous settings | `solver_errors`, `scaling_and_weighted_dls_are_refused_with_inequality_rows` |
//! | [`LevelMut::set_inequality_row`], [`LevelMut::inequalities_mut`], [`TaskStack::inequality_task_mut`] | row ≥ rows; wrong length; unknown task; NaN in the Jacobian or a bound; `lower > upper`, `lower = +∞`, `upper = −∞` | `NoSuchRow`; `DimensionMismatch`; `NoSuchTask`; refused by the next solve: `NonFinite` naming level, row (and column), `InvertedBounds { level, name, row, lower, upper }`. Infinite bounds on one side mean "no bound" | `solver_errors`, `bad_inequality_rows_name_level_and_row` |
//! | [`Solver::with_settings`], [`Solver::set_settings`] ([`Settings`]) | a NaN, infinite or negative field; `rank_tolerance = 0` | `InvalidParameter { name }` naming the field; `set_settings` keeps the previous settings | `solver_errors`, `bad_q_dt_limits_and_settings_are_rejected`; `hardening_entry_points`, `settings_out_of_range_are_refused_by_name_at_construction_and_on_update` |
//! | [`TaskStack::try_level_mut`], [`TaskStack::task_mut`] | a level index or task name the stack lacks | `NoSuchLevel`; `NoSuchTask` ([`TaskStack::level_mut`] panics by contract, like slice indexing) | `solver_errors`, `wrong_sizes_are_rejected` |
//! | [`LevelMut::set_row`] | row ≥ rows; wrong length | `NoSuchRow`; `DimensionMismatch` | `solver_errors`, `wrong_sizes_are_rejected` |
//! | [`LevelMut::set_row`], [`LevelMut::jacobian_mut`], [`LevelMut::target_mut`], [`TaskStack::gradient_mut`] | NaN or ±∞ written | accepted when written (in-place writes stay free), refused by the next solve: `NonFinite` naming level, row and column (Jacobian), level and row (target) or index (gradient); the previous result is kept | `solver_errors`, `non_finite_jacobian_entry_names_level_row_and_column`, `non_finite_target_and_gradient_are_rejected`, `a_rejected_solve_keeps_the_previous_result` |
//! | [`TaskStack::add_gradient`] | non-finite κ; `q` of wrong length or non-finite | `NonFinite` ("gradient gain κ"); `DimensionMismatch`; `NonFinite` ("q at index i"); nothing added | `hardening_entry_points`, `add_gradient_refuses_non_finite_gain_wrong_length_and_non_finite_q` |
//! | [`TaskStack::damping_reference_mut`] | NaN or ±∞ written | refused by the next solve: `NonFinite` ("damping reference at index i") | `solver_damping_reference`, `a_non_finite_reference_is_refused_by_name` |
//! | [`driver::PositionDriver::set_step_reference`] | wrong length; a non-finite entry | `DimensionMismatch`; `NonFinite` ("step reference at index i"); the previous reference kept | `solver_damping_reference`, `the_driver_damps_each_iteration_toward_what_is_left_of_the_step_reference` |
//! | [`Solver::solve`] | `q` or bounds of wrong size; non-finite `q`; `dt` ≤ 0, NaN or ∞ | `DimensionMismatch`; `NonFinite`; `InvalidParameter { name: "dt" }` | `solver_errors`, `wrong_sizes_are_rejected`, `bad_q_dt_limits_and_settings_are_rejected` |
//! | [`Solver::solve`] | `q` outside its limits | graceful: the step lands inside (position wins over velocity, see [`JointBounds`]) | `solver_clamping`, `start_outside_the_limits_lands_inside` |
//! | [`Solver::solve`], [`Solver::solve_unbounded`] | finite but extreme stacks (entries 1e−150…1e150, duplicate rows, all-zero levels, contradictory levels) | graceful: finite velocities within the limits; the report says which levels are infeasible | `hardening_solver`, `random_extreme_stacks_give_finite_bounded_velocities` |
//! | [`Solver::solve_unbounded`] | non-finite Jacobian, target or gradient | `NonFinite` naming the place | `solver_errors`, `non_finite_target_and_gradient_are_rejected` |
//! | [`JointBounds::new`], [`JointBounds::with_velocity`] | NaN limit, `lower > upper`, `lower = +∞`, `upper = −∞`; velocity NaN or < 0; lengths differ | `InvertedLimits { joint }`; `InvalidParameter { name: "velocity limit" }`; `DimensionMismatch`. Infinite limits mean "no limit" | `solver_errors`, `bad_q_dt_limits_and_settings_are_rejected`; `hardening_entry_points`, `joint_bounds_refuse_nan_inverted_and_empty_ranges_and_accept_infinite_ones` |
//! | [`JointBounds::scale_velocity`] | fraction NaN, ∞ or < 0 | `InvalidParameter { name: "velocity fraction" }`, limits unchanged | `hardening_entry_points`, `scale_velocity_refuses_non_finite_and_negative_fractions_and_keeps_the_limits` |
//! | [`JointBounds::clamp_position`] | ±∞ or NaN in `q` | ±∞ clamped to the limits; NaN left as is (clamping is not validation: `solve` and `run` refuse it) | `hardening_entry_points`, `clamp_position_clamps_infinities_and_passes_nan_through` |
//! | [`JointLimitAvoidance::new`] | infinite or zero-width ranges | graceful: those joints do not contribute; a non-finite `q` is refused (`NonFinite`) when the gradient is taken | `hardening_entry_points`, `joint_limit_avoidance_ignores_unbounded_and_zero_width_joints` |
//! | [`JointTracking::new`], [`JointTracking::weighted`], [`JointTracking::set_reference`] | non-finite reference or weight; negative weight; wrong length | `NonFinite`; `InvalidParameter { name: "joint tracking weight" }`; `DimensionMismatch`; `set_reference` keeps the old reference | `solver_errors`, `bad_q_dt_limits_and_settings_are_rejected`; `hardening_entry_points`, `joint_tracking_refuses_bad_weights_and_references_and_keeps_the_old_reference` |
//! | [`driver::PositionDriver::new`], [`driver::PositionDriver::set_settings`] ([`driver::DriverSettings`]) | NaN or negative field; `gain`, `dt` 0 or ∞; `tolerance`, `stall_tolerance` ∞; `max_task_error`, `max_joint_step` 0 (∞ allowed) | `InvalidParameter { name }`; `set_settings` keeps the previous settings | `solver_errors`, `bad_q_dt_limits_and_settings_are_rejected`; `hardening_entry_points`, `driver_settings_out_of_range_are_refused_by_name` |
//! | [`driver::PositionDriver::run`] | `q` or bounds of wrong size; non-finite `q`; a non-finite Jacobian, task error or gradient from the model | `DimensionMismatch`; `NonFinite` ("q at index i", or the stack place), before any step | `hardening_entry_points`, `driver_run_refuses_bad_q_bounds_and_non_finite_task_errors` |
//! | [`driver::PositionDriver::run`] | targets out of reach (a kilometre, 1e300) | graceful: steps clipped to `max_task_error`, `q` finite and within the limits, `Stalled` or `IterationLimit`, the report says which levels gave way | `hardening_entry_points`, `driver_run_refuses_bad_q_bounds_and_non_finite_task_errors`; `hardening_solver`, `targets_a_kilometre_away_are_reported_infeasible_from_the_top` |
//! | [`Model::forward_kinematics`](crate::model::Model::forward_kinematics) | `q` of wrong length; NaN or ±∞ entry | `ModelError::WrongQLength`; `ModelError::NonFiniteQ { index, variable }`; the workspace keeps the previous result | `model_kinematics`, `algorithm_errors_are_typed`; `hardening_entry_points`, `forward_kinematics_refuses_infinite_q_and_leaves_the_data_as_it_was` |
//! | [`Imitator::new`](crate::imitation::imitator::Imitator::new) | `velocity_fraction`, `upper_body_velocity_fraction`, `nominal_dt`, `max_task_speed`, `motion` limits NaN, ∞ or ≤ 0; `footsteps` values NaN or < 0; `iterations_per_frame = 0`; `initial_q` of wrong length | `ImitationError::InvalidParameter { name }`; `ImitationError::Solver(DimensionMismatch)` | `hardening_entry_points`, `imitator_config_out_of_range_is_refused_by_name` |
//! | [`Imitator::step`](crate::imitation::imitator::Imitator::step) | frame time NaN or ±∞; time before the previous frame's | first frame NaN or ±∞, or +∞ later: `ImitationError::Scale(ScaleError::NonFiniteTime)`; NaN or −∞ after a first frame, or an earlier time: `ImitationError::TimeGoesBack`; the imitator's state is unchanged (the same time as the previous frame is accepted, with the nominal Δt) | `hardening_entry_points`, `imitator_refuses_bad_frame_times_without_changing_its_state` |
//! | [`HumanFrame::set`](crate::human::HumanFrame::set) → [`Imitator::step`](crate::imitation::imitator::Imitator::step) | NaN or ±∞ joint position | graceful: the joint is missing (a frame cannot hold a non-finite position); the output equals that of the frame with the joint left out, finite | `hardening_entry_points`, `imitator_treats_non_finite_joint_positions_as_missing` |

mod bounds;
pub(crate) mod check;
pub mod driver;
mod error;
mod gradient;
mod householder;
pub mod prioritized;
mod report;
pub(crate) mod stack;

pub use bounds::JointBounds;
pub use error::SolverError;
pub use gradient::{GradientFunction, JointLimitAvoidance, JointTracking};
pub use prioritized::{Method, Settings, Solver, limit_criterion_gradient, limit_weight};
pub use report::{ActiveInequality, Bound, LevelReport, Solution, SolveReport};
pub use stack::{InequalityRowsMut, LevelMut, LevelSpec, StackShape, TaskSpec, TaskStack};
