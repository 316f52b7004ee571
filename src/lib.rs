//! Prioritized task-stack inverse kinematics, and online imitation of human whole-body motion
//! by a humanoid robot (the NAO, the Unitree G1, any biped from its URDF and a short profile),
//! including changes of support from two feet to one and back.
//!
//! Units everywhere: metres, radians, kilograms, seconds. Frames: x forward, y left, z up.
//!
//! The layers point one way: [`solver`], [`model`], [`human`] and [`scene`] (the surfaces around
//! the human) at the bottom; [`tasks`] (tasks named by frame) and [`robots`] (what imitation knows
//! of a robot) above them; [`locomotion`] (walking a queue of footsteps) above those; [`io`] (clip
//! readers) and [`imitation`] above those; [`batch`] and [`problem`] at the edge. The
//! `taskstack` command-line tool (the `cli/` folder of the repository) is built on this API.
//!
//! # Guide
//!
//! ## Solve a custom task stack
//!
//! A [`StackShape`] names the levels and their rows; the [`Solver`] is built once for it and
//! then solves without allocating. Level 1 has strict priority over level 2: level 2 gets its
//! least-squares best in level 1's null space.
//!
//! ```
//! use taskstack::solver::{JointBounds, Solver, StackShape};
//!
//! let shape = StackShape::new(3)
//!     .with_level("primary", &[("sum", 1)])
//!     .with_level("secondary", &[("difference", 1)]);
//! let mut solver = Solver::new(&shape)?;
//! let stack = solver.stack_mut();
//! stack.level_mut(0).set_row(0, &[1.0, 1.0, 1.0], 0.5)?; // J row, desired rate (units/s)
//! stack.level_mut(1).set_row(0, &[1.0, 0.0, -1.0], 0.2)?;
//! let bounds = JointBounds::new(&[-1.0; 3], &[1.0; 3])?; // rad
//! let solution = solver.solve(&[0.0, 0.5, -0.2], &bounds, 0.01)?; // q (rad), dt (s)
//! let v = solution.velocity; // rad/s
//! assert!((v[0] + v[1] + v[2] - 0.5).abs() < 1e-12);
//! assert!((v[0] - v[2] - 0.2).abs() < 1e-12);
//! # Ok::<(), taskstack::solver::SolverError>(())
//! ```
//!
//! ## Load a URDF and solve for a link
//!
//! [`Model::from_urdf_file`] builds a kinematic tree, rooted at any link; every link becomes a
//! named frame. A [`TaskSet`] stacks ready-made tasks by frame name, and the position-level
//! [`solver::driver::PositionDriver`] iterates the solver toward their targets within the joint
//! limits.
//!
//! ```
//! use taskstack::model::UrdfOptions;
//! use taskstack::solver::driver::{DriverSettings, PositionDriver};
//! use taskstack::tasks::{joint_bounds, PositionTask};
//! use taskstack::{Model, Solver, TaskSet, Vector3};
//!
//! let options = UrdfOptions { root_link: Some("pelvis".into()), ..UrdfOptions::default() };
//! let model = Model::from_urdf_file("robots/g1/g1_29dof_rev_1_0.urdf", &options)?;
//! let target = Vector3::new(0.3, -0.2, 0.1); // m, in the pelvis frame
//! let hand = PositionTask::new(&model, "right_rubber_hand", target)?;
//! let mut set = TaskSet::new(&model).level("reach", vec![Box::new(hand)]);
//! let mut solver = Solver::new(&set.shape())?;
//! let mut driver = PositionDriver::new(&solver, DriverSettings::default())?;
//! let mut q = vec![0.0; model.nv()];
//! let report = driver.run(&mut solver, &mut set, &mut q, &joint_bounds(&model)?)?;
//! assert!(report.task_errors()[0] < 1e-3, "the hand reaches the point (m)");
//! # Ok::<(), taskstack::Error>(())
//! ```
//!
//! ## Retarget a clip to a robot
//!
//! An [`Imitator`] takes one human frame at a time (from a clip reader of [`io`], or any live
//! source filling a [`HumanFrame`]) and returns a [`RobotFrame`]: joint angles within the limits
//! and reachable at the allowed velocities, the support phase, the feet and the CoM.
//!
//! ```
//! use taskstack::imitation::reference::support::SupportConfig;
//! use taskstack::io::clip::Clip;
//! use taskstack::robots::nao;
//! use taskstack::{HumanFrame, Imitator, ImitatorConfig};
//!
//! let mut clip = Clip::open("tests/data/mocap/cmu_07_04_slow_walk.bvh")?; // BVH or Kinect CSV
//! let config = ImitatorConfig {
//!     support: SupportConfig::for_capture(clip.capture()), // thresholds for this kind of capture
//!     ..ImitatorConfig::default()
//! };
//! let mut imitator = Imitator::new(nao::profile(), config)?; // or g1::profile(), or a TOML file
//! let mut human = HumanFrame::new(0.0);
//! while clip.read_frame(&mut human)? {
//!     let robot = imitator.step(&human)?;
//!     assert_eq!(robot.q.len(), 23); // rad, in the order of imitator.variable_names()
//! }
//! # Ok::<(), taskstack::Error>(())
//! ```
//!
//! ## Read the outputs
//!
//! Per frame, [`RobotFrame`] holds the joint angles `q` (rad), the `phase` (DS, RS, LS or a
//! transition step of Poubel's Table I), the world placements of both soles and of the model
//! root, the CoM (m, world frame), the scaled human `reference` and the robot's `effectors`
//! (hands and ankles, m, root frame) to compare with it. [`imitation::metrics::MetricsRecorder`]
//! turns the frames into the run's metrics (tracking errors, CoM margin, limit violations,
//! foot slip, travel, solve times). [`batch`] writes them to disk, as the `taskstack` tool does:
//! `joints.csv` (a header `time,<joint names>`, then per frame the time in s and the angles in
//! rad, six decimals; [`export::JointsWriter`]) and `metrics.json` ([`batch::metrics_json`]:
//! the metrics with their units in the key names). The tool adds `view.html`, a 3D viewer of the
//! robot and the scaled human, and SVG plots.
#![forbid(unsafe_code)]
#![deny(missing_docs)]
#![warn(missing_debug_implementations, unreachable_pub)]

pub mod batch;
pub mod error;
pub mod export;
pub mod human;
pub mod imitation;
pub mod io;
pub mod live;
pub mod locomotion;
pub mod model;
pub mod problem;
pub mod robots;
pub mod scene;
pub mod solver;
pub mod tasks;

// What a user touches most, at the crate root.
pub use error::Error;
pub use human::{HumanFrame, HumanJoint, Side};
pub use imitation::phase::SupportPhase;
pub use imitation::{ImitationError, Imitator, ImitatorConfig, RobotFrame};
pub use io::clip::{Clip, ClipError};
pub use model::{Model, ModelData, ModelError};
pub use robots::{BipedProfile, ProfileError};
pub use solver::driver::{DriverSettings, PositionDriver};
pub use solver::{JointBounds, Solver, SolverError, StackShape};
pub use tasks::{
    ComTask, OrientationTask, PoseTask, PositionTask, PostureTask, TaskError, TaskSet,
};

/// The linear-algebra crates of the API, re-exported so that users name the same versions
/// without adding them to their own `Cargo.toml`: `nalgebra` for geometry (points, rotations,
/// rigid transforms), `faer` for the solver's matrix views.
pub use faer;
pub use nalgebra;
/// The geometry types of the API (metres, radians): positions and offsets, planar points,
/// rotations and rigid placements.
pub use nalgebra::{IsometryMatrix3, Rotation3, Vector2, Vector3};

/// The README's code blocks, compiled and run as doctests (the README is not part of the crate
/// documentation: its image paths are the repository's).
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;
