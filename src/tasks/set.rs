//! A hierarchy of ready-made tasks, evaluated for the solver.

use crate::model::{Model, ModelData};
use crate::solver::driver::TaskModel;
use crate::solver::{JointTracking, StackShape, TaskStack};

use super::{InequalityTask, Task, TaskError, finite_target};

/// One level of a [`TaskSet`]: its name, equality tasks and inequality tasks.
#[derive(Debug)]
struct Level {
    name: String,
    tasks: Vec<Box<dyn Task>>,
    inequalities: Vec<Box<dyn InequalityTask>>,
}

/// Tasks in strict priority levels (first level highest) on one model, plus an optional posture
/// gradient in the null space of all of them; a [`TaskModel`] for the
/// [`PositionDriver`](crate::solver::driver::PositionDriver). Holds its own [`ModelData`]:
/// evaluating does not allocate.
#[derive(Debug)]
pub struct TaskSet<'m> {
    model: &'m Model,
    data: ModelData,
    levels: Vec<Level>,
    posture: Option<(f64, JointTracking)>,
}

impl<'m> TaskSet<'m> {
    /// No tasks yet, on `model`.
    pub fn new(model: &'m Model) -> Self {
        Self {
            model,
            data: model.new_data(),
            levels: Vec::new(),
            posture: None,
        }
    }

    /// Adds a level of equality tasks below the existing ones.
    pub fn level(self, name: &str, tasks: Vec<Box<dyn Task>>) -> Self {
        self.mixed_level(name, tasks, Vec::new())
    }

    /// Adds a level of inequality tasks below the existing ones.
    pub fn inequality_level(self, name: &str, tasks: Vec<Box<dyn InequalityTask>>) -> Self {
        self.mixed_level(name, Vec::new(), tasks)
    }

    /// Adds a level with both kinds of task, solved together at this priority.
    pub fn mixed_level(
        mut self,
        name: &str,
        tasks: Vec<Box<dyn Task>>,
        inequalities: Vec<Box<dyn InequalityTask>>,
    ) -> Self {
        self.levels.push(Level {
            name: name.to_owned(),
            tasks,
            inequalities,
        });
        self
    }

    /// Pulls every joint toward `reference` (rad or m, model variable order) with gain `kappa`
    /// (1/iteration, e.g. 0.1: a tenth of the way per step) in the null space of every level.
    ///
    /// # Errors
    /// [`TaskError::WrongLength`], [`TaskError::NonFiniteTarget`].
    pub fn posture_gradient(mut self, kappa: f64, reference: &[f64]) -> Result<Self, TaskError> {
        finite_target("posture gradient", &[kappa])?;
        finite_target("posture gradient", reference)?;
        if reference.len() != self.model.nv() {
            return Err(TaskError::WrongLength {
                task: "posture gradient".to_owned(),
                expected: self.model.nv(),
                got: reference.len(),
            });
        }
        // The stack's gradient term is added to q̇ as `κ ∇f`; JointTracking's gradient points
        // away from the reference, so a pull is a negative κ.
        self.posture = Some((-kappa, JointTracking::new(reference)?));
        Ok(self)
    }

    /// The solver shape: one level per [`TaskSet::level`], one named task per task.
    pub fn shape(&self) -> StackShape {
        self.levels
            .iter()
            .fold(StackShape::new(self.model.nv()), |shape, level| {
                let specs: Vec<(&str, usize)> =
                    level.tasks.iter().map(|t| (t.name(), t.rows())).collect();
                let inequalities: Vec<(&str, usize)> = level
                    .inequalities
                    .iter()
                    .map(|t| (t.name(), t.rows()))
                    .collect();
                shape.with_mixed_level(&level.name, &specs, &inequalities)
            })
    }

    /// The task named `name` as its concrete type, to change its target between solves.
    ///
    /// # Errors
    /// [`TaskError::UnknownTask`] when no task has that name and type.
    pub fn task_mut<T: Task>(&mut self, name: &str) -> Result<&mut T, TaskError> {
        self.levels
            .iter_mut()
            .flat_map(|level| level.tasks.iter_mut())
            .filter(|t| t.name() == name)
            .find_map(|t| t.as_any_mut().downcast_mut::<T>())
            .ok_or_else(|| TaskError::UnknownTask(name.to_owned()))
    }

    /// The inequality task named `name` as its concrete type (e.g. to move a support polygon).
    ///
    /// # Errors
    /// [`TaskError::UnknownTask`] when no inequality task has that name and type.
    pub fn inequality_mut<T: InequalityTask>(&mut self, name: &str) -> Result<&mut T, TaskError> {
        self.levels
            .iter_mut()
            .flat_map(|level| level.inequalities.iter_mut())
            .filter(|t| t.name() == name)
            .find_map(|t| t.as_any_mut().downcast_mut::<T>())
            .ok_or_else(|| TaskError::UnknownTask(name.to_owned()))
    }

    /// The model data of the last evaluation (forward kinematics at the last `q` evaluated).
    pub fn data(&self) -> &ModelData {
        &self.data
    }
}

impl TaskModel for TaskSet<'_> {
    type Error = TaskError;

    fn evaluate(&mut self, q: &[f64], stack: &mut TaskStack) -> Result<(), TaskError> {
        self.model.forward_kinematics(&mut self.data, q)?;
        for (l, spec) in self.levels.iter().enumerate() {
            let mut level = stack.try_level_mut(l)?;
            let rows: usize = spec.tasks.iter().map(|t| t.rows()).sum();
            let inequality_rows: usize = spec.inequalities.iter().map(|t| t.rows()).sum();
            if level.rows() != rows || level.inequality_rows() != inequality_rows {
                return Err(TaskError::WrongLength {
                    task: format!("rows of level {l}"),
                    expected: rows + inequality_rows,
                    got: level.rows() + level.inequality_rows(),
                });
            }
            let mut row = 0;
            for task in &spec.tasks {
                let rows = task.rows();
                let (jacobian, target) = level.rows_mut(row, rows);
                task.write(self.model, &self.data, q, jacobian, target)?;
                row += rows;
            }
            let (mut jacobian, lower, upper) = level.inequalities_mut();
            let mut row = 0;
            for task in &spec.inequalities {
                let rows = task.rows();
                task.write(
                    self.model,
                    &self.data,
                    jacobian.as_mut().subrows_mut(row, rows),
                    &mut lower[row..row + rows],
                    &mut upper[row..row + rows],
                )?;
                row += rows;
            }
        }
        stack.clear_gradient();
        if let Some((kappa, posture)) = &self.posture {
            stack.add_gradient(*kappa, posture, q)?;
        }
        Ok(())
    }
}
