//! What the imitation reads off the human, before anything about the robot's balance: which feet
//! support the body ([`support`], Poubel §III.A), the human scaled to the robot's size
//! ([`scaler`], eq. 1) and, for a recorded clip, when body parts start and stop resting on a
//! scene's surfaces ([`contact_events`], Di Fava et al. §III.C).

pub mod contact_events;
pub mod scaler;
pub mod support;
