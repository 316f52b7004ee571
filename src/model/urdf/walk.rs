//! The URDF's link graph walked from the chosen root: joints walked forwards or backwards (module
//! docs of [`super`]), fixed links folded into their moving body's mass and named frames.

use std::collections::HashMap;

use nalgebra::{IsometryMatrix3, Matrix3, Vector3};

use super::joints::{Checked, Drive, check_joint, motion, pose};
use super::options::{UrdfError, UrdfOptions};
use crate::model::Link;
use crate::model::tree::{FrameSpec, JointSpec, TreeIssue, TreeSpec};

/// The joints of a URDF as a graph over its links, each joint checked.
pub(super) struct JointGraph<'r> {
    pub(super) joint_index: HashMap<&'r str, usize>,
    /// The joint whose child each link is, if any.
    pub(super) parent_joint: Vec<Option<usize>>,
    /// (parent link, child link) of each joint.
    pub(super) ends: Vec<(usize, usize)>,
    pub(super) checked: Vec<Checked>,
}

impl<'r> JointGraph<'r> {
    pub(super) fn of(
        robot: &'r urdf_rs::Robot,
        link_index: &HashMap<&str, usize>,
    ) -> Result<Self, UrdfError> {
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
    pub(super) fn only_root(&self) -> Result<usize, UrdfError> {
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
pub(super) struct TreeWalk {
    /// The URDF link that names each body (body 0 is the root).
    pub(super) bodies: Vec<usize>,
    /// The joint of each body after the root, its link still massless.
    pub(super) joints: Vec<JointSpec>,
    /// Per URDF link: its body and the placement of the link's frame in that body.
    pub(super) placed: Vec<(usize, IsometryMatrix3<f64>)>,
}

/// Walks the undirected link graph from `root`: a joint driven by a variable starts a new body
/// (its direction reversed when walked from child to parent), a locked or fixed one folds its
/// far link into the near body.
pub(super) fn walk_tree(
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
pub(super) struct BodyMasses {
    pub(super) mass: Vec<f64>,
    pub(super) com: Vec<Vector3<f64>>,
    pub(super) inertia: Vec<Matrix3<f64>>,
}

/// The links' masses folded into their bodies: m = Σ m_k, c = Σ m_k c_k / m (body frame), and the
/// inertia about c by the parallel-axis theorem: I = Σ R_k I_k R_kᵀ + m_k (|d_k|² 1 − d_k d_kᵀ),
/// d_k = c_k − c.
pub(super) fn fold_masses(
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
pub(super) fn frame_specs(
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
pub(super) fn tree_issue_error(spec: &TreeSpec, issue: TreeIssue) -> UrdfError {
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
