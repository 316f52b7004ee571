//! Human-to-robot imitation (DESIGN §4): the human skeleton frame every motion source is converted
//! to, and the detection of which of the human's feet support the body.
//!
//! A motion source (a BVH file, a Kinect stream; see [`crate::io`]) yields one
//! [`human::HumanFrame`] per time step: named joint positions in metres in a right-handed frame
//! with z up. [`support::SupportDetector`] turns the stream of frames into a stream of
//! [`support::HumanSupport`] phases (Poubel §III.A).

pub mod human;
pub mod scaler;
pub mod support;
