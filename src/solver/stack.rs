//! The task stack: levels in priority order, each made of named tasks that are blocks of rows, and
//! the summed gradient of the optimization tasks.
//!
//! A level has **equality rows** `J q̇ = ẋ` (a Jacobian and a desired task velocity) and
//! **inequality rows** `l ≤ J q̇ ≤ u` (a Jacobian and two bounds, either of which may be infinite).
//! Both are solved at the level's priority: see [`Solver`](super::Solver).

use faer::{Mat, MatMut, MatRef};

use super::SolverError;
use super::check::{all_finite, check_finite_slice, check_len};
use super::gradient::GradientFunction;

/// Inequality rows written in place: the Jacobian block (`rows × n`), the lower bounds and the
/// upper bounds (task velocity units; `−∞`/`+∞` for no bound).
pub type InequalityRowsMut<'a> = (MatMut<'a, f64>, &'a mut [f64], &'a mut [f64]);

/// One named block of rows inside a level (e.g. `"l_hand"`, 3 rows).
#[derive(Debug, Clone, PartialEq)]
pub struct TaskSpec {
    /// Task name, unique in the stack.
    pub name: String,
    /// Number of rows (task coordinates).
    pub rows: usize,
}

/// One level: a name, its equality tasks and its inequality tasks, each in row order.
#[derive(Debug, Clone, PartialEq)]
pub struct LevelSpec {
    /// Level name.
    pub name: String,
    /// The equality tasks of the level (`J q̇ = ẋ`); their rows are stacked in this order.
    pub tasks: Vec<TaskSpec>,
    /// The inequality tasks of the level (`l ≤ J q̇ ≤ u`), stacked in this order.
    pub inequalities: Vec<TaskSpec>,
}

impl LevelSpec {
    /// Number of equality rows of the level.
    pub fn rows(&self) -> usize {
        self.tasks.iter().map(|t| t.rows).sum()
    }

    /// Number of inequality rows of the level.
    pub fn inequality_rows(&self) -> usize {
        self.inequalities.iter().map(|t| t.rows).sum()
    }
}

fn task_specs(tasks: &[(&str, usize)]) -> Vec<TaskSpec> {
    tasks
        .iter()
        .map(|&(name, rows)| TaskSpec {
            name: name.to_owned(),
            rows,
        })
        .collect()
}

/// The sizes of a stack: the number of joints `n` and the levels, highest priority first.
///
/// ```
/// use taskstack::solver::StackShape;
/// let shape = StackShape::new(23)
///     .with_inequality_level("balance", &[("com_in_polygon", 4)])
///     .with_level("tracking", &[("l_hand", 3), ("r_hand", 3), ("l_ankle", 3)])
///     .with_mixed_level("posture", &[("torso", 3)], &[("hands_apart", 1)]);
/// assert_eq!(shape.level_rows().collect::<Vec<_>>(), vec![0, 9, 3]);
/// assert_eq!(shape.level_inequality_rows().collect::<Vec<_>>(), vec![4, 0, 1]);
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

    /// Appends a level (lower priority than every level already added) made of named equality
    /// tasks.
    pub fn with_level(self, name: &str, tasks: &[(&str, usize)]) -> Self {
        self.with_mixed_level(name, tasks, &[])
    }

    /// Appends a level made of named inequality tasks (`l ≤ J q̇ ≤ u` rows).
    pub fn with_inequality_level(self, name: &str, tasks: &[(&str, usize)]) -> Self {
        self.with_mixed_level(name, &[], tasks)
    }

    /// Appends a level with both equality and inequality tasks, solved together at this
    /// priority: the level's equality residual and inequality violations are minimized in one
    /// least-squares sense.
    pub fn with_mixed_level(
        mut self,
        name: &str,
        equalities: &[(&str, usize)],
        inequalities: &[(&str, usize)],
    ) -> Self {
        self.levels.push(LevelSpec {
            name: name.to_owned(),
            tasks: task_specs(equalities),
            inequalities: task_specs(inequalities),
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

    /// Equality row counts of the levels.
    pub fn level_rows(&self) -> impl Iterator<Item = usize> + '_ {
        self.levels.iter().map(LevelSpec::rows)
    }

    /// Inequality row counts of the levels.
    pub fn level_inequality_rows(&self) -> impl Iterator<Item = usize> + '_ {
        self.levels.iter().map(LevelSpec::inequality_rows)
    }

    /// Whether any level has inequality rows.
    pub fn has_inequalities(&self) -> bool {
        self.levels.iter().any(|l| l.inequality_rows() > 0)
    }

    pub(crate) fn validate(&self) -> Result<(), SolverError> {
        if self.dof == 0 {
            return Err(SolverError::NoDegreesOfFreedom);
        }
        if self.levels.is_empty() {
            return Err(SolverError::EmptyStack);
        }
        if let Some((level, spec)) = self
            .levels
            .iter()
            .enumerate()
            .find(|(_, l)| l.rows() + l.inequality_rows() == 0)
        {
            return Err(SolverError::EmptyLevel {
                level,
                name: spec.name.clone(),
            });
        }
        Ok(())
    }
}

/// The numbers of a stack: per level the equality Jacobian `J_j` (`m_j × n`) and desired task
/// velocity `ẋ_j` (`m_j`), the inequality Jacobian `C_j` (`p_j × n`) and bounds `l_j ≤ C_j q̇ ≤ u_j`
/// (`p_j` each, task velocity units; `−∞`/`+∞` for a side without bound, the default), and the
/// combined gradient term `Σ_k κ_k ∇f_k(q)` (`n`, joint velocity units).
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
    /// The same for the inequality rows.
    inequality_start: Vec<usize>,
    inequality_jacobian_t: Mat<f64>,
    lower: Vec<f64>,
    upper: Vec<f64>,
    gradient: Vec<f64>,
    damping_reference: Vec<f64>,
}

/// `[0, c₀, c₀ + c₁, …]`: the first index of each block of `counts` rows, and the total.
pub(crate) fn prefix_sums(counts: impl Iterator<Item = usize>) -> Vec<usize> {
    let mut starts = vec![0];
    for c in counts {
        starts.push(starts.last().copied().unwrap_or(0) + c);
    }
    starts
}

impl TaskStack {
    pub(crate) fn new(shape: &StackShape) -> Result<Self, SolverError> {
        shape.validate()?;
        let level_start = prefix_sums(shape.level_rows());
        let inequality_start = prefix_sums(shape.level_inequality_rows());
        let total = level_start[level_start.len() - 1];
        let inequalities = inequality_start[inequality_start.len() - 1];
        Ok(Self {
            shape: shape.clone(),
            level_start,
            jacobian_t: Mat::zeros(shape.dof, total),
            target: vec![0.0; total],
            inequality_start,
            inequality_jacobian_t: Mat::zeros(shape.dof, inequalities),
            lower: vec![f64::NEG_INFINITY; inequalities],
            upper: vec![f64::INFINITY; inequalities],
            gradient: vec![0.0; shape.dof],
            damping_reference: vec![0.0; shape.dof],
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

    /// Total number of equality rows over all levels.
    pub fn total_rows(&self) -> usize {
        self.target.len()
    }

    /// Total number of inequality rows over all levels.
    pub fn total_inequality_rows(&self) -> usize {
        self.lower.len()
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
        let (first, last) = (
            self.inequality_start[level],
            self.inequality_start[level + 1],
        );
        let n = self.shape.dof;
        Ok(LevelMut {
            index: level,
            name: &self.shape.levels[level].name,
            jacobian_t: self
                .jacobian_t
                .as_mut()
                .submatrix_mut(0, start, n, end - start),
            target: &mut self.target[start..end],
            inequality_jacobian_t: self.inequality_jacobian_t.as_mut().submatrix_mut(
                0,
                first,
                n,
                last - first,
            ),
            lower: &mut self.lower[first..last],
            upper: &mut self.upper[first..last],
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

    /// Mutable access to the rows of the inequality task named `task`: its Jacobian block
    /// (`rows × n`), its lower bounds and its upper bounds (task velocity units; `−∞` and `+∞`
    /// mean no bound).
    pub fn inequality_task_mut(
        &mut self,
        task: &str,
    ) -> Result<InequalityRowsMut<'_>, SolverError> {
        let (start, rows) = self.inequality_task_rows(task)?;
        let n = self.shape.dof;
        Ok((
            self.inequality_jacobian_t
                .as_mut()
                .submatrix_mut(0, start, n, rows)
                .transpose_mut(),
            &mut self.lower[start..start + rows],
            &mut self.upper[start..start + rows],
        ))
    }

    /// First stacked row and row count of the equality task named `task`.
    pub fn task_rows(&self, task: &str) -> Result<(usize, usize), SolverError> {
        find_task(self.shape.levels.iter().map(|l| &l.tasks), task)
    }

    /// First stacked inequality row and row count of the inequality task named `task`.
    pub fn inequality_task_rows(&self, task: &str) -> Result<(usize, usize), SolverError> {
        find_task(self.shape.levels.iter().map(|l| &l.inequalities), task)
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

    /// The inequality Jacobian of level `level` (`p_j × n`).
    pub fn inequality_jacobian(&self, level: usize) -> MatRef<'_, f64> {
        let (start, end) = (
            self.inequality_start[level],
            self.inequality_start[level + 1],
        );
        self.inequality_jacobian_t
            .as_ref()
            .submatrix(0, start, self.shape.dof, end - start)
            .transpose()
    }

    /// The lower and upper bounds of level `level`'s inequality rows (`p_j` each).
    pub fn bounds(&self, level: usize) -> (&[f64], &[f64]) {
        let range = self.inequality_start[level]..self.inequality_start[level + 1];
        (&self.lower[range.clone()], &self.upper[range])
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

    /// The velocity a damped level is damped toward (length `n`, joint velocity units; zero
    /// by default): see [`Settings::max_damping`](super::Settings::max_damping).
    pub fn damping_reference(&self) -> &[f64] {
        &self.damping_reference
    }

    /// Mutable access to the damping reference, e.g. a share of the previous solve's
    /// velocity: a damped (near-singular) level then keeps moving as it did in its poorly
    /// conditioned directions instead of being pulled toward rest, which can turn a level's
    /// frame-to-frame reversals into smooth motion without slowing its well-conditioned
    /// directions. Nothing brakes those directions but the damping itself, so a reference of
    /// the whole last velocity can drift (the imitation keeps a share of it). The weighted DLS
    /// method ignores it (it damps toward the gradient term).
    pub fn damping_reference_mut(&mut self) -> &mut [f64] {
        &mut self.damping_reference
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

    pub(crate) fn inequality_start(&self, level: usize) -> usize {
        self.inequality_start[level]
    }

    /// Inequality row `row` of the stacked inequality Jacobian (length `n`).
    pub(crate) fn inequality_row(&self, row: usize) -> &[f64] {
        self.inequality_jacobian_t.col_as_slice(row)
    }

    /// Bounds `(l, u)` of stacked inequality row `row`.
    pub(crate) fn inequality_bounds(&self, row: usize) -> (f64, f64) {
        (self.lower[row], self.upper[row])
    }

    pub(crate) fn stacked_target(&self) -> &[f64] {
        &self.target
    }

    /// Checks that every number of the stack is finite and every inequality row's bounds are
    /// valid; an error names the first offending place. A solve calls this every time, so the
    /// common case (all finite) is one quick pass, and only a failure is searched row by row.
    pub(crate) fn check_finite(&self) -> Result<(), SolverError> {
        let columns_finite = |m: &Mat<f64>| (0..m.ncols()).all(|c| all_finite(m.col_as_slice(c)));
        if columns_finite(&self.jacobian_t)
            && all_finite(&self.target)
            && columns_finite(&self.inequality_jacobian_t)
            && all_finite(&self.gradient)
            && all_finite(&self.damping_reference)
        {
            return self.check_inequality_bounds();
        }
        self.find_non_finite()
    }

    /// Finds the first non-finite number, naming its place.
    fn find_non_finite(&self) -> Result<(), SolverError> {
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
        self.check_inequalities()?;
        check_finite_slice("gradient term", &self.gradient)?;
        check_finite_slice("damping reference", &self.damping_reference)
    }

    /// Finite inequality Jacobians, then [`TaskStack::check_inequality_bounds`].
    fn check_inequalities(&self) -> Result<(), SolverError> {
        for (j, level) in self.shape.levels.iter().enumerate() {
            for row in self.inequality_start[j]..self.inequality_start[j + 1] {
                let local = row - self.inequality_start[j];
                if let Some((col, &v)) = self
                    .inequality_row(row)
                    .iter()
                    .enumerate()
                    .find(|(_, v)| !v.is_finite())
                {
                    return Err(SolverError::NonFinite {
                        what: format!(
                            "inequality Jacobian of level {j} ({:?}) at row {local}, column {col}",
                            level.name
                        ),
                        value: v,
                    });
                }
            }
        }
        self.check_inequality_bounds()
    }

    /// Inequality bounds not NaN, `l ≤ u`, `l < +∞` and `u > −∞`.
    fn check_inequality_bounds(&self) -> Result<(), SolverError> {
        for (j, level) in self.shape.levels.iter().enumerate() {
            for row in self.inequality_start[j]..self.inequality_start[j + 1] {
                let local = row - self.inequality_start[j];
                let (lower, upper) = (self.lower[row], self.upper[row]);
                if lower.is_nan() || upper.is_nan() {
                    return Err(SolverError::NonFinite {
                        what: format!(
                            "inequality bounds of level {j} ({:?}) at row {local}",
                            level.name
                        ),
                        value: f64::NAN,
                    });
                }
                if lower > upper || lower == f64::INFINITY || upper == f64::NEG_INFINITY {
                    return Err(SolverError::InvertedBounds {
                        level: j,
                        name: level.name.clone(),
                        row: local,
                        lower,
                        upper,
                    });
                }
            }
        }
        Ok(())
    }
}

fn find_task<'a>(
    levels: impl Iterator<Item = &'a Vec<TaskSpec>>,
    task: &str,
) -> Result<(usize, usize), SolverError> {
    let mut row = 0;
    for tasks in levels {
        for t in tasks {
            if t.name == task {
                return Ok((row, t.rows));
            }
            row += t.rows;
        }
    }
    Err(SolverError::NoSuchTask(task.to_owned()))
}

/// Mutable view of one level: its equality Jacobian and desired task velocity, its inequality
/// Jacobian and bounds.
#[derive(Debug)]
pub struct LevelMut<'a> {
    index: usize,
    name: &'a str,
    jacobian_t: MatMut<'a, f64>,
    target: &'a mut [f64],
    inequality_jacobian_t: MatMut<'a, f64>,
    lower: &'a mut [f64],
    upper: &'a mut [f64],
}

impl LevelMut<'_> {
    /// Number of equality rows `m_j`.
    pub fn rows(&self) -> usize {
        self.target.len()
    }

    /// Number of inequality rows `p_j`.
    pub fn inequality_rows(&self) -> usize {
        self.lower.len()
    }

    /// The level's inequality Jacobian `C_j` as a `p_j × n` view, and its lower and upper bounds
    /// (task velocity units, e.g. m/s; `−∞`/`+∞` for no bound), to be written in place.
    pub fn inequalities_mut(&mut self) -> InequalityRowsMut<'_> {
        (
            self.inequality_jacobian_t.as_mut().transpose_mut(),
            self.lower,
            self.upper,
        )
    }

    /// Sets inequality row `row`: its Jacobian entries (`n` values) and its bounds
    /// `lower ≤ c q̇ ≤ upper` (checked by the next solve: `lower ≤ upper`, no NaN).
    pub fn set_inequality_row(
        &mut self,
        row: usize,
        jacobian: &[f64],
        lower: f64,
        upper: f64,
    ) -> Result<(), SolverError> {
        self.check_row(row, self.inequality_rows(), jacobian.len())?;
        for (i, &v) in jacobian.iter().enumerate() {
            self.inequality_jacobian_t[(i, row)] = v;
        }
        self.lower[row] = lower;
        self.upper[row] = upper;
        Ok(())
    }

    fn check_row(&self, row: usize, rows: usize, len: usize) -> Result<(), SolverError> {
        if row >= rows {
            return Err(SolverError::NoSuchRow {
                level: self.index,
                name: self.name.to_owned(),
                row,
                rows,
            });
        }
        let n = self.jacobian_t.nrows();
        if len != n {
            return Err(SolverError::DimensionMismatch {
                what: format!(
                    "Jacobian row {row} of level {} ({:?})",
                    self.index, self.name
                ),
                expected: n,
                got: len,
            });
        }
        Ok(())
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
        self.check_row(row, self.rows(), jacobian.len())?;
        for (i, &v) in jacobian.iter().enumerate() {
            self.jacobian_t[(i, row)] = v;
        }
        self.target[row] = velocity;
        Ok(())
    }
}
