//! URDF loader (via `urdf-rs`): builds a [`Model`] re-rooted at any link.
//!
//! A URDF joint places its child link `c` in its parent link `p` as `ᵖT_c = O · M(u, v)` (origin
//! `O`, motion `M` about/along the unit axis `u` by the joint value `v`). Rooting the tree at a link
//! `r` walks the undirected link graph from `r`:
//!
//! * a joint walked forwards (parent → child) keeps its origin as placement and its multiplier;
//! * a joint walked backwards (child → parent) uses `ᶜT_p = M(u, −v) · O⁻¹`: placement identity
//!   (in the old child's frame), the same axis, multiplier and offset negated, and the old parent's
//!   model frame is the frame just after the motion, so that link's URDF frame sits at `O⁻¹` in it
//!   (its CoM and the frames fixed to it are re-expressed accordingly).
//!
//! Fixed joints, and the joints locked at a given value, are folded: their child link becomes a
//! named frame of the moving body it is attached to (when [`UrdfOptions::link_frames`] is on), and
//! its mass joins that body's mass, CoM and inertia (`m = Σ m_k`, `c = Σ m_k c_k / m`, parallel-axis
//! theorem about `c`). A `<mimic>` joint
//! `v = μ·v_t + o` of a free joint `t` becomes a joint driven by `t`'s variable; mimics of mimics
//! compose; mimics of locked joints are locked too. Continuous joints are revolute joints with
//! infinite limits. A free base — a `floating` joint from a massless link with no other joint,
//! the `world → pelvis` of most humanoid descriptions — is dropped: a model is a fixed-base tree
//! and rooting it (at a sole, say) is what replaces the free base. All lengths metres, angles
//! radians, masses kilograms.

use std::collections::HashMap;
use std::path::Path;

use nalgebra::{IsometryMatrix3, Matrix3, Rotation3, Translation3, Unit, Vector3};
use thiserror::Error;
use urdf_rs::JointType;

use super::kinematics::rotation_about;
use super::tree::{FrameSpec, JointSpec, TreeIssue, TreeSpec};
use super::{JointKind, Link, Model, Variable};

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

/// How to turn a URDF into a [`Model`].
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
    /// [`MAX_MAGNITUDE`](super::MAX_MAGNITUDE) in magnitude.
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

impl Model {
    /// Builds a model from URDF text (see [`urdf`](self)).
    pub fn from_urdf_str(text: &str, options: &UrdfOptions) -> Result<Model, UrdfError> {
        let mut robot =
            urdf_rs::read_from_string(text).map_err(|e| UrdfError::Xml(e.to_string()))?;
        drop_free_base(&mut robot);
        build(&robot, options)
    }

    /// Reads and builds a URDF file (see [`Model::from_urdf_str`]).
    pub fn from_urdf_file(
        path: impl AsRef<Path>,
        options: &UrdfOptions,
    ) -> Result<Model, UrdfError> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path).map_err(|e| UrdfError::Io {
            path: path.display().to_string(),
            message: e.to_string(),
        })?;
        Model::from_urdf_str(&text, options)
    }
}

/// Removes a free base: a `floating` joint whose parent link is a massless stand-in for the world
/// (no other joint, as in `world → pelvis` of the Unitree and many ROS descriptions). A model is
/// a fixed-base tree rooted where the caller says (a sole, usually); the free base is what the
/// rooting replaces, so the joint and the world link go and the joint's child becomes the
/// default root. Any other `floating` joint stays and is refused by [`check_joint`].
fn drop_free_base(robot: &mut urdf_rs::Robot) {
    let joints_at = |joints: &[urdf_rs::Joint], link: &str| {
        joints
            .iter()
            .filter(|j| j.parent.link == link || j.child.link == link)
            .count()
    };
    let massless = |robot: &urdf_rs::Robot, link: &str| {
        robot
            .links
            .iter()
            .any(|l| l.name == link && l.inertial.mass.value == 0.0)
    };
    let free_base = robot.joints.iter().position(|j| {
        j.joint_type == JointType::Floating
            && joints_at(&robot.joints, &j.parent.link) == 1
            && massless(robot, &j.parent.link)
    });
    if let Some(j) = free_base {
        let world = robot.joints.remove(j).parent.link;
        robot.links.retain(|l| l.name != world);
    }
}

/// How a URDF joint moves once mimics and locks are resolved.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Drive {
    /// Fixed joint, or locked at this joint value.
    Locked(f64),
    /// `value = multiplier · q[variable] + offset`.
    Variable {
        variable: usize,
        multiplier: f64,
        offset: f64,
    },
}

/// Every value finite and at most [`MAX_MAGNITUDE`](super::MAX_MAGNITUDE) in magnitude.
fn finite(place: impl Fn() -> String, values: &[f64]) -> Result<(), UrdfError> {
    match values
        .iter()
        .find(|v| v.is_nan() || v.abs() > super::MAX_MAGNITUDE)
    {
        Some(&value) if value.is_finite() => Err(UrdfError::TooLarge {
            place: place(),
            value,
        }),
        Some(&value) => Err(UrdfError::NonFinite {
            place: place(),
            value,
        }),
        None => Ok(()),
    }
}

fn pose(p: &urdf_rs::Pose) -> IsometryMatrix3<f64> {
    IsometryMatrix3::from_parts(
        Translation3::new(p.xyz[0], p.xyz[1], p.xyz[2]),
        Rotation3::from_euler_angles(p.rpy[0], p.rpy[1], p.rpy[2]),
    )
}

/// `M(u, v)`: the motion of a joint of `kind` by value `v`.
fn motion(kind: JointKind, axis: &Unit<Vector3<f64>>, value: f64) -> IsometryMatrix3<f64> {
    match kind {
        JointKind::Revolute => {
            IsometryMatrix3::from_parts(Translation3::identity(), rotation_about(axis, value))
        }
        JointKind::Prismatic => IsometryMatrix3::from_parts(
            Translation3::from(axis.into_inner() * value),
            Rotation3::identity(),
        ),
        JointKind::Fixed => IsometryMatrix3::identity(),
    }
}

/// Per URDF joint: checked geometry and kind.
struct Checked {
    kind: JointKind,
    axis: Unit<Vector3<f64>>,
    origin: IsometryMatrix3<f64>,
}

fn check_joint(joint: &urdf_rs::Joint) -> Result<Checked, UrdfError> {
    let name = &joint.name;
    let kind = match joint.joint_type {
        JointType::Revolute | JointType::Continuous => JointKind::Revolute,
        JointType::Prismatic => JointKind::Prismatic,
        JointType::Fixed => JointKind::Fixed,
        ref other => {
            return Err(UrdfError::UnsupportedJointType {
                joint: name.clone(),
                kind: format!("{other:?}").to_lowercase(),
            });
        }
    };
    finite(|| format!("joint `{name}` origin"), &joint.origin.xyz.0)?;
    finite(|| format!("joint `{name}` origin"), &joint.origin.rpy.0)?;
    let axis = if kind == JointKind::Fixed {
        Vector3::x_axis()
    } else {
        finite(|| format!("joint `{name}` axis"), &joint.axis.xyz.0)?;
        let a = Vector3::from(joint.axis.xyz.0);
        Unit::try_new(a, 1e-12).ok_or_else(|| UrdfError::ZeroAxis(name.clone()))?
    };
    if let Some(mimic) = &joint.mimic {
        let values = [mimic.multiplier.unwrap_or(1.0), mimic.offset.unwrap_or(0.0)];
        finite(|| format!("joint `{name}` mimic"), &values)?;
    }
    Ok(Checked {
        kind,
        axis,
        origin: pose(&joint.origin),
    })
}

/// Builds the model of `robot` under `options`: checks links and joints, resolves which joints
/// are variables, walks the tree from the root folding rigidly attached links into bodies, and
/// adds the frames.
fn build(robot: &urdf_rs::Robot, options: &UrdfOptions) -> Result<Model, UrdfError> {
    let link_index = check_links(robot)?;
    let graph = JointGraph::of(robot, &link_index)?;
    let drives = resolve_drives(robot, &graph.checked, &graph.joint_index, options)?;
    let (variables, drives) = number_variables(robot, drives, options)?;
    let root = match &options.root_link {
        Some(name) => *link_index
            .get(name.as_str())
            .ok_or_else(|| UrdfError::UnknownRootLink(name.clone()))?,
        None => graph.only_root()?,
    };
    let walk = walk_tree(robot, &graph, &drives, root)?;
    let mut joints = walk.joints;
    let masses = fold_masses(robot, &walk.bodies, &walk.placed);
    let body_link = |b: usize| Link {
        name: robot.links[walk.bodies[b]].name.clone(),
        mass: masses.mass[b],
        com: masses.com[b],
        inertia: Some(masses.inertia[b]),
    };
    for (k, joint) in joints.iter_mut().enumerate() {
        joint.link = body_link(k + 1);
    }
    let frames = frame_specs(robot, options, &link_index, &walk.bodies, &walk.placed)?;
    let spec = TreeSpec {
        name: robot.name.clone(),
        base: body_link(0),
        variables,
        joints,
        frames,
    };
    // Links, joints and variables were checked above and the walk only emits a tree, so in
    // practice only duplicate frame names reach this point; every issue still maps to its name.
    spec.clone()
        .build()
        .map_err(|issue| tree_issue_error(&spec, issue))
}

/// Every link's index by name, after checking names are unique and inertial values are finite
/// with a non-negative mass.
fn check_links(robot: &urdf_rs::Robot) -> Result<HashMap<&str, usize>, UrdfError> {
    let mut link_index: HashMap<&str, usize> = HashMap::new();
    for (i, link) in robot.links.iter().enumerate() {
        if link_index.insert(link.name.as_str(), i).is_some() {
            return Err(UrdfError::DuplicateLink(link.name.clone()));
        }
        let name = &link.name;
        let inertial = &link.inertial;
        finite(|| format!("link `{name}` mass"), &[inertial.mass.value])?;
        if inertial.mass.value < 0.0 {
            return Err(UrdfError::NegativeMass {
                link: name.clone(),
                mass: inertial.mass.value,
            });
        }
        let origin = || format!("link `{name}` inertial origin");
        finite(origin, &inertial.origin.xyz.0)?;
        finite(origin, &inertial.origin.rpy.0)?;
        let i = &inertial.inertia;
        let values = [i.ixx, i.ixy, i.ixz, i.iyy, i.iyz, i.izz];
        finite(|| format!("link `{name}` inertia"), &values)?;
    }
    Ok(link_index)
}

/// The joints of a URDF as a graph over its links, each joint checked.
struct JointGraph<'r> {
    joint_index: HashMap<&'r str, usize>,
    /// The joint whose child each link is, if any.
    parent_joint: Vec<Option<usize>>,
    /// (parent link, child link) of each joint.
    ends: Vec<(usize, usize)>,
    checked: Vec<Checked>,
}

impl<'r> JointGraph<'r> {
    fn of(robot: &'r urdf_rs::Robot, link_index: &HashMap<&str, usize>) -> Result<Self, UrdfError> {
        let mut graph = JointGraph {
            joint_index: HashMap::new(),
            parent_joint: vec![None; robot.links.len()],
            ends: Vec::with_capacity(robot.joints.len()),
            checked: Vec::with_capacity(robot.joints.len()),
        };
        for (j, joint) in robot.joints.iter().enumerate() {
            if graph.joint_index.insert(joint.name.as_str(), j).is_some() {
                return Err(UrdfError::DuplicateJoint(joint.name.clone()));
            }
            let find = |link: &str| {
                link_index
                    .get(link)
                    .copied()
                    .ok_or_else(|| UrdfError::UnknownJointLink {
                        joint: joint.name.clone(),
                        link: link.to_owned(),
                    })
            };
            let (parent, child) = (find(&joint.parent.link)?, find(&joint.child.link)?);
            if let Some(first) = graph.parent_joint[child].replace(j) {
                return Err(UrdfError::TwoParents {
                    link: joint.child.link.clone(),
                    first: robot.joints[first].name.clone(),
                    second: joint.name.clone(),
                });
            }
            graph.ends.push((parent, child));
            graph.checked.push(check_joint(joint)?);
        }
        Ok(graph)
    }

    /// The one link that is no joint's child.
    fn only_root(&self) -> Result<usize, UrdfError> {
        let roots: Vec<usize> = (0..self.parent_joint.len())
            .filter(|&l| self.parent_joint[l].is_none())
            .collect();
        match roots[..] {
            [r] => Ok(r),
            _ => Err(UrdfError::NoUniqueRoot(roots.len())),
        }
    }
}

/// The tree of bodies found by walking the link graph from the root.
struct TreeWalk {
    /// The URDF link that names each body (body 0 is the root).
    bodies: Vec<usize>,
    /// The joint of each body after the root, its link still massless.
    joints: Vec<JointSpec>,
    /// Per URDF link: its body and the placement of the link's frame in that body.
    placed: Vec<(usize, IsometryMatrix3<f64>)>,
}

/// Walks the undirected link graph from `root`: a joint driven by a variable starts a new body
/// (its direction reversed when walked from child to parent), a locked or fixed one folds its
/// far link into the near body.
fn walk_tree(
    robot: &urdf_rs::Robot,
    graph: &JointGraph<'_>,
    drives: &[Drive],
    root: usize,
) -> Result<TreeWalk, UrdfError> {
    let mut adjacent: Vec<Vec<usize>> = vec![Vec::new(); robot.links.len()];
    for (j, &(p, c)) in graph.ends.iter().enumerate() {
        adjacent[p].push(j);
        adjacent[c].push(j);
    }
    let mut body_of: Vec<Option<(usize, IsometryMatrix3<f64>)>> = vec![None; robot.links.len()];
    let mut walk = TreeWalk {
        bodies: vec![root],
        joints: Vec::new(),
        placed: Vec::with_capacity(robot.links.len()),
    };
    body_of[root] = Some((0, IsometryMatrix3::identity()));
    let mut stack = vec![root];
    let mut used_joint = vec![false; robot.joints.len()];
    while let Some(u) = stack.pop() {
        let Some((body, body_t_u)) = body_of[u] else {
            continue;
        };
        for &j in &adjacent[u] {
            if std::mem::replace(&mut used_joint[j], true) {
                continue;
            }
            let (p, c) = graph.ends[j];
            let forward = p == u;
            let v = if forward { c } else { p };
            if body_of[v].is_some() {
                return Err(UrdfError::NotATree(robot.links[v].name.clone()));
            }
            let placed = walk.cross(
                robot,
                j,
                &graph.checked[j],
                drives[j],
                (body, body_t_u),
                v,
                forward,
            );
            body_of[v] = Some(placed);
            stack.push(v);
        }
    }
    for (link, placed) in robot.links.iter().zip(&body_of) {
        walk.placed
            .push(placed.ok_or_else(|| UrdfError::NotATree(link.name.clone()))?);
    }
    Ok(walk)
}

impl TreeWalk {
    /// Crosses joint `j` from the link placed at `(body, body_t_u)` to link `v` (`forward`:
    /// from the joint's parent to its child): returns `v`'s body and placement in it.
    #[allow(clippy::too_many_arguments)] // one step of the walk: the joint and both of its sides
    fn cross(
        &mut self,
        robot: &urdf_rs::Robot,
        j: usize,
        checked: &Checked,
        drive: Drive,
        (body, body_t_u): (usize, IsometryMatrix3<f64>),
        v: usize,
        forward: bool,
    ) -> (usize, IsometryMatrix3<f64>) {
        let Checked { kind, axis, origin } = checked;
        let (variable, multiplier, offset) = match drive {
            Drive::Locked(value) => {
                let u_t_v = origin * motion(*kind, axis, value);
                let u_t_v = if forward { u_t_v } else { u_t_v.inverse() };
                return (body, body_t_u * u_t_v);
            }
            Drive::Variable {
                variable,
                multiplier,
                offset,
            } => (variable, multiplier, offset),
        };
        let sign = if forward { 1.0 } else { -1.0 };
        self.joints.push(JointSpec {
            name: robot.joints[j].name.clone(),
            antecedent: robot.links[self.bodies[body]].name.clone(),
            link: Link {
                name: robot.links[v].name.clone(),
                mass: 0.0,
                com: Vector3::zeros(),
                inertia: None,
            },
            placement: if forward { body_t_u * origin } else { body_t_u },
            axis: *axis,
            kind: *kind,
            variable: Some(variable),
            multiplier: sign * multiplier,
            offset: sign * offset,
        });
        self.bodies.push(v);
        let new_t_v = if forward {
            IsometryMatrix3::identity()
        } else {
            origin.inverse()
        };
        (self.bodies.len() - 1, new_t_v)
    }
}

/// Mass, centre of mass and inertia about it of each body (body frame).
struct BodyMasses {
    mass: Vec<f64>,
    com: Vec<Vector3<f64>>,
    inertia: Vec<Matrix3<f64>>,
}

/// The links' masses folded into their bodies: m = Σ m_k, c = Σ m_k c_k / m (body frame), and the
/// inertia about c by the parallel-axis theorem: I = Σ R_k I_k R_kᵀ + m_k (|d_k|² 1 − d_k d_kᵀ),
/// d_k = c_k − c.
fn fold_masses(
    robot: &urdf_rs::Robot,
    bodies: &[usize],
    placed: &[(usize, IsometryMatrix3<f64>)],
) -> BodyMasses {
    let mut mass = vec![0.0; bodies.len()];
    let mut moment = vec![Vector3::zeros(); bodies.len()];
    let mut com_of_link = Vec::with_capacity(robot.links.len());
    for (link, &(body, body_t_link)) in robot.links.iter().zip(placed) {
        let m = link.inertial.mass.value;
        let c = body_t_link.transform_point(&Vector3::from(link.inertial.origin.xyz.0).into());
        mass[body] += m;
        moment[body] += c.coords * m;
        com_of_link.push(c.coords);
    }
    let com: Vec<Vector3<f64>> = (0..bodies.len())
        .map(|b| match mass[b] > 0.0 {
            true => moment[b] / mass[b],
            false => Vector3::zeros(),
        })
        .collect();
    let mut inertia = vec![Matrix3::zeros(); bodies.len()];
    for ((link, &(body, body_t_link)), c) in robot.links.iter().zip(placed).zip(&com_of_link) {
        let i = &link.inertial.inertia;
        let own = Matrix3::new(
            i.ixx, i.ixy, i.ixz, //
            i.ixy, i.iyy, i.iyz, //
            i.ixz, i.iyz, i.izz,
        );
        let r = body_t_link.rotation * pose(&link.inertial.origin).rotation;
        let d = c - com[body];
        inertia[body] += r.matrix() * own * r.matrix().transpose()
            + (Matrix3::identity() * d.norm_squared() - d * d.transpose())
                * link.inertial.mass.value;
    }
    BodyMasses { mass, com, inertia }
}

/// The named frames: every URDF link's (with `options.link_frames`) and the extra frames of
/// `options`, each on its body.
fn frame_specs(
    robot: &urdf_rs::Robot,
    options: &UrdfOptions,
    link_index: &HashMap<&str, usize>,
    bodies: &[usize],
    placed: &[(usize, IsometryMatrix3<f64>)],
) -> Result<Vec<FrameSpec>, UrdfError> {
    let mut frames = Vec::new();
    if options.link_frames {
        for (link, &(body, body_t_link)) in robot.links.iter().zip(placed) {
            frames.push(FrameSpec {
                name: link.name.clone(),
                link: robot.links[bodies[body]].name.clone(),
                placement: body_t_link,
            });
        }
    }
    for frame in &options.frames {
        let &(body, body_t_link) = link_index
            .get(frame.link.as_str())
            .map(|&l| &placed[l])
            .ok_or_else(|| UrdfError::UnknownFrameLink {
                frame: frame.name.clone(),
                link: frame.link.clone(),
            })?;
        frames.push(FrameSpec {
            name: frame.name.clone(),
            link: robot.links[bodies[body]].name.clone(),
            placement: body_t_link * frame.placement,
        });
    }
    Ok(frames)
}

/// The URDF error naming what a tree-building issue of `spec` is about.
fn tree_issue_error(spec: &TreeSpec, issue: TreeIssue) -> UrdfError {
    match issue {
        TreeIssue::DuplicateFrame(i) => UrdfError::DuplicateFrame(spec.frames[i].name.clone()),
        TreeIssue::UnknownFrameLink(i) => UrdfError::UnknownFrameLink {
            frame: spec.frames[i].name.clone(),
            link: spec.frames[i].link.clone(),
        },
        TreeIssue::DuplicateJoint(i) => UrdfError::DuplicateJoint(spec.joints[i].name.clone()),
        TreeIssue::DuplicateLink(i) => UrdfError::DuplicateLink(spec.joints[i].link.name.clone()),
        TreeIssue::UnknownAntecedent(i) | TreeIssue::Cycle(i) => {
            UrdfError::NotATree(spec.joints[i].link.name.clone())
        }
        TreeIssue::DuplicateVariable(i) | TreeIssue::UnusedVariable(i) => {
            UrdfError::UnknownVariable(spec.variables[i].name.clone())
        }
    }
}

/// Per joint: locked value or (for now) the index of the free URDF joint that drives it.
fn resolve_drives(
    robot: &urdf_rs::Robot,
    checked: &[Checked],
    joint_index: &HashMap<&str, usize>,
    options: &UrdfOptions,
) -> Result<Vec<Drive>, UrdfError> {
    let n = robot.joints.len();
    let mut locked: Vec<Option<f64>> = vec![None; n];
    for (name, value) in &options.locked_joints {
        let j = joint_index
            .get(name.as_str())
            .copied()
            .filter(|&j| checked[j].kind != JointKind::Fixed)
            .ok_or_else(|| UrdfError::UnknownLockedJoint(name.clone()))?;
        finite(|| format!("locked joint `{name}` value"), &[*value])?;
        locked[j] = Some(*value);
    }
    let mut drives: Vec<Option<Drive>> = vec![None; n];
    for j in 0..n {
        resolve(j, robot, checked, joint_index, &locked, &mut drives, 0)?;
    }
    Ok(drives
        .into_iter()
        .map(|d| d.unwrap_or(Drive::Locked(0.0)))
        .collect())
}

/// Resolves joint `j`'s drive, following mimic targets (`depth` guards against mimic loops).
fn resolve(
    j: usize,
    robot: &urdf_rs::Robot,
    checked: &[Checked],
    joint_index: &HashMap<&str, usize>,
    locked: &[Option<f64>],
    drives: &mut [Option<Drive>],
    depth: usize,
) -> Result<Drive, UrdfError> {
    if let Some(d) = drives[j] {
        return Ok(d);
    }
    let joint = &robot.joints[j];
    let drive = match (checked[j].kind, locked[j], &joint.mimic) {
        (JointKind::Fixed, _, _) => Drive::Locked(0.0),
        (_, Some(value), _) => Drive::Locked(value),
        (_, None, None) => Drive::Variable {
            variable: j,
            multiplier: 1.0,
            offset: 0.0,
        },
        (_, None, Some(mimic)) => {
            let bad = || UrdfError::BadMimicTarget {
                joint: joint.name.clone(),
                target: mimic.joint.clone(),
            };
            let t = *joint_index.get(mimic.joint.as_str()).ok_or_else(|| {
                UrdfError::UnknownMimicTarget {
                    joint: joint.name.clone(),
                    target: mimic.joint.clone(),
                }
            })?;
            if checked[t].kind == JointKind::Fixed || depth > robot.joints.len() {
                return Err(bad());
            }
            let (m, o) = (mimic.multiplier.unwrap_or(1.0), mimic.offset.unwrap_or(0.0));
            match resolve(t, robot, checked, joint_index, locked, drives, depth + 1)? {
                Drive::Locked(v) => Drive::Locked(m * v + o),
                Drive::Variable {
                    variable,
                    multiplier,
                    offset,
                } => Drive::Variable {
                    variable,
                    multiplier: m * multiplier,
                    offset: m * offset + o,
                },
            }
        }
    };
    drives[j] = Some(drive);
    Ok(drive)
}

/// The free joints (indices into the URDF's joints) in the order of their variables:
/// `options.variable_order` when given (every free joint named once), else the URDF's.
fn variable_order(
    robot: &urdf_rs::Robot,
    free: &[usize],
    options: &UrdfOptions,
) -> Result<Vec<usize>, UrdfError> {
    match &options.variable_order {
        None => Ok(free.to_vec()),
        Some(names) => {
            let mut order = Vec::with_capacity(names.len());
            for name in names {
                let j = free
                    .iter()
                    .copied()
                    .find(|&j| robot.joints[j].name == *name)
                    .filter(|j| !order.contains(j))
                    .ok_or_else(|| UrdfError::UnknownVariable(name.clone()))?;
                order.push(j);
            }
            if let Some(&missing) = free.iter().find(|j| !order.contains(j)) {
                return Err(UrdfError::MissingVariable(
                    robot.joints[missing].name.clone(),
                ));
            }
            Ok(order)
        }
    }
}

/// The variable of the free joint `joint`: its limits (none for a continuous joint), velocity
/// and effort. Errors: a non-finite limit, lower above upper, a negative velocity or effort.
fn joint_variable(joint: &urdf_rs::Joint) -> Result<Variable, UrdfError> {
    let limit = &joint.limit;
    let (lower, upper) = if joint.joint_type == JointType::Continuous {
        (f64::NEG_INFINITY, f64::INFINITY)
    } else {
        finite(
            || format!("joint `{}` limit", joint.name),
            &[limit.lower, limit.upper],
        )?;
        (limit.lower, limit.upper)
    };
    if lower > upper {
        return Err(UrdfError::LowerAboveUpper {
            joint: joint.name.clone(),
            lower,
            upper,
        });
    }
    // An infinite limit means none.
    if limit.velocity.is_nan() || limit.velocity < 0.0 {
        return Err(UrdfError::NegativeVelocity {
            joint: joint.name.clone(),
            velocity: limit.velocity,
        });
    }
    if limit.effort.is_nan() || limit.effort < 0.0 {
        return Err(UrdfError::NegativeEffort {
            joint: joint.name.clone(),
            effort: limit.effort,
        });
    }
    Ok(Variable {
        name: joint.name.clone(),
        lower,
        upper,
        velocity: limit.velocity,
        // urdf-rs reads a missing effort as 0: no actuator has none, so 0 means "not stated".
        effort: if limit.effort > 0.0 {
            limit.effort
        } else {
            f64::INFINITY
        },
    })
}

/// Numbers the free joints as variables (in `variable_order` or URDF order) and rewrites the
/// drives from free-joint indices to variable indices.
fn number_variables(
    robot: &urdf_rs::Robot,
    drives: Vec<Drive>,
    options: &UrdfOptions,
) -> Result<(Vec<Variable>, Vec<Drive>), UrdfError> {
    let free: Vec<usize> = (0..drives.len())
        .filter(|&j| {
            // A free joint drives itself; mimics are driven by their (resolved) target.
            matches!(drives[j], Drive::Variable { variable, .. } if variable == j)
        })
        .collect();
    let order = variable_order(robot, &free, options)?;
    let mut variable_of = vec![usize::MAX; drives.len()];
    let mut variables = Vec::with_capacity(order.len());
    for (k, &j) in order.iter().enumerate() {
        variable_of[j] = k;
        variables.push(joint_variable(&robot.joints[j])?);
    }
    let drives = drives
        .into_iter()
        .map(|d| match d {
            Drive::Variable {
                variable,
                multiplier,
                offset,
            } => Drive::Variable {
                variable: variable_of[variable],
                multiplier,
                offset,
            },
            locked => locked,
        })
        .collect();
    Ok((variables, drives))
}
