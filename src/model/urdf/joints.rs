//! A URDF's joints checked one by one, their drives resolved (fixed and locked joints, mimics of
//! mimics) and the free ones numbered as the model's variables.

use std::collections::HashMap;

use nalgebra::{IsometryMatrix3, Rotation3, Translation3, Unit, Vector3};
use urdf_rs::JointType;

use super::options::{UrdfError, UrdfOptions};
use crate::model::kinematics::rotation_about;
use crate::model::{JointKind, Variable};

/// How a URDF joint moves once mimics and locks are resolved.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Drive {
    /// Fixed joint, or locked at this joint value.
    Locked(f64),
    /// `value = multiplier · q[variable] + offset`.
    Variable {
        variable: usize,
        multiplier: f64,
        offset: f64,
    },
}

/// Every value finite and at most [`MAX_MAGNITUDE`](crate::model::MAX_MAGNITUDE) in magnitude.
pub(super) fn finite(place: impl Fn() -> String, values: &[f64]) -> Result<(), UrdfError> {
    match values
        .iter()
        .find(|v| v.is_nan() || v.abs() > crate::model::MAX_MAGNITUDE)
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

pub(super) fn pose(p: &urdf_rs::Pose) -> IsometryMatrix3<f64> {
    IsometryMatrix3::from_parts(
        Translation3::new(p.xyz[0], p.xyz[1], p.xyz[2]),
        Rotation3::from_euler_angles(p.rpy[0], p.rpy[1], p.rpy[2]),
    )
}

/// `M(u, v)`: the motion of a joint of `kind` by value `v`.
pub(super) fn motion(
    kind: JointKind,
    axis: &Unit<Vector3<f64>>,
    value: f64,
) -> IsometryMatrix3<f64> {
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
pub(super) struct Checked {
    pub(super) kind: JointKind,
    pub(super) axis: Unit<Vector3<f64>>,
    pub(super) origin: IsometryMatrix3<f64>,
}

pub(super) fn check_joint(joint: &urdf_rs::Joint) -> Result<Checked, UrdfError> {
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

/// Per joint: locked value or (for now) the index of the free URDF joint that drives it.
pub(super) fn resolve_drives(
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
pub(super) fn resolve(
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
pub(super) fn variable_order(
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
pub(super) fn joint_variable(joint: &urdf_rs::Joint) -> Result<Variable, UrdfError> {
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
pub(super) fn number_variables(
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
