//! Walking: footsteps in, a balanced CoM trajectory and swing-foot paths out.
//!
//! [`PatternGenerator`] takes a queue of [`Footstep`]s (which foot, where it lands in the world,
//! how long the double and single support take) and, every control tick, gives the CoM
//! trajectory whose **zero-moment point** stays on the support, the swing sole's path and which
//! feet are on the floor ([`WalkState`]). It knows no robot: a robot enters through the CoM
//! height, the sole outlines and the timing, which [`params`] derives from a
//! [`BipedProfile`](crate::robots::BipedProfile). [`walker::WholeBodyWalker`] turns the states
//! into joint angles with the task-stack solver.
//!
//! ```
//! use taskstack::locomotion::{GroundPose, WalkParams, WholeBodyWalker, goal_feet, plan_steps};
//! use taskstack::robots::nao;
//!
//! let profile = nao::profile();
//! let params = WalkParams::for_profile(&profile)?; // derived from the NAO's size
//! let timing = params.timing;
//! // The right sole at the world origin, facing x.
//! let mut walker = WholeBodyWalker::new(&profile, params, GroundPose::new(0.0, 0.0, 0.0))?;
//! let start = *walker.generator().standing_feet();
//! let goal = goal_feet(&start, &GroundPose::new(0.1, 0.0, 0.0)); // 10 cm forward
//! for step in plan_steps(&start, &goal, &profile.step_envelope, timing, 20) {
//!     walker.push(step)?;
//! }
//! while !walker.generator().is_stopped() {
//!     let frame = walker.tick()?; // every 10 ms
//!     assert!(frame.com_error < 1e-4); // m
//!     let _q = walker.q(); // joint angles (rad) for a robot or `JointsWriter`
//! }
//! let end = walker.generator().standing_feet();
//! assert!((end[0].xy - goal[0].xy).norm() < 1e-9);
//! # Ok::<(), taskstack::Error>(())
//! ```
//!
//! # The model
//!
//! The robot is a cart on a table (the linear inverted pendulum with its CoM at a constant
//! height `z_c`): the ZMP of a CoM motion `c(t)` is `p = c − (z_c/g) c̈`, per horizontal axis.
//! The reference ZMP `p*(t)` sits at the centre of the stance sole in single support and moves
//! from one sole centre to the next in double support (cubic blend). The CoM is found by
//! **ZMP preview control** (Kajita et al., *Biped walking pattern generation by using preview
//! control of zero-moment point*, ICRA 2003): a discrete LQ tracker of `p*` with the jerk as input,
//! whose feedforward weighs the reference over the next `N` ticks. Its gains ([`PreviewGains`])
//! solve a Riccati equation once per robot and tick ([`preview`] states the maths).
//!
//! # Why preview control and not a DCM planner
//!
//! Both keep the ZMP on the support. We chose preview control because the imitation feeds the
//! generator an *online, changing* queue: the robot is behind the human, so the next steps are
//! known, but a step may be added at any tick. The preview controller consumes whatever the
//! queue says over its window and re-plans every tick with a fixed cost (`N` multiply-adds per
//! axis, no allocation), it needs no end-of-plan boundary condition (a DCM plan is solved
//! backwards from a final capture point, so each added step changes the whole plan), and a
//! queue that runs short is simply a reference that comes to rest between the feet (a stop in
//! double support). The ZMP follows its reference within millimetres with Kajita's weights
//! (`Q = 1`, `R = 1e-6`). Not measured: a DCM planner in physics side by side.
//!
//! # Frames and units
//!
//! World frame: x forward, y left, z up, the floor at z = 0. Metres, radians, seconds.

pub mod footstep;
pub mod generator;
pub mod margin;
pub mod multibody;
pub mod params;
pub mod planner;
pub mod preview;
pub mod schedule;
pub mod swing;
pub mod walker;

use thiserror::Error;

pub use footstep::{Footstep, GroundPose, StepTiming};
pub use generator::{PatternGenerator, WalkSettings, WalkState};
pub use margin::SupportPolygon;
pub use multibody::MultibodyZmp;
pub use params::WalkParams;
pub use planner::{StepPlan, goal_feet, plan_steps};
pub use preview::{CartTable, PreviewGains, PreviewSettings};
pub use schedule::{SoleCentres, Support};
pub use swing::{SolePose, SwingProfile};
pub use walker::{WalkerError, WalkerFrame, WholeBodyWalker};

/// Errors of the walking pattern generator and walker.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum LocomotionError {
    /// A setting out of range.
    #[error("locomotion: {name} = {value}: {reason}")]
    InvalidParameter {
        /// The setting.
        name: &'static str,
        /// Its value.
        value: f64,
        /// What is expected.
        reason: &'static str,
    },
    /// A non-finite input.
    #[error("locomotion: {0} is not finite")]
    NonFinite(&'static str),
    /// The step queue is full.
    #[error("locomotion: the step queue is full ({capacity} steps); tick until a step lands")]
    QueueFull {
        /// The queue's capacity (steps).
        capacity: usize,
    },
    /// The Riccati iteration of the preview gains did not converge.
    #[error("locomotion: the Riccati equation of the preview controller did not converge")]
    RiccatiDiverged,
}
