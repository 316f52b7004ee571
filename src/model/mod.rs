//! Kinematic trees: one type for robots written as modified-DH tables ([`dh`]) or loaded from a
//! URDF ([`urdf`]), with forward kinematics, point/orientation Jacobians and the centre of mass.
//!
//! # The tree
//!
//! Links are numbered `0..L` in a topological order (link 0 is the fixed base, the antecedent
//! `a(i)` of link `i > 0` has a smaller index, and each subtree is a contiguous index range).
//! Link `i > 0` hangs from its antecedent through joint `i − 1` of [`Model::joints`]:
//!
//! ```text
//! T(a(i) → i) = P_i · M_i(v_i),    v_i = μ_i · q[k_i] + o_i
//! ```
//!
//! where `P_i` is the joint's constant placement, `M_i(v)` a rotation by `v` about the joint's
//! unit axis `u_i` (revolute) or a translation by `v` along it (prismatic), or the identity (fixed),
//! and the joint value `v_i` is an affine function of one variable `q[k_i]` (multiplier `μ_i`,
//! offset `o_i`). Several joints may share one variable (the NAO's HipYawPitch motor drives both
//! legs; URDF `<mimic>` joints). A Khalil–Dombre modified-DH row is the special case
//! `P_i = Rot(z, γ) Trans(z, b) Rot(x, α) Trans(x, d) Rot(z, θ) Trans(z, r)`, `u_i = z`, `o_i = 0`.
//!
//! # Jacobians
//!
//! With `⁰T_i = (R_i, p_i)` the placement of link `i` in the base frame after forward kinematics,
//! `w_i = R_i u_i` the joint axis in the base frame and `A(f)` the moving joints on the path from
//! the base to the link of frame `f`, the column of variable `k` is
//!
//! ```text
//! J_pos(x)[:, k] = Σ_{i ∈ A(f), k_i = k} μ_i · (w_i × (x − p_i))    (revolute)
//!                                        μ_i · w_i                  (prismatic)
//! J_rot(f)[:, k] = Σ_{i ∈ A(f), k_i = k} μ_i · w_i                  (revolute; 0 for prismatic)
//! ```
//!
//! for a point `x` (base frame) fixed to that link; rows are x, y, z of the base frame and the
//! orientation Jacobian maps `q̇` to the angular velocity of the frame expressed in the base frame.
//!
//! # Centre of mass
//!
//! `c = (1/M) Σ_i m_i c_i` over all links (`c_i` the CoM of link `i` in the base frame, `M` the total
//! mass). With `S_i` the mass of the subtree of link `i` and `s_i = Σ_{j ∈ subtree(i)} m_j c_j`
//! (one backward pass), the CoM Jacobian column of variable `k` is
//! `Σ_{i: k_i = k} μ_i · w_i × (s_i − S_i p_i) / M` (revolute) or `μ_i · w_i S_i / M` (prismatic):
//! no per-link Jacobian is formed.
//!
//! # Workspace
//!
//! [`Model`] is immutable (`Send + Sync`, share it freely); [`ModelData`] (from
//! [`Model::new_data`]) holds the placements of one configuration. Nothing allocates on the heap
//! after `new_data`.

pub mod dh;
mod kinematics;
mod levers;
mod statics;
mod tree;
pub mod urdf;

use nalgebra::{IsometryMatrix3, Matrix3, Unit, Vector3};
use thiserror::Error;

pub use dh::DhError;
pub use statics::PointLoad;
pub use urdf::{UrdfError, UrdfFrame, UrdfOptions};

/// Largest magnitude the loaders ([`dh`], [`urdf`]) accept for a number of a robot description
/// (lengths in metres, angles in radians, masses in kilograms, multipliers, offsets, inertias,
/// speeds; except a URDF velocity limit, which only bounds and may be infinite): `10^6`. No robot needs more, and with every number
/// below it the sums and products of forward kinematics, the CoM and the Jacobians stay far from
/// `f64` overflow for any tree that fits in memory. Without it a description with `1e308` in it
/// would load and give an infinite centre of mass.
pub const MAX_MAGNITUDE: f64 = 1e6;

/// How a joint moves its link relative to the antecedent link.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum JointKind {
    /// Rotation about the joint axis by the joint value (radians).
    Revolute,
    /// Translation along the joint axis by the joint value (metres).
    Prismatic,
    /// No motion: the link is rigidly attached to its antecedent.
    Fixed,
}

/// A joint: connects its antecedent link to its own link (the link whose index is this joint's
/// index + 1).
#[derive(Debug, Clone, PartialEq)]
pub struct Joint {
    /// Unique joint name.
    pub name: String,
    /// Index of the antecedent link (the link this joint hangs from).
    pub antecedent: usize,
    /// Constant placement of the joint frame in the antecedent link frame (metres, radians).
    pub placement: IsometryMatrix3<f64>,
    /// Unit axis of the motion, in the joint frame (which is also the link frame for a revolute
    /// joint; a prismatic joint translates the link frame along it).
    pub axis: Unit<Vector3<f64>>,
    /// Revolute, prismatic or fixed.
    pub kind: JointKind,
    /// Index of the driving variable in `q`; `None` for a fixed joint.
    pub variable: Option<usize>,
    /// Joint value = `multiplier · q[variable] + offset` (dimensionless).
    pub multiplier: f64,
    /// Joint value = `multiplier · q[variable] + offset` (radians or metres).
    pub offset: f64,
}

/// A rigid link with its mass properties.
#[derive(Debug, Clone, PartialEq)]
pub struct Link {
    /// Unique link name.
    pub name: String,
    /// Mass in kilograms (≥ 0), including everything rigidly attached to it.
    pub mass: f64,
    /// Centre of mass in the link frame (metres).
    pub com: Vector3<f64>,
    /// Rotational inertia about the centre of mass, in link-frame axes (kg·m²), including
    /// everything rigidly attached; `None` when the source has none (DH tables).
    pub inertia: Option<Matrix3<f64>>,
}

/// An IK variable (an entry of `q`) and its limits.
#[derive(Debug, Clone, PartialEq)]
pub struct Variable {
    /// Unique variable name (for the NAO, the NAOqi joint name).
    pub name: String,
    /// Lower limit (radians, or metres for a prismatic variable).
    pub lower: f64,
    /// Upper limit (radians or metres), ≥ `lower`.
    pub upper: f64,
    /// Maximum speed |q̇| (rad/s or m/s).
    pub velocity: f64,
    /// Largest torque (N·m) or force (N) the variable's actuator gives, > 0; `f64::INFINITY`
    /// when the description states none (DH tables; a URDF `effort` of 0 or left out).
    pub effort: f64,
}

/// A named frame: a link plus a constant placement in that link's frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Frame {
    /// Unique frame name.
    pub name: String,
    /// Index of the link the frame is fixed to.
    pub link: usize,
    /// Placement of the frame in the link frame (metres, radians).
    pub placement: IsometryMatrix3<f64>,
}

/// A Cartesian axis of the base frame (x forward, y left, z up).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Axis {
    /// x (forward).
    X = 0,
    /// y (left).
    Y = 1,
    /// z (up).
    Z = 2,
}

/// Index of a named frame in a [`Model`] (look it up once with [`Model::frame_id`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct FrameId(usize);

impl FrameId {
    /// Position of the frame in [`Model::frames`].
    pub fn index(self) -> usize {
        self.0
    }
}

/// Errors of the kinematic algorithms and name look-ups.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum ModelError {
    /// `q` does not have one entry per variable.
    #[error("q has {got} entries, the model has {expected} variables")]
    WrongQLength {
        /// Number of variables of the model.
        expected: usize,
        /// Length of the given `q`.
        got: usize,
    },
    /// An entry of `q` is NaN or infinite.
    #[error("q[{index}] (variable `{variable}`) is not finite: {value}")]
    NonFiniteQ {
        /// Index in `q`.
        index: usize,
        /// Name of the variable.
        variable: String,
        /// The offending value.
        value: f64,
    },
    /// No named frame has this name.
    #[error("unknown frame `{0}`")]
    UnknownFrame(String),
    /// No variable has this name.
    #[error("unknown variable `{0}`")]
    UnknownVariable(String),
    /// A frame id that does not belong to this model.
    #[error("frame id {0} is out of range")]
    FrameOutOfRange(usize),
    /// A point offset (or other geometric input) is not finite.
    #[error("the point offset is not finite: {0:?}")]
    NonFiniteOffset([f64; 3]),
    /// A number of CoM Jacobian rows other than 1, 2 or 3.
    #[error("{0} CoM Jacobian rows asked (1: x, 2: x and y, 3: x, y and z)")]
    BadRowCount(usize),
    /// The output matrix view has the wrong shape.
    #[error("output matrix is {rows}×{cols}, expected {expected_rows}×{expected_cols}")]
    OutputShape {
        /// Expected number of rows.
        expected_rows: usize,
        /// Expected number of columns (number of variables).
        expected_cols: usize,
        /// Rows of the given view.
        rows: usize,
        /// Columns of the given view.
        cols: usize,
    },
    /// The workspace was created by another model (different sizes).
    #[error("the ModelData was not created by this model")]
    ForeignData,
    /// Jacobians or CoM were asked before [`Model::forward_kinematics`] was run on the data.
    #[error("forward kinematics has not been computed on this ModelData")]
    KinematicsNotComputed,
    /// The model has zero total mass, so its centre of mass is undefined.
    #[error("the model has zero total mass: its centre of mass is undefined")]
    NoMass,
    /// A gravity or load of [`Model::static_torques`] is NaN or infinite.
    #[error("a gravity or load is not finite: {0}")]
    NonFiniteLoad(f64),
}

/// An immutable kinematic tree (see the [module docs](self) for the maths). Two models are equal
/// when their links, joints, variables and frames are.
#[derive(Debug, Clone, PartialEq)]
pub struct Model {
    name: String,
    links: Vec<Link>,
    joints: Vec<Joint>,
    variables: Vec<Variable>,
    frames: Vec<Frame>,
    total_mass: f64,
    /// Per link: mass of the subtree rooted at it (kg).
    subtree_mass: Vec<f64>,
    /// Moving ancestors: links `chain[chain_start[i]..chain_start[i + 1]]` are the links whose
    /// (driven) joint lies on the path from the base to link `i`.
    chain_start: Vec<usize>,
    chain: Vec<usize>,
    /// Links whose joint is driven by a variable (the CoM Jacobian visits these).
    moving: Vec<usize>,
}

/// Mutable workspace of one configuration of a [`Model`]: link and frame placements in the base
/// frame, joint axes, mass moments. Create it with [`Model::new_data`] and reuse it.
#[derive(Debug, Clone)]
pub struct ModelData {
    link_placements: Vec<IsometryMatrix3<f64>>,
    frame_placements: Vec<IsometryMatrix3<f64>>,
    /// Per link: its joint's axis in the base frame.
    axes: Vec<Vector3<f64>>,
    /// Per link: Σ m_j c_j over its subtree, base frame (kg·m).
    mass_moments: Vec<Vector3<f64>>,
    computed: bool,
}

impl ModelData {
    /// Placement of link `link` in the base frame, from the last forward kinematics (identity before).
    ///
    /// # Panics
    /// If `link` is not a link index of the model (`< model.links().len()`).
    pub fn link_placement(&self, link: usize) -> &IsometryMatrix3<f64> {
        &self.link_placements[link]
    }

    /// Placement of a named frame in the base frame, from the last forward kinematics.
    ///
    /// # Panics
    /// If `frame` comes from another model with fewer frames.
    pub fn frame_placement(&self, frame: FrameId) -> &IsometryMatrix3<f64> {
        &self.frame_placements[frame.0]
    }

    /// Placements of all named frames in the base frame, in [`Model::frames`] order.
    pub fn frame_placements(&self) -> &[IsometryMatrix3<f64>] {
        &self.frame_placements
    }
}

impl Model {
    /// Free-text name of the model (from the DH table's `name` or the URDF robot name).
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Links in topological order; link 0 is the fixed base.
    pub fn links(&self) -> &[Link] {
        &self.links
    }

    /// Joints; joint `j` connects `joints[j].antecedent` to link `j + 1`.
    pub fn joints(&self) -> &[Joint] {
        &self.joints
    }

    /// The variables, in the order of `q`.
    pub fn variables(&self) -> &[Variable] {
        &self.variables
    }

    /// Number of variables (the length of `q` and the number of Jacobian columns).
    pub fn nv(&self) -> usize {
        self.variables.len()
    }

    /// Named frames.
    pub fn frames(&self) -> &[Frame] {
        &self.frames
    }

    /// Total mass of all links (kg).
    pub fn total_mass(&self) -> f64 {
        self.total_mass
    }

    /// Id of the named frame `name`.
    pub fn frame_id(&self, name: &str) -> Result<FrameId, ModelError> {
        self.frames
            .iter()
            .position(|f| f.name == name)
            .map(FrameId)
            .ok_or_else(|| ModelError::UnknownFrame(name.to_owned()))
    }

    /// Index in `q` of the variable `name`.
    pub fn variable_index(&self, name: &str) -> Result<usize, ModelError> {
        self.variables
            .iter()
            .position(|v| v.name == name)
            .ok_or_else(|| ModelError::UnknownVariable(name.to_owned()))
    }

    /// Index of the link `name`.
    pub fn link_index(&self, name: &str) -> Option<usize> {
        self.links.iter().position(|l| l.name == name)
    }

    /// A workspace sized for this model (the only allocation of the kinematics).
    pub fn new_data(&self) -> ModelData {
        let nl = self.links.len();
        ModelData {
            link_placements: vec![IsometryMatrix3::identity(); nl],
            frame_placements: vec![IsometryMatrix3::identity(); self.frames.len()],
            axes: vec![Vector3::zeros(); nl],
            mass_moments: vec![Vector3::zeros(); nl],
            computed: false,
        }
    }
}
