//! Human-to-robot imitation: a stream of human frames in, executable robot postures out.
//!
//! A motion source (a BVH file, a Kinect stream; see [`crate::io`]) yields one
//! [`crate::human::HumanFrame`] per time step: named joint positions in metres in a right-handed
//! frame with z up. [`imitator::Imitator`] runs the pipeline frame by frame ([`crate::batch`] over
//! many clips in parallel). The rooms, bottom up (a room imports only rooms before it in this
//! list, besides the [`config`] and [`error`] every room shares):
//!
//! * [`reference`](mod@reference): what is read off the human: which feet support the body
//!   ([`reference::support::SupportDetector`], Poubel §III.A), the human scaled to the robot
//!   (eq. 1), a recorded clip's contact events with a scene;
//! * [`phase`]: the robot's support phase ([`phase::PhaseMachine`]: DS, RS, LS and the two-step
//!   transitions of Table I, each step ended on measured conditions), the task tables that say
//!   what is solved in each phase ([`phase::tables::TaskTables`], Table I as data) and the
//!   prioritized solve of one phase's table; [`shaping`]: the speed of the references that
//!   decide whether the robot stays up;
//! * [`output`]: what a frame returns ([`output::RobotFrame`]); [`reach`]: what the robot's arm
//!   can reach;
//! * [`walking`]: the robot's own steps where the human steps (footstep planning, the look-ahead
//!   of an offline clip, the pattern generator inside the imitation);
//! * the two methods, [`poubel`] (the default) and [`koenemann`], on the robot's state both
//!   share (a private module);
//! * [`imitator`]: the dispatcher a user holds; [`metrics`]: what a run did, measured frame by
//!   frame (hands, balance, travel, walking, clearance).

pub mod config;
pub mod error;
pub mod imitator;
pub mod koenemann;
pub mod metrics;
pub mod output;
pub mod phase;
pub mod poubel;
pub mod reach;
pub mod reference;
pub mod shaping;
mod state;
pub mod walking;

pub use config::{ImitationMethod, ImitatorConfig};
pub use error::ImitationError;
pub use imitator::Imitator;
pub use output::{EFFECTORS, RobotFrame};

// The paths of the modules before they moved into their rooms, kept for one release.
#[doc(hidden)]
pub use metrics::{clearance, travel};
#[doc(hidden)]
pub use phase::tables;
#[doc(hidden)]
pub use poubel::hand_support;
#[doc(hidden)]
pub use reference::{contact_events, scaler, support};
#[doc(hidden)]
pub use walking::{footsteps, look_ahead};
