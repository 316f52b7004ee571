//! Walking where the human walks: where the robot puts its feet ([`footsteps`]: the human's
//! footprints scaled to robot steps), what an offline clip tells of the human's steps ahead
//! ([`look_ahead`]), and the [pattern generator](crate::locomotion) inside the imitation (this
//! module).
//!
//! **Experimental**: with [`FootstepConfig::follow`] and [`FootstepConfig::dynamic`] on, a
//! robot standing
//! in double support whose feet are off the scaled human's footprints (by more than the
//! footstep distance or heading) starts a walk: the footprints are the goals, and at every
//! frame up to two steps toward them are queued in a [`PatternGenerator`] (each clipped to the
//! step envelope around the stance sole, the feet alternating, the profile's step timing). The
//! robot is behind the human, so the generator's preview holds the steps the human has
//! already taken; when the human stops the goals stop moving, the queue runs out and the
//! generator brings the CoM to rest between the feet. Then the imitation goes back to its
//! support phases (a human standing on one leg for [`long_stance_time`] is followed onto one
//! leg there, not while walking).
//!
//! Each walking frame roots the model at the stance sole and solves [`walking_table`]: the other
//! sole where the walk plans it, the CoM's ground point on the generator's, the torso leaning
//! over the stance hip at the cart-table height, the body tracking the posture it started the
//! walk in. Then an arm step ([`walking_arms_table`]) brings the hands toward the scaled
//! human's, at the hands' speed, moving the arm joints alone and keeping the arms clear of the
//! torso and head. The legs move at the walking velocity fraction of their rated speed (the
//! support phases keep Poubel's 10 %).
//!
//! Executable on the NAO: with the landing clearance of
//! [`WalkParams`](crate::locomotion::WalkParams) its walks stand in the physics judge on both
//! servo models. Still off by default: its steps are slow
//! (about 0.02 m/s), pivot turns are not followed, and the G1's walk falls (issue 29's notes).
//!
//! [`PatternGenerator`]: crate::locomotion::PatternGenerator
//! [`FootstepConfig::follow`]: footsteps::FootstepConfig::follow
//! [`FootstepConfig::dynamic`]: footsteps::FootstepConfig::dynamic
//! [`long_stance_time`]: footsteps::FootstepConfig::long_stance_time
//!
//! Units: metres, radians, seconds; world frame as the imitation's.

pub(crate) mod follower;
pub mod footsteps;
pub mod look_ahead;
mod table;

pub use table::{walking_arms_table, walking_table};
