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

mod joints;
mod options;
mod walk;

pub use options::{UrdfError, UrdfFrame, UrdfOptions};

use joints::{finite, number_variables, resolve_drives};
use urdf_rs::JointType;
use walk::{JointGraph, fold_masses, frame_specs, tree_issue_error, walk_tree};

use super::tree::TreeSpec;
use super::{Link, Model};

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
