//! The task stack: equality levels in priority order (each a Jacobian and a desired task velocity,
//! made of named tasks that are blocks of rows) and the summed gradient of the optimization tasks.

use faer::{Mat, MatMut, MatRef};

use super::SolverError;
use super::gradient::GradientFunction;

/// One named block of rows inside a level (e.g. `"l_hand"`, 3 rows).
#[derive(Debug, Clone, PartialEq)]
pub struct TaskSpec {
    /// Task name, unique in the stack.
    pub name: String,
    /// Number of rows (task coordinates).
    pub rows: usize,
}

/// One equality level: a name and the tasks it stacks, in row order.
#[derive(Debug, Clone, PartialEq)]
pub struct LevelSpec {
    /// Level name.
    pub name: String,
    /// The tasks of the level; their rows are stacked in this order.
    pub tasks: Vec<TaskSpec>,
}

impl LevelSpec {
    /// Total number of rows of the level.
    pub fn rows(&self) -> usize {
        self.tasks.iter().map(|t| t.rows).sum()
    }
}

/// The sizes of a stack: the number of joints `n` and the levels, highest priority first.
///
/// ```
/// use taskstack::solver::StackShape;
/// let shape = StackShape::new(23)
///     .with_level("balance", &[("com_xy", 2)])
///     .with_level("tracking", &[("l_hand", 3), ("r_hand", 3), ("l_ankle", 3)]);
/// assert_eq!(shape.level_rows().collect::<Vec<_>>(), vec![2, 9]);
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct StackShape {
    dof: usize,
    levels: Vec<LevelSpec>,
}

impl StackShape {
    /// A stack over `dof` joints with no level yet.
    pub fn new(dof: usize) -> Self {
        Self {
            dof,
            levels: Vec::new(),
        }
    }

    /// A stack whose levels are single anonymous tasks with the given row counts, named
    /// `"level 1"`, `"level 2"`, … (task names equal level names).
    pub fn from_level_rows(dof: usize, rows: &[usize]) -> Self {
        rows.iter()
            .enumerate()
            .fold(Self::new(dof), |shape, (j, &m)| {
                let name = format!("level {}", j + 1);
                shape.with_level(&name, &[(&name, m)])
            })
    }

    /// Appends a level (lower priority than every level already added) made of named tasks.
    pub fn with_level(mut self, name: &str, tasks: &[(&str, usize)]) -> Self {
        self.levels.push(LevelSpec {
            name: name.to_owned(),
            tasks: tasks
                .iter()
                .map(|&(name, rows)| TaskSpec {
                    name: name.to_owned(),
                    rows,
                })
                .collect(),
        });
        self
    }

    /// Number of joints (columns of every Jacobian).
    pub fn dof(&self) -> usize {
        self.dof
    }

    /// The levels, highest priority first.
    pub fn levels(&self) -> &[LevelSpec] {
        &self.levels
    }

    /// Row counts of the levels.
    pub fn level_rows(&self) -> impl Iterator<Item = usize> + '_ {
        self.levels.iter().map(LevelSpec::rows)
    }

    pub(crate) fn validate(&self) -> Result<(), SolverError> {
        if self.dof == 0 {
            return Err(SolverError::NoDegreesOfFreedom);
        }
        if self.levels.is_empty() {
            return Err(SolverError::EmptyStack);
        }
        if let Some((level, spec)) = self.levels.iter().enumerate().find(|(_, l)| l.rows() == 0) {
            return Err(SolverError::EmptyLevel {
                level,
                name: spec.name.clone(),
            });
        }
        Ok(())
    }
}

/// The numbers of a stack: per level the Jacobian `J_j` (`m_j × n`) and the desired task velocity
/// `ẋ_j` (`m_j`), and the combined gradient term `Σ_k κ_k ∇f_k(q)` (`n`, joint velocity units).
///
/// Storage is allocated once, at construction; filling and solving allocate nothing.
#[derive(Debug, Clone)]
pub struct TaskStack {
    shape: StackShape,
    /// First row of each level in the stacked storage, plus the total at the end.
    level_start: Vec<usize>,
    /// Stacked Jacobian, transposed (`n × total_rows`): each task row is a contiguous column.
    jacobian_t: Mat<f64>,
    target: Vec<f64>,
    gradient: Vec<f64>,
}

impl TaskStack {
    pub(crate) fn new(shape: &StackShape) -> Result<Self, SolverError> {
        shape.validate()?;
        let mut level_start = Vec::with_capacity(shape.levels.len() + 1);
        let mut total = 0;
        for rows in shape.level_rows() {
            level_start.push(total);
            total += rows;
        }
        level_start.push(total);
        Ok(Self {
            shape: shape.clone(),
            level_start,
            jacobian_t: Mat::zeros(shape.dof, total),
            target: vec![0.0; total],
            gradient: vec![0.0; shape.dof],
        })
    }

    /// The shape the stack was built with.
    pub fn shape(&self) -> &StackShape {
        &self.shape
    }

    /// Number of joints.
    pub fn dof(&self) -> usize {
        self.shape.dof
    }

    /// Number of equality levels.
    pub fn level_count(&self) -> usize {
        self.shape.levels.len()
    }

    /// Total number of rows over all levels.
    pub fn total_rows(&self) -> usize {
        self.target.len()
    }

    /// Mutable access to level `level` (0 = highest priority).
    ///
    /// # Panics
    /// If `level >= self.level_count()`; use [`TaskStack::try_level_mut`] for a checked version.
    pub fn level_mut(&mut self, level: usize) -> LevelMut<'_> {
        self.try_level_mut(level)
            .expect("level index within the stack")
    }

    /// Mutable access to level `level`, or an error naming the index.
    pub fn try_level_mut(&mut self, level: usize) -> Result<LevelMut<'_>, SolverError> {
        let levels = self.level_count();
        if level >= levels {
            return Err(SolverError::NoSuchLevel { level, levels });
        }
        let (start, end) = (self.level_start[level], self.level_start[level + 1]);
        let n = self.shape.dof;
        Ok(LevelMut {
            index: level,
            name: &self.shape.levels[level].name,
            jacobian_t: self
                .jacobian_t
                .as_mut()
                .submatrix_mut(0, start, n, end - start),
            target: &mut self.target[start..end],
        })
    }

    /// Mutable access to the rows of the task named `task`: its Jacobian block (`rows × n`) and
    /// its desired velocity block.
    pub fn task_mut(&mut self, task: &str) -> Result<(MatMut<'_, f64>, &mut [f64]), SolverError> {
        let (start, rows) = self.task_rows(task)?;
        let n = self.shape.dof;
        Ok((
            self.jacobian_t
                .as_mut()
                .submatrix_mut(0, start, n, rows)
                .transpose_mut(),
            &mut self.target[start..start + rows],
        ))
    }

    /// First stacked row and row count of the task named `task`.
    pub fn task_rows(&self, task: &str) -> Result<(usize, usize), SolverError> {
        let mut row = 0;
        for level in &self.shape.levels {
            for t in &level.tasks {
                if t.name == task {
                    return Ok((row, t.rows));
                }
                row += t.rows;
            }
        }
        Err(SolverError::NoSuchTask(task.to_owned()))
    }

    /// The Jacobian of level `level` (`m_j × n`).
    pub fn jacobian(&self, level: usize) -> MatRef<'_, f64> {
        let (start, end) = (self.level_start[level], self.level_start[level + 1]);
        self.jacobian_t
            .as_ref()
            .submatrix(0, start, self.shape.dof, end - start)
            .transpose()
    }

    /// The desired task velocity of level `level` (`m_j`).
    pub fn target(&self, level: usize) -> &[f64] {
        &self.target[self.level_start[level]..self.level_start[level + 1]]
    }

    /// The combined gradient term `Σ κ_k ∇f_k(q)` (length `n`, joint velocity units, e.g. rad/s).
    pub fn gradient(&self) -> &[f64] {
        &self.gradient
    }

    /// Mutable access to the combined gradient term, for users who compute it themselves.
    pub fn gradient_mut(&mut self) -> &mut [f64] {
        &mut self.gradient
    }

    /// Sets the combined gradient term to zero (no optimization task).
    pub fn clear_gradient(&mut self) {
        self.gradient.fill(0.0);
    }

    /// Adds `κ ∇f(q)` of an optimization task (eq. 3) to the combined gradient term. A negative
    /// `kappa` descends `f` (the paper: κ = −0.10 for joint limits, −0.02 for joint tracking).
    pub fn add_gradient(
        &mut self,
        kappa: f64,
        task: &impl GradientFunction,
        q: &[f64],
    ) -> Result<(), SolverError> {
        if !kappa.is_finite() {
            return Err(SolverError::NonFinite {
                what: "gradient gain κ".into(),
                value: kappa,
            });
        }
        check_len("q", self.shape.dof, q.len())?;
        task.add_scaled_gradient(q, kappa, &mut self.gradient)
    }

    pub(crate) fn level_start(&self, level: usize) -> usize {
        self.level_start[level]
    }

    /// Task row `row` of the stacked Jacobian (length `n`).
    pub(crate) fn row(&self, row: usize) -> &[f64] {
        self.jacobian_t.col_as_slice(row)
    }

    pub(crate) fn stacked_target(&self) -> &[f64] {
        &self.target
    }

    /// Finds the first non-finite number, naming its place.
    pub(crate) fn check_finite(&self) -> Result<(), SolverError> {
        for (j, level) in self.shape.levels.iter().enumerate() {
            for row in self.level_start[j]..self.level_start[j + 1] {
                let local = row - self.level_start[j];
                if let Some((col, &v)) = self
                    .row(row)
                    .iter()
                    .enumerate()
                    .find(|(_, v)| !v.is_finite())
                {
                    return Err(SolverError::NonFinite {
                        what: format!(
                            "Jacobian of level {j} ({:?}) at row {local}, column {col}",
                            level.name
                        ),
                        value: v,
                    });
                }
                let v = self.target[row];
                if !v.is_finite() {
                    return Err(SolverError::NonFinite {
                        what: format!(
                            "desired velocity of level {j} ({:?}) at row {local}",
                            level.name
                        ),
                        value: v,
                    });
                }
            }
        }
        check_finite_slice("gradient term", &self.gradient)
    }
}

/// Mutable view of one level: its Jacobian and desired task velocity.
#[derive(Debug)]
pub struct LevelMut<'a> {
    index: usize,
    name: &'a str,
    jacobian_t: MatMut<'a, f64>,
    target: &'a mut [f64],
}

impl LevelMut<'_> {
    /// Number of rows `m_j`.
    pub fn rows(&self) -> usize {
        self.target.len()
    }

    /// The level's Jacobian `J_j` as an `m_j × n` view, to be written in place (task units per
    /// joint unit, e.g. m/rad).
    pub fn jacobian_mut(&mut self) -> MatMut<'_, f64> {
        self.jacobian_t.as_mut().transpose_mut()
    }

    /// The desired task velocity `ẋ_j` (task units per second, e.g. m/s).
    pub fn target_mut(&mut self) -> &mut [f64] {
        self.target
    }

    /// Rows `first..first + rows` of the Jacobian (an `rows × n` view) and of the desired
    /// velocity, together: one task's block, written in place.
    ///
    /// # Panics
    /// If `first + rows` exceeds [`LevelMut::rows`].
    pub fn rows_mut(&mut self, first: usize, rows: usize) -> (MatMut<'_, f64>, &mut [f64]) {
        (
            self.jacobian_t
                .as_mut()
                .transpose_mut()
                .subrows_mut(first, rows),
            &mut self.target[first..first + rows],
        )
    }

    /// Sets row `row`: its Jacobian entries (`n` values) and its desired velocity.
    pub fn set_row(
        &mut self,
        row: usize,
        jacobian: &[f64],
        velocity: f64,
    ) -> Result<(), SolverError> {
        if row >= self.rows() {
            return Err(SolverError::NoSuchRow {
                level: self.index,
                name: self.name.to_owned(),
                row,
                rows: self.rows(),
            });
        }
        let n = self.jacobian_t.nrows();
        if jacobian.len() != n {
            return Err(SolverError::DimensionMismatch {
                what: format!(
                    "Jacobian row {row} of level {} ({:?})",
                    self.index, self.name
                ),
                expected: n,
                got: jacobian.len(),
            });
        }
        for (i, &v) in jacobian.iter().enumerate() {
            self.jacobian_t[(i, row)] = v;
        }
        self.target[row] = velocity;
        Ok(())
    }
}

pub(crate) fn check_len(what: &str, expected: usize, got: usize) -> Result<(), SolverError> {
    if expected == got {
        Ok(())
    } else {
        Err(SolverError::DimensionMismatch {
            what: what.to_owned(),
            expected,
            got,
        })
    }
}

pub(crate) fn check_finite_slice(what: &str, values: &[f64]) -> Result<(), SolverError> {
    match values.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        None => Ok(()),
        Some((i, &value)) => Err(SolverError::NonFinite {
            what: format!("{what} at index {i}"),
            value,
        }),
    }
}
