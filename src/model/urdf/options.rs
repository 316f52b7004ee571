//! What the URDF loader takes besides the file ([`UrdfOptions`], [`UrdfFrame`]) and how it fails
//! ([`UrdfError`]).

use nalgebra::IsometryMatrix3;
use thiserror::Error;

/// A named frame to add to a URDF model: a URDF link plus a placement in that link's frame.
#[derive(Debug, Clone, PartialEq)]
pub struct UrdfFrame {
    /// Name of the frame (unique).
    pub name: String,
    /// URDF link the frame is fixed to (any link, also one folded by a fixed joint).
    pub link: String,
    /// Placement of the frame in the URDF link's frame (metres, radians).
    pub placement: IsometryMatrix3<f64>,
}

/// How to turn a URDF into a [`Model`](crate::model::Model).
#[derive(Debug, Clone, PartialEq)]
pub struct UrdfOptions {
    /// The link to use as fixed base (default: the URDF's root link).
    pub root_link: Option<String>,
    /// Joints fixed at a value (radians or metres) instead of becoming variables; joints that
    /// mimic them are locked too.
    pub locked_joints: Vec<(String, f64)>,
    /// Order of the variables (names of the free joints, all of them); default: URDF joint order.
    pub variable_order: Option<Vec<String>>,
    /// Extra named frames.
    pub frames: Vec<UrdfFrame>,
    /// Also make every URDF link a named frame of the same name (default true).
    pub link_frames: bool,
}

impl Default for UrdfOptions {
    fn default() -> Self {
        UrdfOptions {
            root_link: None,
            locked_joints: Vec::new(),
            variable_order: None,
            frames: Vec::new(),
            link_frames: true,
        }
    }
}

/// Errors of the URDF loader; each names the joint, link or frame at fault.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum UrdfError {
    /// The file could not be read.
    #[error("{path}: cannot read: {message}")]
    Io {
        /// File path.
        path: String,
        /// The I/O error.
        message: String,
    },
    /// Malformed XML or URDF structure (message from urdf-rs).
    #[error("malformed URDF: {0}")]
    Xml(String),
    /// Two links share a name.
    #[error("duplicate link `{0}`")]
    DuplicateLink(String),
    /// Two joints share a name.
    #[error("duplicate joint `{0}`")]
    DuplicateJoint(String),
    /// A joint names a parent or child link that does not exist.
    #[error("joint `{joint}`: unknown link `{link}`")]
    UnknownJointLink {
        /// Joint name.
        joint: String,
        /// The missing link.
        link: String,
    },
    /// A link is the child of two joints.
    #[error("link `{link}` is the child of two joints (`{first}`, `{second}`)")]
    TwoParents {
        /// Link name.
        link: String,
        /// First parent joint.
        first: String,
        /// Second parent joint.
        second: String,
    },
    /// The requested root link does not exist.
    #[error("unknown root link `{0}`")]
    UnknownRootLink(String),
    /// No root given and the URDF does not have exactly one link without parent.
    #[error("the URDF has {0} links without a parent joint (expected exactly 1)")]
    NoUniqueRoot(usize),
    /// A link is not connected to the root, or the joints form a loop.
    #[error("link `{0}` is not reachable from the root as a tree (disconnected or in a loop)")]
    NotATree(String),
    /// Planar or spherical joints are not supported, nor floating joints other than a free base
    /// (a `floating` joint from a massless world link, which is dropped: the model's root
    /// replaces it).
    #[error("joint `{joint}`: unsupported type {kind}")]
    UnsupportedJointType {
        /// Joint name.
        joint: String,
        /// The URDF type.
        kind: String,
    },
    /// A movable joint with a zero axis.
    #[error("joint `{0}`: zero axis")]
    ZeroAxis(String),
    /// A number (origin, axis, limit, mimic, mass, CoM, locked value) is NaN or infinite.
    #[error("{place}: not a finite number ({value})")]
    NonFinite {
        /// E.g. "joint `HeadYaw` origin".
        place: String,
        /// The offending value.
        value: f64,
    },
    /// A number (origin, axis, limit, mimic, mass, CoM, inertia, locked value) above
    /// [`MAX_MAGNITUDE`](crate::model::MAX_MAGNITUDE) in magnitude.
    #[error("{place}: magnitude above 1e6 ({value})")]
    TooLarge {
        /// E.g. "joint `HeadYaw` origin".
        place: String,
        /// The offending value.
        value: f64,
    },
    /// A joint with a negative (or NaN) velocity limit.
    #[error("joint `{joint}`: velocity limit {velocity} is not >= 0")]
    NegativeVelocity {
        /// Joint name.
        joint: String,
        /// The velocity limit (rad/s or m/s).
        velocity: f64,
    },
    /// A joint with a negative (or NaN) effort limit.
    #[error("joint `{joint}`: effort limit {effort} is not >= 0")]
    NegativeEffort {
        /// Joint name.
        joint: String,
        /// The effort limit (N·m or N).
        effort: f64,
    },
    /// A link with negative mass.
    #[error("link `{link}`: negative mass {mass}")]
    NegativeMass {
        /// Link name.
        link: String,
        /// The mass (kg).
        mass: f64,
    },
    /// A joint's lower limit is above its upper limit.
    #[error("joint `{joint}`: lower limit {lower} above upper limit {upper}")]
    LowerAboveUpper {
        /// Joint name.
        joint: String,
        /// Lower limit.
        lower: f64,
        /// Upper limit.
        upper: f64,
    },
    /// A `<mimic>` names a joint that does not exist.
    #[error("joint `{joint}`: unknown mimic target `{target}`")]
    UnknownMimicTarget {
        /// The mimic joint.
        joint: String,
        /// The missing target.
        target: String,
    },
    /// A `<mimic>` names a fixed joint, or mimics form a loop.
    #[error("joint `{joint}`: mimic target `{target}` is fixed or part of a mimic loop")]
    BadMimicTarget {
        /// The mimic joint.
        joint: String,
        /// The target.
        target: String,
    },
    /// A locked joint that does not exist or cannot move.
    #[error("locked joint `{0}` is not a movable joint of the URDF")]
    UnknownLockedJoint(String),
    /// `variable_order` names something that is not a free joint (unknown, fixed, mimic, locked),
    /// or names it twice.
    #[error("variable order: `{0}` is not a free joint of the URDF (or is listed twice)")]
    UnknownVariable(String),
    /// `variable_order` leaves out a free joint.
    #[error("variable order: free joint `{0}` is missing")]
    MissingVariable(String),
    /// An extra frame names a link that does not exist.
    #[error("frame `{frame}`: unknown link `{link}`")]
    UnknownFrameLink {
        /// Frame name.
        frame: String,
        /// The missing link.
        link: String,
    },
    /// Two named frames share a name.
    #[error("duplicate frame `{0}`")]
    DuplicateFrame(String),
}
