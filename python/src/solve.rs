//! The prioritized solver from Python: `Task` (what to reach) and `TaskSet` (levels of tasks
//! on a `Model`, solved from a starting posture by the position-level driver).

use numpy::{PyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use taskstack::model::Model;
use taskstack::nalgebra::{Matrix3, Translation3};
use taskstack::solver::Solver;
use taskstack::solver::driver::{DriverSettings, PositionDriver, StopReason};
use taskstack::tasks::{
    ComTask, OrientationTask, PoseTask, PositionTask, PostureTask, Task, TaskSet, joint_bounds,
};
use taskstack::{IsometryMatrix3, Rotation3};

use crate::errors::{to_py, value_error};
use crate::kinematics::PyModel;

/// One task, by value: built against a model when its set is solved.
#[derive(Debug, Clone)]
enum Spec {
    Position {
        frame: String,
        target: [f64; 3],
    },
    Orientation {
        frame: String,
        rotation: Rotation3<f64>,
    },
    Pose {
        frame: String,
        placement: IsometryMatrix3<f64>,
    },
    Com {
        target: [f64; 3],
    },
    ComGround {
        xy: [f64; 2],
    },
    Posture {
        joints: Vec<String>,
        target: Vec<f64>,
    },
}

impl Spec {
    fn build(&self, model: &Model) -> PyResult<Box<dyn Task>> {
        Ok(match self {
            Spec::Position { frame, target } => {
                Box::new(PositionTask::new(model, frame, (*target).into()).map_err(to_py)?)
            }
            Spec::Orientation { frame, rotation } => {
                Box::new(OrientationTask::new(model, frame, *rotation).map_err(to_py)?)
            }
            Spec::Pose { frame, placement } => {
                Box::new(PoseTask::new(model, frame, *placement).map_err(to_py)?)
            }
            Spec::Com { target } => Box::new(ComTask::new(model, (*target).into()).map_err(to_py)?),
            Spec::ComGround { xy } => Box::new(ComTask::ground(model, *xy).map_err(to_py)?),
            Spec::Posture { joints, target } => {
                let names: Vec<&str> = joints.iter().map(String::as_str).collect();
                Box::new(PostureTask::new(model, &names, target).map_err(to_py)?)
            }
        })
    }
}

/// A rotation from a 3 × 3 array.
fn rotation(array: &PyReadonlyArray2<'_, f64>) -> PyResult<Rotation3<f64>> {
    let a = array.as_array();
    if a.shape() != [3, 3] {
        return Err(value_error(format!(
            "rotation of shape {:?}: expected (3, 3)",
            a.shape()
        )));
    }
    checked_rotation(Matrix3::from_fn(|r, c| a[(r, c)]))
}

/// `m` if it is a rotation (orthonormal, determinant +1, to 1e-6).
fn checked_rotation(m: Matrix3<f64>) -> PyResult<Rotation3<f64>> {
    let orthonormal = (m.transpose() * m - Matrix3::identity()).abs().max() < 1e-6;
    if !(orthonormal && (m.determinant() - 1.0).abs() < 1e-6) {
        return Err(value_error(
            "rotation: not a rotation matrix (orthonormal, determinant 1)",
        ));
    }
    Ok(Rotation3::from_matrix_unchecked(m))
}

/// A task to add to a `TaskSet` level.
#[pyclass(name = "Task", module = "taskstack._taskstack", frozen)]
#[derive(Debug, Clone)]
pub(crate) struct PyTask(Spec);

#[pymethods]
impl PyTask {
    /// The origin of `frame` at `target` (base frame, m).
    #[staticmethod]
    fn position(frame: String, target: [f64; 3]) -> Self {
        Self(Spec::Position { frame, target })
    }

    /// `frame`'s axes at `rotation` (3 x 3 rotation matrix, base frame).
    #[staticmethod]
    fn orientation(frame: String, rotation: PyReadonlyArray2<'_, f64>) -> PyResult<Self> {
        Ok(Self(Spec::Orientation {
            frame,
            rotation: self::rotation(&rotation)?,
        }))
    }

    /// `frame` at `placement` (4 x 4 homogeneous matrix, base frame, m).
    #[staticmethod]
    fn pose(frame: String, placement: PyReadonlyArray2<'_, f64>) -> PyResult<Self> {
        let a = placement.as_array();
        if a.shape() != [4, 4] {
            return Err(value_error(format!(
                "placement of shape {:?}: expected (4, 4)",
                a.shape()
            )));
        }
        let rotation = checked_rotation(Matrix3::from_fn(|i, j| a[(i, j)]))?;
        let translation = Translation3::new(a[(0, 3)], a[(1, 3)], a[(2, 3)]);
        Ok(Self(Spec::Pose {
            frame,
            placement: IsometryMatrix3::from_parts(translation, rotation),
        }))
    }

    /// The centre of mass at `target` (base frame, m).
    #[staticmethod]
    fn com(target: [f64; 3]) -> Self {
        Self(Spec::Com { target })
    }

    /// The centre of mass's ground projection at `xy` (base frame x, y, m); its height free.
    #[staticmethod]
    fn com_ground(xy: [f64; 2]) -> Self {
        Self(Spec::ComGround { xy })
    }

    /// The joints `joints` at the angles `target` (rad).
    #[staticmethod]
    fn posture(joints: Vec<String>, target: Vec<f64>) -> PyResult<Self> {
        if joints.len() != target.len() {
            return Err(value_error(format!(
                "posture: {} joints and {} angles",
                joints.len(),
                target.len()
            )));
        }
        Ok(Self(Spec::Posture { joints, target }))
    }

    fn __repr__(&self) -> String {
        format!("Task({:?})", self.0)
    }
}

/// Levels of tasks on one model, highest priority first.
#[pyclass(name = "TaskSet", module = "taskstack._taskstack")]
pub(crate) struct PyTaskSet {
    model: Model,
    levels: Vec<(String, Vec<Spec>)>,
}

#[pymethods]
impl PyTaskSet {
    #[new]
    fn new(model: PyRef<'_, PyModel>) -> Self {
        Self {
            model: model.model.clone(),
            levels: Vec::new(),
        }
    }

    /// Adds a level below the existing ones (`name` names it in reports). Returns the set.
    fn level<'py>(
        mut slf: PyRefMut<'py, Self>,
        name: String,
        tasks: Vec<PyRef<'py, PyTask>>,
    ) -> PyResult<PyRefMut<'py, Self>> {
        if tasks.is_empty() {
            return Err(value_error(format!("level {name:?}: no task")));
        }
        // Built once here so that a bad frame or joint name fails now, naming the task.
        for task in &tasks {
            task.0.build(&slf.model)?;
        }
        slf.levels
            .push((name, tasks.iter().map(|t| t.0.clone()).collect()));
        Ok(slf)
    }

    /// Solves from `q` (rad): Gauss–Newton iterations of the prioritized velocity solve within
    /// the joint limits, until every task is within `tolerance` or `max_iterations`.
    #[pyo3(signature = (q, tolerance = 1e-4, max_iterations = 50))]
    fn solve<'py>(
        &self,
        py: Python<'py>,
        q: Vec<f64>,
        tolerance: f64,
        max_iterations: usize,
    ) -> PyResult<Bound<'py, PyDict>> {
        if self.levels.is_empty() {
            return Err(value_error("the task set has no level"));
        }
        if q.len() != self.model.nv() || !q.iter().all(|v| v.is_finite()) {
            return Err(value_error(format!(
                "q: expected {} finite angles, got {} values",
                self.model.nv(),
                q.len()
            )));
        }
        let mut set = TaskSet::new(&self.model);
        for (name, specs) in &self.levels {
            let tasks = specs
                .iter()
                .map(|s| s.build(&self.model))
                .collect::<PyResult<Vec<_>>>()?;
            set = set.level(name, tasks);
        }
        let mut solver = Solver::new(&set.shape()).map_err(to_py)?;
        let settings = DriverSettings {
            tolerance,
            max_iterations,
            ..DriverSettings::default()
        };
        let mut driver = PositionDriver::new(&solver, settings).map_err(to_py)?;
        let bounds = joint_bounds(&self.model).map_err(to_py)?;
        let mut q = q;
        let report = driver
            .run(&mut solver, &mut set, &mut q, &bounds)
            .map_err(to_py)?;
        let out = PyDict::new(py);
        out.set_item("q", PyArray1::from_vec(py, q))?;
        out.set_item("task_errors", report.task_errors().to_vec())?;
        out.set_item("iterations", report.iterations)?;
        let stop = match report.stop {
            StopReason::Converged => "converged",
            StopReason::Stalled => "stalled",
            StopReason::IterationLimit => "iteration_limit",
        };
        out.set_item("stop", stop)?;
        Ok(out)
    }
}
