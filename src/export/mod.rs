//! What a run writes for robots and robot-learning pipelines.
//!
//! * [`joints`]: `joints.csv`, the joint angles a robot with position servos plays
//!   ([`JointsWriter`]).
//! * [`motion`]: a run as a [`MotionTrack`]: per frame the time, the joint angles, the world
//!   pose of the robot's floating base and which soles are on the floor; recorded frame by
//!   frame ([`MotionRecorder`]) and resampled to a uniform rate.
//! * [`npz`]: numpy's `.npz` (a zip of `.npy` arrays), written without a dependency:
//!   [`write_motion_npz`] writes `motion.npz`.
//! * [`unitree`]: the CSV layout of Unitree's retargeted LAFAN1 dataset.
//!
//! Frames: the world frame of the imitation (z up, the floor at z = 0, the first frame's right
//! sole at the origin). The floating base is the profile's torso frame
//! ([`BipedProfile::torso`](crate::robots::BipedProfile::torso): the NAO's `torso`, the G1's
//! `pelvis`, the links the robots' URDFs hang everything from). Quaternions are `x y z w`.

pub mod joints;
pub mod motion;
pub mod npz;
pub mod unitree;

pub use joints::JointsWriter;
pub use motion::{ExportError, MotionRecorder, MotionTrack};
pub use npz::{NpyArray, write_motion_npz, write_npz};
pub use unitree::write_unitree_csv;
