//! Joints at a reference posture.

use std::any::Any;

use faer::MatMut;

use super::{Task, TaskError, finite_target};
use crate::model::{Model, ModelData, ModelError};

/// Chosen joints at reference values (rad or m): one row per joint, `J` its unit row,
/// `e = q* − q`. As a strict level it fixes those joints; for a soft pull toward a posture in the
/// null space of everything else, use [`TaskSet::posture_gradient`](super::TaskSet::posture_gradient).
/// Named `"posture"`.
#[derive(Debug, Clone, PartialEq)]
pub struct PostureTask {
    joints: Vec<usize>,
    /// Reference value of each joint, in the order given to [`PostureTask::new`] (rad or m).
    pub target: Vec<f64>,
}

impl PostureTask {
    /// The named joints (model variable names) at `target`.
    ///
    /// # Errors
    /// [`TaskError::Model`] for an unknown variable, [`TaskError::NonFiniteTarget`],
    /// [`TaskError::WrongLength`] when `target` and `joints` differ in length.
    pub fn new(model: &Model, joints: &[&str], target: &[f64]) -> Result<Self, TaskError> {
        finite_target("posture", target)?;
        if joints.len() != target.len() {
            return Err(TaskError::WrongLength {
                task: "posture".to_owned(),
                expected: joints.len(),
                got: target.len(),
            });
        }
        let joints = joints
            .iter()
            .map(|j| model.variable_index(j))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Self {
            joints,
            target: target.to_vec(),
        })
    }
}

impl Task for PostureTask {
    fn name(&self) -> &str {
        "posture"
    }

    fn rows(&self) -> usize {
        self.joints.len()
    }

    fn write(
        &self,
        _model: &Model,
        _data: &ModelData,
        q: &[f64],
        mut jacobian: MatMut<'_, f64>,
        error: &mut [f64],
    ) -> Result<(), ModelError> {
        jacobian.fill(0.0);
        for (r, (&k, &target)) in self.joints.iter().zip(&self.target).enumerate() {
            jacobian[(r, k)] = 1.0;
            error[r] = target - q[k];
        }
        Ok(())
    }

    fn as_any_mut(&mut self) -> &mut dyn Any {
        self
    }
}
