//! Streaming reader of Biovision Hierarchy (BVH) motion capture into [`HumanFrame`](crate::human::HumanFrame)s.
//!
//! # Format
//!
//! A BVH file is a `HIERARCHY` of joints (`ROOT`, nested `JOINT`s, `End Site`s), each with an
//! `OFFSET` from its parent (file units, file axes) and a `CHANNELS n …` list naming, in order, the
//! values it takes per frame (`Xposition Yposition Zposition Xrotation Yrotation Zrotation`, any
//! subset, any order, angles in degrees), then `MOTION`, `Frames: N`, `Frame Time: dt` (seconds)
//! and one line of values per frame, the joints' channels concatenated in file order.
//!
//! # Forward kinematics
//!
//! The convention checked on the CMU files (`tests/data/mocap/README.md` in the repository): for each joint,
//! `R_local = R_c1·R_c2·R_c3` with the rotation channels multiplied **in the order the joint
//! lists them** (so CMU-MB's `Zrotation Yrotation Xrotation` gives `Rz·Ry·Rx`, and CMU-MAX's arm
//! joints' `Zrotation Xrotation Yrotation` give `Rz·Rx·Ry`), `t_local = OFFSET + (position
//! channels)`, then
//!
//! ```text
//! R_global = R_parent_global · R_local
//! p_joint  = p_parent + R_parent_global · t_local      (root: p = t_local, R = R_local)
//! ```
//!
//! Positions are then mapped to the human frame of [`crate::human`]:
//! `p = scale · A · p_bvh`, with `A` from [`UpAxis`] (a proper rotation, so the result stays
//! right-handed) and `scale` the file unit in metres (CMU: 0.056444).
//!
//! # Joint names
//!
//! [`BvhNames`] maps skeleton joints to [`HumanJoint`](crate::human::HumanJoint)s: the CMU MotionBuilder-friendly (CMU-MB)
//! and 3dsMax-friendly (CMU-MAX) skeletons are built in, chosen automatically by
//! [`BvhNames::Auto`]; any other skeleton takes a user map. A human joint the map does not cover
//! is missing in every frame, except [`HumanJoint::MidHip`](crate::human::HumanJoint::MidHip), derived from the two hips.
//!
//! # Why not a crate
//!
//! The crates.io candidates were read before writing this. `bvh_anim` 0.4.0 (last release
//! April 2019, "alpha quality" by its own README) honours per-joint channel order, but it loads
//! the whole motion eagerly (no streaming), stores values as `f32`, reserves
//! `channels × Frames` values straight from the header (a header claiming 10^12 frames aborts the
//! process) and only checks the total value count, not each line's; its dependencies
//! (`smallvec` 0.6, `lexical` 2, `bstr` 0.1) are long outdated. `bvh_anim_parser` 1.0.1 depends on
//! the `cargo` crate, `regex` and `cgmath` and is 17 % documented. Neither fits a streaming,
//! never-panicking reader, so this module is a small hand-written parser (~one screen of grammar).
//!
//! # Limits
//!
//! Nothing is allocated from a number in the file: the frame count only tells when to stop, the
//! per-frame work reuses buffers sized by the hierarchy, whose size is capped by
//! [`BvhConfig::max_joints`]; lines longer than [`BvhConfig::max_line_bytes`] are refused.

mod parse;
mod reader;
mod skeleton;

pub use reader::BvhReader;
pub use skeleton::{
    BvhChannel, BvhConfig, BvhError, BvhJoint, BvhNames, BvhSkeleton, CMU_MAX_NAMES, CMU_MB_NAMES,
    UpAxis,
};
