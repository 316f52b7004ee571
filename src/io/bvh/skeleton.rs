//! What a BVH header describes and how it is read: the skeleton (joints, offsets, channels),
//! the file's up axis and joint naming, the reader's settings and its errors.

use std::io;

use nalgebra::{Matrix3, Vector3};

use crate::human::HumanJoint;

/// Errors of the BVH reader. Each names the origin (file path or the string given to
/// [`BvhReader::new`](super::BvhReader::new)), the 1-based line and what is wrong.
#[derive(Debug, thiserror::Error)]
pub enum BvhError {
    /// Reading failed (including invalid UTF-8).
    #[error("{origin}:{line}: read error: {source}")]
    Io {
        /// File or stream name.
        origin: String,
        /// Line being read.
        line: usize,
        /// The underlying error.
        #[source]
        source: io::Error,
    },
    /// A token other than the grammar allows.
    #[error("{origin}:{line}: expected {expected}, found `{found}`")]
    Syntax {
        /// File or stream name.
        origin: String,
        /// Line of the token.
        line: usize,
        /// What the grammar allows here.
        expected: &'static str,
        /// What the file has.
        found: String,
    },
    /// The file ends inside the header.
    #[error("{origin}:{line}: truncated header: file ends where {expected} was expected")]
    TruncatedHeader {
        /// File or stream name.
        origin: String,
        /// Last line of the file.
        line: usize,
        /// What was expected next.
        expected: &'static str,
    },
    /// The file ends before the number of frames its header declares.
    #[error("{origin}:{line}: truncated motion: file ends after {found} of {declared} frames")]
    TruncatedMotion {
        /// File or stream name.
        origin: String,
        /// Last line of the file.
        line: usize,
        /// `Frames:` in the header.
        declared: u64,
        /// Complete frames read.
        found: u64,
    },
    /// `CHANNELS n` followed by a different number of channel names, or more than 6.
    #[error(
        "{origin}:{line}: joint `{joint}` declares {declared} channels but lists {listed} (at most 6)"
    )]
    ChannelCount {
        /// File or stream name.
        origin: String,
        /// Line of the `CHANNELS` statement.
        line: usize,
        /// Joint name.
        joint: String,
        /// The declared count `n`.
        declared: usize,
        /// Channel names on the line.
        listed: usize,
    },
    /// A channel name other than `[XYZ]position` / `[XYZ]rotation`.
    #[error("{origin}:{line}: joint `{joint}`: unknown channel `{channel}`")]
    UnknownChannel {
        /// File or stream name.
        origin: String,
        /// Line of the `CHANNELS` statement.
        line: usize,
        /// Joint name.
        joint: String,
        /// The unknown name.
        channel: String,
    },
    /// A channel list that repeats an axis (e.g. `Zrotation Xrotation Zrotation`), so it is no
    /// rotation order (or translation) this reader can interpret.
    #[error("{origin}:{line}: joint `{joint}`: channel order `{order}` repeats an axis")]
    RotationOrder {
        /// File or stream name.
        origin: String,
        /// Line of the `CHANNELS` statement.
        line: usize,
        /// Joint name.
        joint: String,
        /// The channel list as written.
        order: String,
    },
    /// A value that is not a finite number (or not a non-negative integer where one is needed).
    #[error("{origin}:{line}: {field}: `{text}` is not a valid number")]
    Number {
        /// File or stream name.
        origin: String,
        /// Line of the value.
        line: usize,
        /// Which value (e.g. "OFFSET of joint `LeftLeg`", "value 12 (LeftLeg Zrotation)").
        field: String,
        /// The text found.
        text: String,
    },
    /// A motion line with a different number of values than the hierarchy has channels.
    #[error(
        "{origin}:{line}: frame has {found} values, the hierarchy declares {expected} channels"
    )]
    FrameValueCount {
        /// File or stream name.
        origin: String,
        /// Line of the frame.
        line: usize,
        /// Channels in the hierarchy.
        expected: usize,
        /// Values on the line.
        found: usize,
    },
    /// The file asks for more than the reader's limits allow.
    #[error("{origin}:{line}: {what} exceeds the limit of {limit}")]
    Limit {
        /// File or stream name.
        origin: String,
        /// Line where the limit was hit.
        line: usize,
        /// What is too large.
        what: &'static str,
        /// The limit ([`BvhConfig`]).
        limit: usize,
    },
    /// The name map names a joint the skeleton lacks, or one it has twice.
    #[error("{origin}: name map: joint `{name}` (for {human:?}) {problem}")]
    NameMap {
        /// File or stream name.
        origin: String,
        /// Skeleton joint name in the map.
        name: String,
        /// Human joint it should give.
        human: HumanJoint,
        /// "is not in the skeleton" or "names several joints".
        problem: &'static str,
    },
    /// [`BvhNames::Auto`] found neither the CMU-MB nor the CMU-MAX joint names.
    #[error(
        "{origin}: skeleton is neither CMU-MB nor CMU-MAX (root `{root}`); give a BvhNames::Custom map"
    )]
    UnknownSkeleton {
        /// File or stream name.
        origin: String,
        /// Name of the root joint, to help identify the skeleton.
        root: String,
    },
    /// Forward kinematics overflowed (values finite but so large the position is not).
    #[error("{origin}:{line}: position of joint `{joint}` is not finite")]
    NonFinitePosition {
        /// File or stream name.
        origin: String,
        /// Line of the frame.
        line: usize,
        /// Skeleton joint name.
        joint: String,
    },
    /// A [`BvhConfig`] field is out of range.
    #[error("invalid BVH reader configuration: {0}")]
    Config(&'static str),
}

/// One BVH channel: a translation (file units) or rotation (degrees) about a file axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BvhChannel {
    /// Translation along X.
    Xposition,
    /// Translation along Y.
    Yposition,
    /// Translation along Z.
    Zposition,
    /// Rotation about X (degrees, right-hand rule).
    Xrotation,
    /// Rotation about Y (degrees, right-hand rule).
    Yrotation,
    /// Rotation about Z (degrees, right-hand rule).
    Zrotation,
}

impl BvhChannel {
    /// The channel spelled `name` as in a BVH file (case-sensitive), if any.
    pub fn from_name(name: &str) -> Option<BvhChannel> {
        Some(match name {
            "Xposition" => BvhChannel::Xposition,
            "Yposition" => BvhChannel::Yposition,
            "Zposition" => BvhChannel::Zposition,
            "Xrotation" => BvhChannel::Xrotation,
            "Yrotation" => BvhChannel::Yrotation,
            "Zrotation" => BvhChannel::Zrotation,
            _ => return None,
        })
    }

    /// The channel's name as written in a BVH file.
    pub const fn name(self) -> &'static str {
        match self {
            BvhChannel::Xposition => "Xposition",
            BvhChannel::Yposition => "Yposition",
            BvhChannel::Zposition => "Zposition",
            BvhChannel::Xrotation => "Xrotation",
            BvhChannel::Yrotation => "Yrotation",
            BvhChannel::Zrotation => "Zrotation",
        }
    }

    /// Bit identifying (kind, axis), to detect repeated axes.
    pub(super) const fn bit(self) -> u8 {
        1 << (self as u8)
    }
}

/// One joint of a BVH hierarchy, as written in the file (file units and axes).
#[derive(Clone, Debug, PartialEq)]
pub struct BvhJoint {
    /// Joint name.
    pub name: String,
    /// Index of the parent joint in [`BvhSkeleton::joints`] (`None` for the root). Parents come
    /// before their children.
    pub parent: Option<usize>,
    /// `OFFSET` from the parent joint, file units, parent's axes.
    pub offset: Vector3<f64>,
    /// Channels in file order.
    pub channels: Vec<BvhChannel>,
    /// `End Site` offset (file units, this joint's axes), if the joint has one.
    pub end_site: Option<Vector3<f64>>,
    /// Index of this joint's first value in a motion line.
    pub(super) first_value: usize,
}

/// The hierarchy of a BVH file, joints in file (depth-first) order.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct BvhSkeleton {
    pub(super) joints: Vec<BvhJoint>,
}

impl BvhSkeleton {
    /// The joints in file order (parents before children).
    pub fn joints(&self) -> &[BvhJoint] {
        &self.joints
    }

    /// Index of the first joint named `name`, if any.
    pub fn index_of(&self, name: &str) -> Option<usize> {
        self.joints.iter().position(|j| j.name == name)
    }

    /// Total number of channels, i.e. of values on each motion line.
    pub fn channel_count(&self) -> usize {
        self.joints.iter().map(|j| j.channels.len()).sum()
    }
}

/// Which file axis is up; fixes the rotation `A` from file axes to the human frame
/// (x forward, y left, z up in the source's reference posture).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum UpAxis {
    /// Y up, subject facing +Z with +X on their left (CMU): `(x, y, z) = (Z, X, Y)`.
    Y,
    /// Z up already, file axes kept: `(x, y, z) = (X, Y, Z)`.
    Z,
}

impl UpAxis {
    /// The rotation matrix `A` (file axes → human frame), a proper rotation (det = +1).
    pub fn matrix(self) -> Matrix3<f64> {
        match self {
            UpAxis::Y => Matrix3::new(0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0),
            UpAxis::Z => Matrix3::identity(),
        }
    }
}

/// Which skeleton joint gives which [`HumanJoint`].
#[derive(Clone, Debug, PartialEq)]
pub enum BvhNames {
    /// CMU-MB if the skeleton has all its names, else CMU-MAX if it has all of those, else
    /// [`BvhError::UnknownSkeleton`].
    Auto,
    /// The CMU MotionBuilder-friendly skeleton ([`CMU_MB_NAMES`]).
    CmuMb,
    /// The CMU 3dsMax-friendly skeleton ([`CMU_MAX_NAMES`]).
    CmuMax,
    /// A user map: (skeleton joint name, human joint). Every name must exist in the skeleton.
    Custom(Vec<(String, HumanJoint)>),
}

/// Name map of the CMU MotionBuilder-friendly BVH release (`tests/data/mocap/README.md` in the repository).
/// MidHip is derived from the hips. `LeftHandIndex1` (the knuckles) stands for the hand because
/// `LeftFingerBase` sits exactly on the wrist.
pub const CMU_MB_NAMES: [(&str, HumanJoint); 20] = [
    ("Hips", HumanJoint::Pelvis),
    ("LeftUpLeg", HumanJoint::LHip),
    ("RightUpLeg", HumanJoint::RHip),
    ("LeftLeg", HumanJoint::LKnee),
    ("RightLeg", HumanJoint::RKnee),
    ("LeftFoot", HumanJoint::LAnkle),
    ("RightFoot", HumanJoint::RAnkle),
    ("LeftToeBase", HumanJoint::LToe),
    ("RightToeBase", HumanJoint::RToe),
    ("Spine1", HumanJoint::MidShoulder),
    ("Neck1", HumanJoint::Neck),
    ("Head", HumanJoint::Head),
    ("LeftArm", HumanJoint::LShoulder),
    ("RightArm", HumanJoint::RShoulder),
    ("LeftForeArm", HumanJoint::LElbow),
    ("RightForeArm", HumanJoint::RElbow),
    ("LeftHand", HumanJoint::LWrist),
    ("RightHand", HumanJoint::RWrist),
    ("LeftHandIndex1", HumanJoint::LHand),
    ("RightHandIndex1", HumanJoint::RHand),
];

/// Name map of the CMU 3dsMax-friendly BVH release. Here `LeftShoulder` is the humerus head
/// (CMU-MB's `LeftArm`); `LFingers` stands for the hand because `lhand` sits on the wrist.
pub const CMU_MAX_NAMES: [(&str, HumanJoint); 20] = [
    ("Hips", HumanJoint::Pelvis),
    ("LeftHip", HumanJoint::LHip),
    ("RightHip", HumanJoint::RHip),
    ("LeftKnee", HumanJoint::LKnee),
    ("RightKnee", HumanJoint::RKnee),
    ("LeftAnkle", HumanJoint::LAnkle),
    ("RightAnkle", HumanJoint::RAnkle),
    ("LeftToe", HumanJoint::LToe),
    ("RightToe", HumanJoint::RToe),
    ("Chest2", HumanJoint::MidShoulder),
    ("Neck", HumanJoint::Neck),
    ("Head", HumanJoint::Head),
    ("LeftShoulder", HumanJoint::LShoulder),
    ("RightShoulder", HumanJoint::RShoulder),
    ("LeftElbow", HumanJoint::LElbow),
    ("RightElbow", HumanJoint::RElbow),
    ("LeftWrist", HumanJoint::LWrist),
    ("RightWrist", HumanJoint::RWrist),
    ("LFingers", HumanJoint::LHand),
    ("RFingers", HumanJoint::RHand),
];

/// Settings of a [`BvhReader`](super::BvhReader).
#[derive(Clone, Debug, PartialEq)]
pub struct BvhConfig {
    /// Metres per file unit (CMU: 0.056444 = (1/0.45)·2.54/100; centimetre files: 0.01).
    pub scale: f64,
    /// Which file axis is up.
    pub up: UpAxis,
    /// Skeleton joint names → human joints.
    pub names: BvhNames,
    /// Most joints a hierarchy may declare.
    pub max_joints: usize,
    /// Longest line accepted, in bytes.
    pub max_line_bytes: usize,
}

impl BvhConfig {
    /// Settings for the CMU BVH releases: ×0.056444 to metres, Y up, names detected
    /// automatically, at most 1024 joints and 1 MiB per line.
    pub fn cmu() -> Self {
        BvhConfig {
            scale: 0.056444,
            up: UpAxis::Y,
            names: BvhNames::Auto,
            max_joints: 1024,
            max_line_bytes: 1 << 20,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    pub(super) fn up_axis_matrices_are_proper_rotations() {
        for up in [UpAxis::Y, UpAxis::Z] {
            let a = up.matrix();
            assert!((a.determinant() - 1.0).abs() < 1e-15);
            assert!((a * a.transpose() - Matrix3::identity()).norm() < 1e-15);
        }
        // Y up: file up (0,1,0) becomes z, file +Z (CMU T-pose facing) becomes x.
        let a = UpAxis::Y.matrix();
        assert_eq!(a * Vector3::y(), Vector3::z());
        assert_eq!(a * Vector3::z(), Vector3::x());
    }
}
