//! Assembly of a [`Model`] from joints given in any order with antecedents named by link name:
//! topological (depth-first preorder) sort, structural checks, and the precomputed ancestor
//! chains and subtree masses the algorithms use. Shared by the DH and URDF loaders, which turn a
//! [`TreeIssue`] (indices into their own rows) into an error naming the file, row and field.

use std::collections::HashMap;

use nalgebra::{IsometryMatrix3, Unit, Vector3};

use super::{Frame, Joint, JointKind, Link, Model, Variable};

/// One joint and the link it carries, antecedent given by name.
#[derive(Debug, Clone)]
pub(crate) struct JointSpec {
    pub name: String,
    pub antecedent: String,
    pub link: Link,
    pub placement: IsometryMatrix3<f64>,
    pub axis: Unit<Vector3<f64>>,
    pub kind: JointKind,
    pub variable: Option<usize>,
    pub multiplier: f64,
    pub offset: f64,
}

/// A named frame fixed to a link given by name.
#[derive(Debug, Clone)]
pub(crate) struct FrameSpec {
    pub name: String,
    pub link: String,
    pub placement: IsometryMatrix3<f64>,
}

/// A whole tree before sorting.
#[derive(Debug, Clone)]
pub(crate) struct TreeSpec {
    pub name: String,
    pub base: Link,
    pub variables: Vec<Variable>,
    pub joints: Vec<JointSpec>,
    pub frames: Vec<FrameSpec>,
}

/// What is wrong with a [`TreeSpec`]; indices are positions in its vectors.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum TreeIssue {
    DuplicateVariable(usize),
    DuplicateJoint(usize),
    /// Joint row whose link name is already used (by the base or an earlier row).
    DuplicateLink(usize),
    UnknownAntecedent(usize),
    /// Joint row that cannot be reached from the base although its antecedent exists.
    Cycle(usize),
    UnusedVariable(usize),
    DuplicateFrame(usize),
    UnknownFrameLink(usize),
}

impl TreeSpec {
    pub(crate) fn build(self) -> Result<Model, TreeIssue> {
        let TreeSpec {
            name,
            base,
            variables,
            joints,
            frames,
        } = self;
        first_duplicate(variables.iter().map(|v| v.name.as_str()))
            .map_or(Ok(()), |i| Err(TreeIssue::DuplicateVariable(i)))?;
        first_duplicate(joints.iter().map(|j| j.name.as_str()))
            .map_or(Ok(()), |i| Err(TreeIssue::DuplicateJoint(i)))?;
        let (order, parent_row) = preorder(&base, &joints)?;
        let mut used = vec![false; variables.len()];
        for j in &joints {
            if let Some(v) = j.variable {
                used[v] = true;
            }
        }
        if let Some(v) = used.iter().position(|u| !u) {
            return Err(TreeIssue::UnusedVariable(v));
        }
        // Row → new link index (base is link 0).
        let mut index_of_row = vec![0usize; joints.len()];
        for (k, &row) in order.iter().enumerate() {
            index_of_row[row] = k + 1;
        }
        let link_index = |row: Option<usize>| row.map_or(0, |r| index_of_row[r]);
        let mut links = Vec::with_capacity(joints.len() + 1);
        links.push(base);
        let mut sorted_joints = Vec::with_capacity(joints.len());
        let mut slots: Vec<Option<JointSpec>> = joints.into_iter().map(Some).collect();
        for &row in &order {
            let Some(spec) = slots[row].take() else {
                continue;
            };
            let antecedent = link_index(parent_row[row]);
            links.push(spec.link);
            sorted_joints.push(Joint {
                name: spec.name,
                antecedent,
                placement: spec.placement,
                axis: spec.axis,
                kind: spec.kind,
                variable: spec.variable,
                multiplier: spec.multiplier,
                offset: spec.offset,
            });
        }
        let model_frames = attach_frames(frames, &links)?;
        Ok(Model::assemble(
            name,
            links,
            sorted_joints,
            variables,
            model_frames,
        ))
    }
}

/// The joint rows in depth-first preorder from the base (parents before children, subtrees
/// contiguous), and the row defining each row's parent link (`None`: the base).
fn preorder(
    base: &Link,
    joints: &[JointSpec],
) -> Result<(Vec<usize>, Vec<Option<usize>>), TreeIssue> {
    // Link name → the row that defines it (None: the base).
    let mut link_row: HashMap<&str, Option<usize>> = HashMap::new();
    link_row.insert(base.name.as_str(), None);
    for (row, j) in joints.iter().enumerate() {
        if link_row.insert(j.link.name.as_str(), Some(row)).is_some() {
            return Err(TreeIssue::DuplicateLink(row));
        }
    }
    // Children of the base (key None) and of each row's link, in row order.
    let mut children: HashMap<Option<usize>, Vec<usize>> = HashMap::new();
    let mut parent_row = Vec::with_capacity(joints.len());
    for (row, j) in joints.iter().enumerate() {
        let parent = *link_row
            .get(j.antecedent.as_str())
            .ok_or(TreeIssue::UnknownAntecedent(row))?;
        children.entry(parent).or_default().push(row);
        parent_row.push(parent);
    }
    let mut order: Vec<usize> = Vec::with_capacity(joints.len());
    let mut stack: Vec<usize> = children.get(&None).cloned().unwrap_or_default();
    stack.reverse();
    while let Some(row) = stack.pop() {
        order.push(row);
        if let Some(kids) = children.get(&Some(row)) {
            stack.extend(kids.iter().rev());
        }
    }
    if order.len() < joints.len() {
        // The rows never reached hang off a cycle.
        let mut seen = vec![false; joints.len()];
        for &r in &order {
            seen[r] = true;
        }
        let row = seen.iter().position(|s| !s).unwrap_or(0);
        return Err(TreeIssue::Cycle(row));
    }
    Ok((order, parent_row))
}

/// The frames, each on the link it names.
fn attach_frames(frames: Vec<FrameSpec>, links: &[Link]) -> Result<Vec<Frame>, TreeIssue> {
    first_duplicate(frames.iter().map(|f| f.name.as_str()))
        .map_or(Ok(()), |i| Err(TreeIssue::DuplicateFrame(i)))?;
    frames
        .into_iter()
        .enumerate()
        .map(|(row, f)| {
            let link = links
                .iter()
                .position(|l| l.name == f.link)
                .ok_or(TreeIssue::UnknownFrameLink(row))?;
            Ok(Frame {
                name: f.name,
                link,
                placement: f.placement,
            })
        })
        .collect()
}

fn first_duplicate<'a>(names: impl Iterator<Item = &'a str>) -> Option<usize> {
    let mut seen = std::collections::HashSet::new();
    names
        .enumerate()
        .find(|(_, n)| !seen.insert(*n))
        .map(|(i, _)| i)
}

impl Model {
    /// Precomputes chains and subtree masses of a tree already in topological order.
    fn assemble(
        name: String,
        links: Vec<Link>,
        joints: Vec<Joint>,
        variables: Vec<Variable>,
        frames: Vec<Frame>,
    ) -> Model {
        let nl = links.len();
        let mut subtree_mass: Vec<f64> = links.iter().map(|l| l.mass).collect();
        for i in (1..nl).rev() {
            let a = joints[i - 1].antecedent;
            subtree_mass[a] += subtree_mass[i];
        }
        let total_mass = subtree_mass[0];
        let is_moving = |i: usize| i > 0 && joints[i - 1].variable.is_some();
        let mut chain_start = vec![0usize; nl + 1];
        let mut chain: Vec<usize> = Vec::new();
        for i in 0..nl {
            if i > 0 {
                let a = joints[i - 1].antecedent;
                let (s, e) = (chain_start[a], chain_start[a + 1]);
                chain.extend_from_within(s..e);
            }
            if is_moving(i) {
                chain.push(i);
            }
            chain_start[i + 1] = chain.len();
        }
        let moving = (1..nl).filter(|&i| is_moving(i)).collect();
        Model {
            name,
            links,
            joints,
            variables,
            frames,
            total_mass,
            subtree_mass,
            chain_start,
            chain,
            moving,
        }
    }
}
