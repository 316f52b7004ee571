//! Poubel et al.'s method (the default, run by [`super::imitator::Imitator`]): the support-phase
//! machine drives the task tables of Table I ([`super::phase`]), one prioritized solve per frame;
//! the hands may rest on the scene ([`hand_support`]); the scaled arms hang from the robot's own
//! shoulders, not the scaled human's.

mod config;
pub mod hand_support;
mod imitator;
mod setup;
mod shoulder_anchor;

pub use config::PoubelConfig;
pub(crate) use imitator::PoubelImitator;
