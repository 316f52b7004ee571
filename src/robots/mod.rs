//! Robots: the biped profile the imitation reads ([`BipedProfile`]: models rooted at the soles,
//! the frames standing for the human's joints, feet, standing posture, step envelope) and the
//! built-in robots, the NAO and the Unitree G1, each with its profile.

mod error;
pub mod g1;
pub mod nao;
pub mod profile;
pub mod profile_toml;
pub mod self_collision;
pub mod servo;
mod size;
pub mod sway;
pub mod tuning;

pub use error::ProfileError;
pub use profile::{
    ASSUMED_FLOOR_FRICTION, BipedProfile, FootArea, FootFrames, HumanJointAngles,
    JointAnglesFactory, LIGHT_FOOT_SHARE, RobotPoint, SolePlacement, outline_bounds,
};
pub use self_collision::{BodyCapsule, FramePoint, SelfCollision};
pub use tuning::{BalancedHands, BipedSize, MotionTuning};
