//! The crate's integration tests, one module per concern (named after the crate's modules), in
//! one test binary: linked once instead of once per file, which took most of CI's test build.
//! Run one concern with `cargo test --release --test suite solver_clamping::`.
//!
//! The binary's allocator counts each thread's allocations (`alloc_counter`), for the tests
//! that prove a warmed-up solve, walk or imitation step allocates nothing; it forwards every
//! call to the system allocator. `tests/hardening_parsers.rs` stays a binary of its own: its
//! allocator measures each allocation's size.

mod alloc_counter;
mod common;
mod solver_common;

#[global_allocator]
static GLOBAL: alloc_counter::Counting = alloc_counter::Counting;

mod batch;
mod batch_session;
mod crate_api;
mod export_motion;
mod hardening_entry_points;
mod hardening_solver;
mod imitation_contact_events;
mod imitation_end_to_end;
mod imitation_hand_support;
mod imitation_koenemann;
mod imitation_koenemann_stability;
mod imitation_koenemann_stops;
mod imitation_metrics;
mod imitation_phase;
mod imitation_priorities;
mod imitation_profiles;
mod imitation_scaler;
mod imitation_support;
mod imitation_urdf_nao;
mod imitation_waist;
mod io_bvh;
mod io_kinect;
mod io_skeleton_map;
mod live;
mod locomotion_alloc;
mod locomotion_generator;
mod locomotion_multibody;
mod locomotion_walker;
mod model_alloc;
mod model_dh;
mod model_fk_example;
mod model_g1;
mod model_kinematics;
mod model_nao;
mod model_statics;
mod model_urdf;
mod problem;
mod robots_self_collision;
mod robots_servo;
mod robots_sway;
mod robots_tuning;
mod scene;
mod soak;
mod solve_benchmark;
mod solver_alloc;
mod solver_clamping;
mod solver_damping_reference;
mod solver_driver;
mod solver_errors;
mod solver_inequalities;
mod solver_priorities;
mod solver_scale_to_fit;
mod solver_weighted_dls;
mod tasks;
mod tasks_alloc;
mod tasks_inequality;
