//! Streaming reader of Biovision Hierarchy (BVH) motion capture into [`HumanFrame`]s.
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
//! [`BvhNames`] maps skeleton joints to [`HumanJoint`]s: the CMU MotionBuilder-friendly (CMU-MB)
//! and 3dsMax-friendly (CMU-MAX) skeletons are built in, chosen automatically by
//! [`BvhNames::Auto`]; any other skeleton takes a user map. A human joint the map does not cover
//! is missing in every frame, except [`HumanJoint::MidHip`], derived from the two hips.
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

use std::fs::File;
use std::io::{self, BufRead, BufReader};
use std::path::Path;

use nalgebra::{Matrix3, Vector3};

use super::read_line_capped;
use crate::human::{HumanFrame, HumanJoint};

/// Errors of the BVH reader. Each names the origin (file path or the string given to
/// [`BvhReader::new`]), the 1-based line and what is wrong.
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
    const fn bit(self) -> u8 {
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
    first_value: usize,
}

/// The hierarchy of a BVH file, joints in file (depth-first) order.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct BvhSkeleton {
    joints: Vec<BvhJoint>,
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

/// Settings of a [`BvhReader`].
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

/// Streaming BVH reader: parses the header on construction, then yields one [`HumanFrame`] per
/// motion line ([`BvhReader::read_frame`], or as an iterator). Frame `k` has time `k·dt`.
///
/// Per frame it reuses its buffers: reading a frame allocates nothing once the longest line has
/// been seen.
#[derive(Debug)]
pub struct BvhReader<R> {
    reader: R,
    origin: String,
    skeleton: BvhSkeleton,
    frame_time: f64,
    declared_frames: u64,
    frames_read: u64,
    line_no: usize,
    line: String,
    max_line_bytes: usize,
    to_human: Matrix3<f64>,
    values: Vec<f64>,
    rotations: Vec<Matrix3<f64>>,
    positions: Vec<Vector3<f64>>,
    map: [Option<usize>; HumanJoint::COUNT],
    done: bool,
}

impl BvhReader<BufReader<File>> {
    /// Opens the file at `path` and parses its header; the path is the origin in errors.
    pub fn open(path: impl AsRef<Path>, config: BvhConfig) -> Result<Self, BvhError> {
        let path = path.as_ref();
        let origin = path.display().to_string();
        let file = File::open(path).map_err(|source| BvhError::Io {
            origin: origin.clone(),
            line: 0,
            source,
        })?;
        BvhReader::new(BufReader::new(file), origin, config)
    }
}

impl<R: BufRead> BvhReader<R> {
    /// Parses the header (hierarchy, frame count, frame time) from `reader`; `origin` names the
    /// source in errors.
    pub fn new(reader: R, origin: impl Into<String>, config: BvhConfig) -> Result<Self, BvhError> {
        if !(config.scale.is_finite() && config.scale > 0.0) {
            return Err(BvhError::Config("scale must be finite and positive"));
        }
        if config.max_line_bytes == 0 || config.max_joints == 0 {
            return Err(BvhError::Config("limits must be positive"));
        }
        let mut lexer = Lexer {
            reader,
            origin: origin.into(),
            line: String::new(),
            pos: 0,
            line_no: 0,
            max_line_bytes: config.max_line_bytes,
        };
        let skeleton = parse_hierarchy(&mut lexer, config.max_joints)?;
        let (declared_frames, frame_time) = parse_motion_header(&mut lexer)?;
        let map = resolve_names(&skeleton, &config.names, &lexer.origin)?;
        let n = skeleton.joints.len();
        let channels = skeleton.channel_count();
        let Lexer {
            reader,
            origin,
            line,
            line_no,
            ..
        } = lexer;
        Ok(BvhReader {
            reader,
            origin,
            skeleton,
            frame_time,
            declared_frames,
            frames_read: 0,
            line_no,
            line,
            max_line_bytes: config.max_line_bytes,
            to_human: config.up.matrix() * config.scale,
            values: vec![0.0; channels],
            rotations: vec![Matrix3::identity(); n],
            positions: vec![Vector3::zeros(); n],
            map,
            done: false,
        })
    }

    /// The hierarchy.
    pub fn skeleton(&self) -> &BvhSkeleton {
        &self.skeleton
    }

    /// Seconds between frames (`Frame Time`).
    pub fn frame_time(&self) -> f64 {
        self.frame_time
    }

    /// Number of frames the header declares (`Frames`). Not trusted for allocation.
    pub fn declared_frames(&self) -> u64 {
        self.declared_frames
    }

    /// Frames read so far.
    pub fn frames_read(&self) -> u64 {
        self.frames_read
    }

    /// Positions of every skeleton joint in the last frame read, in metres in the human frame
    /// (z up), indexed like [`BvhSkeleton::joints`]. All zeros before the first frame.
    pub fn joint_positions(&self) -> &[Vector3<f64>] {
        &self.positions
    }

    /// Reads the next frame into `out` (its time and every joint; unmapped joints are missing).
    /// Returns `Ok(false)` once all declared frames were read. After an error, the reader is
    /// finished and returns `Ok(false)`.
    pub fn read_frame(&mut self, out: &mut HumanFrame) -> Result<bool, BvhError> {
        if self.done || self.frames_read >= self.declared_frames {
            self.done = true;
            return Ok(false);
        }
        // Frame counts in real files are far below 2^53, so the conversion is exact.
        let time = self.frames_read as f64 * self.frame_time;
        let result = self
            .read_values()
            .and_then(|()| self.forward_kinematics())
            .and_then(|()| {
                if time.is_finite() {
                    Ok(())
                } else {
                    Err(BvhError::Number {
                        origin: self.origin.clone(),
                        line: self.line_no,
                        field: "frame time × frame index".to_owned(),
                        text: time.to_string(),
                    })
                }
            });
        if result.is_err() {
            self.done = true;
        }
        result?;
        out.clear(time);
        for joint in HumanJoint::ALL {
            out.set(joint, self.map[joint.index()].map(|j| self.positions[j]));
        }
        out.derive_mid_hip();
        self.frames_read += 1;
        Ok(true)
    }

    fn read_values(&mut self) -> Result<(), BvhError> {
        loop {
            self.line_no += 1;
            let read = read_line_capped(&mut self.reader, &mut self.line, self.max_line_bytes)
                .map_err(|source| BvhError::Io {
                    origin: self.origin.clone(),
                    line: self.line_no,
                    source,
                })?;
            match read {
                None => {
                    return Err(BvhError::TruncatedMotion {
                        origin: self.origin.clone(),
                        line: self.line_no - 1,
                        declared: self.declared_frames,
                        found: self.frames_read,
                    });
                }
                Some(true) => return Err(self.limit("line length in bytes", self.max_line_bytes)),
                Some(false) if self.line.trim().is_empty() => continue,
                Some(false) => break,
            }
        }
        let expected = self.values.len();
        let mut found = 0;
        for token in self.line.split_ascii_whitespace() {
            if found < expected {
                match token.parse::<f64>() {
                    Ok(v) if v.is_finite() => self.values[found] = v,
                    _ => {
                        return Err(BvhError::Number {
                            origin: self.origin.clone(),
                            line: self.line_no,
                            field: describe_value(&self.skeleton, found),
                            text: token.to_owned(),
                        });
                    }
                }
            }
            found += 1;
        }
        if found != expected {
            return Err(BvhError::FrameValueCount {
                origin: self.origin.clone(),
                line: self.line_no,
                expected,
                found,
            });
        }
        Ok(())
    }

    fn forward_kinematics(&mut self) -> Result<(), BvhError> {
        for (j, joint) in self.skeleton.joints.iter().enumerate() {
            let mut rotation = Matrix3::identity();
            let mut translation = joint.offset;
            let values = &self.values[joint.first_value..joint.first_value + joint.channels.len()];
            for (&channel, &v) in joint.channels.iter().zip(values) {
                match channel {
                    BvhChannel::Xposition => translation.x += v,
                    BvhChannel::Yposition => translation.y += v,
                    BvhChannel::Zposition => translation.z += v,
                    BvhChannel::Xrotation => rotation *= rot_x(v.to_radians()),
                    BvhChannel::Yrotation => rotation *= rot_y(v.to_radians()),
                    BvhChannel::Zrotation => rotation *= rot_z(v.to_radians()),
                }
            }
            // `positions` holds file-frame positions during the pass and is mapped afterwards.
            match joint.parent {
                None => {
                    self.rotations[j] = rotation;
                    self.positions[j] = translation;
                }
                Some(p) => {
                    self.positions[j] = self.positions[p] + self.rotations[p] * translation;
                    self.rotations[j] = self.rotations[p] * rotation;
                }
            }
        }
        for (j, p) in self.positions.iter_mut().enumerate() {
            *p = self.to_human * *p;
            if !p.iter().all(|c| c.is_finite()) {
                return Err(BvhError::NonFinitePosition {
                    origin: self.origin.clone(),
                    line: self.line_no,
                    joint: self.skeleton.joints[j].name.clone(),
                });
            }
        }
        Ok(())
    }

    fn limit(&self, what: &'static str, limit: usize) -> BvhError {
        BvhError::Limit {
            origin: self.origin.clone(),
            line: self.line_no,
            what,
            limit,
        }
    }
}

impl<R: BufRead> Iterator for BvhReader<R> {
    type Item = Result<HumanFrame, BvhError>;

    fn next(&mut self) -> Option<Self::Item> {
        super::next_frame(|frame| self.read_frame(frame))
    }
}

fn rot_x(a: f64) -> Matrix3<f64> {
    let (s, c) = a.sin_cos();
    Matrix3::new(1.0, 0.0, 0.0, 0.0, c, -s, 0.0, s, c)
}

fn rot_y(a: f64) -> Matrix3<f64> {
    let (s, c) = a.sin_cos();
    Matrix3::new(c, 0.0, s, 0.0, 1.0, 0.0, -s, 0.0, c)
}

fn rot_z(a: f64) -> Matrix3<f64> {
    let (s, c) = a.sin_cos();
    Matrix3::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0)
}

/// "value 12 (LeftLeg Zrotation)": names the motion value at `index` for error messages.
fn describe_value(skeleton: &BvhSkeleton, index: usize) -> String {
    skeleton
        .joints
        .iter()
        .find(|j| (j.first_value..j.first_value + j.channels.len()).contains(&index))
        .map(|j| {
            format!(
                "value {} ({} {})",
                index + 1,
                j.name,
                j.channels[index - j.first_value].name()
            )
        })
        .unwrap_or_else(|| format!("value {}", index + 1))
}

/// Tokenizer over the header: whitespace-separated tokens with line numbers.
struct Lexer<R> {
    reader: R,
    origin: String,
    line: String,
    pos: usize,
    line_no: usize,
    max_line_bytes: usize,
}

impl<R: BufRead> Lexer<R> {
    /// Reads the next line; `false` at end of input.
    fn next_line(&mut self) -> Result<bool, BvhError> {
        self.line_no += 1;
        self.pos = 0;
        match read_line_capped(&mut self.reader, &mut self.line, self.max_line_bytes) {
            Ok(None) => {
                self.line_no -= 1;
                Ok(false)
            }
            Ok(Some(false)) => Ok(true),
            Ok(Some(true)) => Err(BvhError::Limit {
                origin: self.origin.clone(),
                line: self.line_no,
                what: "line length in bytes",
                limit: self.max_line_bytes,
            }),
            Err(source) => Err(BvhError::Io {
                origin: self.origin.clone(),
                line: self.line_no,
                source,
            }),
        }
    }

    /// The next token, reading lines as needed; `None` at end of input.
    fn token(&mut self) -> Result<Option<String>, BvhError> {
        loop {
            let rest = &self.line[self.pos..];
            if let Some(start) = rest.find(|c: char| !c.is_ascii_whitespace()) {
                let len = rest[start..]
                    .find(|c: char| c.is_ascii_whitespace())
                    .unwrap_or(rest.len() - start);
                let token = rest[start..start + len].to_owned();
                self.pos += start + len;
                return Ok(Some(token));
            }
            self.pos = self.line.len();
            if !self.next_line()? {
                return Ok(None);
            }
        }
    }

    /// The next token; at end of input a [`BvhError::TruncatedHeader`] saying what was expected.
    fn expect_token(&mut self, expected: &'static str) -> Result<String, BvhError> {
        self.token()?.ok_or_else(|| BvhError::TruncatedHeader {
            origin: self.origin.clone(),
            line: self.line_no,
            expected,
        })
    }

    fn expect_keyword(&mut self, keyword: &'static str) -> Result<(), BvhError> {
        let token = self.expect_token(keyword)?;
        if token == keyword {
            Ok(())
        } else {
            Err(self.syntax(keyword, token))
        }
    }

    /// The tokens left on the current line.
    fn rest_of_line(&mut self) -> Vec<String> {
        let tokens = self.line[self.pos..]
            .split_ascii_whitespace()
            .map(str::to_owned)
            .collect();
        self.pos = self.line.len();
        tokens
    }

    fn number(&mut self, field: impl Fn() -> String) -> Result<f64, BvhError> {
        let text = self.expect_token("a number")?;
        match text.parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(v),
            _ => Err(self.number_error(field(), text)),
        }
    }

    fn vector(&mut self, field: impl Fn() -> String) -> Result<Vector3<f64>, BvhError> {
        Ok(Vector3::new(
            self.number(&field)?,
            self.number(&field)?,
            self.number(&field)?,
        ))
    }

    fn syntax(&self, expected: &'static str, found: String) -> BvhError {
        BvhError::Syntax {
            origin: self.origin.clone(),
            line: self.line_no,
            expected,
            found,
        }
    }

    fn number_error(&self, field: String, text: String) -> BvhError {
        BvhError::Number {
            origin: self.origin.clone(),
            line: self.line_no,
            field,
            text,
        }
    }

    /// The next line with something on it, trimmed; what it should hold is `expected`.
    fn next_content_line(&mut self, expected: &'static str) -> Result<String, BvhError> {
        loop {
            if !self.next_line()? {
                return Err(BvhError::TruncatedHeader {
                    origin: self.origin.clone(),
                    line: self.line_no,
                    expected,
                });
            }
            let trimmed = self.line.trim();
            if !trimmed.is_empty() {
                return Ok(trimmed.to_owned());
            }
        }
    }
}

/// `HIERARCHY ROOT name { … }`, iteratively (an explicit stack, so deep nesting cannot overflow
/// the call stack), up to and including the `MOTION` keyword.
fn parse_hierarchy<R: BufRead>(
    lexer: &mut Lexer<R>,
    max_joints: usize,
) -> Result<BvhSkeleton, BvhError> {
    lexer.expect_keyword("HIERARCHY")?;
    lexer.expect_keyword("ROOT")?;
    let mut joints: Vec<BvhJoint> = Vec::new();
    let mut open: Vec<usize> = Vec::new();
    let mut parent = None;
    loop {
        // Here a joint keyword (ROOT or JOINT) has just been read.
        if joints.len() >= max_joints {
            return Err(BvhError::Limit {
                origin: lexer.origin.clone(),
                line: lexer.line_no,
                what: "number of joints",
                limit: max_joints,
            });
        }
        let name = lexer.expect_token("a joint name")?;
        lexer.expect_keyword("{")?;
        joints.push(BvhJoint {
            name,
            parent,
            offset: Vector3::zeros(),
            channels: Vec::new(),
            end_site: None,
            first_value: 0,
        });
        open.push(joints.len() - 1);
        // Statements of the open joints until the next JOINT (or the end of the hierarchy).
        let next_joint_parent = loop {
            let Some(&current) = open.last() else {
                break None;
            };
            let token = lexer.expect_token("OFFSET, CHANNELS, JOINT, End Site or }")?;
            match token.as_str() {
                "OFFSET" => {
                    let offset =
                        lexer.vector(|| format!("OFFSET of joint `{}`", joints[current].name))?;
                    joints[current].offset = offset;
                }
                "CHANNELS" => {
                    joints[current].channels = parse_channels(lexer, &joints[current].name)?;
                }
                "JOINT" => break Some(current),
                "End" => {
                    lexer.expect_keyword("Site")?;
                    lexer.expect_keyword("{")?;
                    lexer.expect_keyword("OFFSET")?;
                    let offset = lexer.vector(|| {
                        format!("End Site OFFSET of joint `{}`", joints[current].name)
                    })?;
                    lexer.expect_keyword("}")?;
                    joints[current].end_site = Some(offset);
                }
                "}" => {
                    open.pop();
                }
                _ => return Err(lexer.syntax("OFFSET, CHANNELS, JOINT, End Site or }", token)),
            }
        };
        match next_joint_parent {
            Some(p) => parent = Some(p),
            None => break,
        }
    }
    let token = lexer.expect_token("MOTION")?;
    if token != "MOTION" {
        return Err(lexer.syntax("MOTION (one ROOT per file)", token));
    }
    let mut first_value = 0;
    for joint in &mut joints {
        joint.first_value = first_value;
        first_value += joint.channels.len();
    }
    Ok(BvhSkeleton { joints })
}

/// `CHANNELS n c1 … cn` after the keyword: the count and the names on the rest of the line.
fn parse_channels<R: BufRead>(
    lexer: &mut Lexer<R>,
    joint: &str,
) -> Result<Vec<BvhChannel>, BvhError> {
    let count_text = lexer.expect_token("a channel count")?;
    let declared: usize = count_text.parse().map_err(|_| {
        lexer.number_error(
            format!("channel count of joint `{joint}`"),
            count_text.clone(),
        )
    })?;
    let names = lexer.rest_of_line();
    if declared > 6 || names.len() != declared {
        return Err(BvhError::ChannelCount {
            origin: lexer.origin.clone(),
            line: lexer.line_no,
            joint: joint.to_owned(),
            declared,
            listed: names.len(),
        });
    }
    let mut seen = 0u8;
    let mut channels = Vec::with_capacity(declared);
    for name in &names {
        let channel = BvhChannel::from_name(name).ok_or_else(|| BvhError::UnknownChannel {
            origin: lexer.origin.clone(),
            line: lexer.line_no,
            joint: joint.to_owned(),
            channel: name.clone(),
        })?;
        if seen & channel.bit() != 0 {
            return Err(BvhError::RotationOrder {
                origin: lexer.origin.clone(),
                line: lexer.line_no,
                joint: joint.to_owned(),
                order: names.join(" "),
            });
        }
        seen |= channel.bit();
        channels.push(channel);
    }
    Ok(channels)
}

/// `Frames: N` and `Frame Time: dt` after `MOTION`.
fn parse_motion_header<R: BufRead>(lexer: &mut Lexer<R>) -> Result<(u64, f64), BvhError> {
    let rest = lexer.rest_of_line();
    if let Some(extra) = rest.into_iter().next() {
        return Err(lexer.syntax("end of line after MOTION", extra));
    }
    let frames_line = lexer.next_content_line("Frames: N")?;
    let frames_text = labelled_value(&frames_line, &["Frames"])
        .ok_or_else(|| lexer.syntax("Frames: N", frames_line.clone()))?;
    let frames: u64 = frames_text
        .parse()
        .map_err(|_| lexer.number_error("Frames".to_owned(), frames_text.to_owned()))?;
    let time_line = lexer.next_content_line("Frame Time: dt")?;
    let time_text = labelled_value(&time_line, &["Frame", "Time"])
        .ok_or_else(|| lexer.syntax("Frame Time: dt", time_line.clone()))?;
    let frame_time = match time_text.parse::<f64>() {
        Ok(t) if t.is_finite() && t > 0.0 => t,
        _ => return Err(lexer.number_error("Frame Time".to_owned(), time_text.to_owned())),
    };
    Ok((frames, frame_time))
}

/// For `line` = `"Frame Time: 0.0083"` and `words` = `["Frame", "Time"]`: `Some("0.0083")`.
/// The words may be separated by any whitespace; the colon is optional.
fn labelled_value<'a>(line: &'a str, words: &[&str]) -> Option<&'a str> {
    let mut rest = line;
    for word in words {
        rest = rest.trim_start().strip_prefix(word)?;
    }
    let rest = rest.trim_start();
    let rest = rest.strip_prefix(':').unwrap_or(rest).trim();
    (!rest.is_empty() && !rest.contains(char::is_whitespace)).then_some(rest)
}

/// Skeleton index of every human joint under `names`.
fn resolve_names(
    skeleton: &BvhSkeleton,
    names: &BvhNames,
    origin: &str,
) -> Result<[Option<usize>; HumanJoint::COUNT], BvhError> {
    let has_all = |table: &[(&str, HumanJoint)]| {
        table
            .iter()
            .all(|(name, _)| skeleton.index_of(name).is_some())
    };
    let table: Vec<(&str, HumanJoint)> = match names {
        BvhNames::Auto if has_all(&CMU_MB_NAMES) => CMU_MB_NAMES.to_vec(),
        BvhNames::Auto if has_all(&CMU_MAX_NAMES) => CMU_MAX_NAMES.to_vec(),
        BvhNames::Auto => {
            return Err(BvhError::UnknownSkeleton {
                origin: origin.to_owned(),
                root: skeleton
                    .joints
                    .first()
                    .map(|j| j.name.clone())
                    .unwrap_or_default(),
            });
        }
        BvhNames::CmuMb => CMU_MB_NAMES.to_vec(),
        BvhNames::CmuMax => CMU_MAX_NAMES.to_vec(),
        BvhNames::Custom(pairs) => pairs.iter().map(|(n, h)| (n.as_str(), *h)).collect(),
    };
    let mut map = [None; HumanJoint::COUNT];
    for (name, human) in table {
        let mut matches = skeleton
            .joints
            .iter()
            .enumerate()
            .filter(|(_, j)| j.name == name)
            .map(|(i, _)| i);
        let problem = match (matches.next(), matches.next()) {
            (Some(index), None) => {
                map[human.index()] = Some(index);
                continue;
            }
            (None, _) => "is not in the skeleton",
            (Some(_), Some(_)) => "names several joints",
        };
        return Err(BvhError::NameMap {
            origin: origin.to_owned(),
            name: name.to_owned(),
            human,
            problem,
        });
    }
    Ok(map)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn labelled_values() {
        assert_eq!(labelled_value("Frames: 12", &["Frames"]), Some("12"));
        assert_eq!(labelled_value("Frames 12", &["Frames"]), Some("12"));
        assert_eq!(
            labelled_value("Frame  Time:\t.0083", &["Frame", "Time"]),
            Some(".0083")
        );
        assert_eq!(labelled_value("Frames: 1 2", &["Frames"]), None);
        assert_eq!(labelled_value("Frame Time:", &["Frame", "Time"]), None);
    }

    #[test]
    fn up_axis_matrices_are_proper_rotations() {
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
