//! Human-to-robot imitation: the human skeleton frame every motion source is converted
//! to, and the detection of which of the human's feet support the body.
//!
//! A motion source (a BVH file, a Kinect stream; see [`crate::io`]) yields one
//! [`crate::human::HumanFrame`] per time step: named joint positions in metres in a right-handed frame
//! with z up. [`support::SupportDetector`] turns the stream of frames into a stream of
//! [`support::HumanSupport`] phases (Poubel §III.A). [`phase::PhaseMachine`] turns those into the
//! robot's [`phase::SupportPhase`] (DS, RS, LS and the two-step transitions of Table I), ending
//! each transition step on measured conditions; [`tables::TaskTables`] says, per phase, which
//! model root, equality levels and gradient tasks the IK solves (Table I as data).
//! [`imitator::Imitator`] runs the whole pipeline frame by frame; [`crate::batch`] runs it over
//! many clips in parallel.

pub mod clearance;
pub mod config;
pub mod contact_events;
pub mod error;
pub mod footsteps;
pub mod hand_support;
pub mod imitator;
pub mod koenemann;
pub mod look_ahead;
pub mod metrics;
pub mod output;
pub mod phase;
mod phase_solver;
mod poubel;
pub mod reach;
pub mod scaler;
pub mod shaping;
mod shoulder_anchor;
mod state;
pub mod support;
pub mod tables;
pub mod travel;
pub mod walking;
mod zmp_balance;
