//! Errors of the solver layer.

use thiserror::Error;

/// What went wrong when building or solving a task stack. Messages name the offending level, row,
/// joint or parameter, so that a caller can tell *why* a solve was refused.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum SolverError {
    /// The stack has no level.
    #[error("the task stack has no level")]
    EmptyStack,
    /// The stack has no joint (degree of freedom).
    #[error("the task stack has no degree of freedom (dof = 0)")]
    NoDegreesOfFreedom,
    /// A level was declared with no rows.
    #[error("level {level} ({name:?}) has no rows")]
    EmptyLevel {
        /// Index of the level (0 = highest priority).
        level: usize,
        /// Name of the level.
        name: String,
    },
    /// A slice or view has the wrong length or shape.
    #[error("{what}: expected {expected}, got {got}")]
    DimensionMismatch {
        /// What was being given (e.g. `"q"`, `"level 1 (\"hands\") row 4"`).
        what: String,
        /// The expected size.
        expected: usize,
        /// The size that was given.
        got: usize,
    },
    /// A level index beyond the stack.
    #[error("level index {level} is out of range (the stack has {levels} levels)")]
    NoSuchLevel {
        /// The requested index.
        level: usize,
        /// How many levels there are.
        levels: usize,
    },
    /// A row index beyond a level.
    #[error("row {row} is out of range for level {level} ({name:?}, {rows} rows)")]
    NoSuchRow {
        /// Level index.
        level: usize,
        /// Level name.
        name: String,
        /// The requested row.
        row: usize,
        /// How many rows the level has.
        rows: usize,
    },
    /// A task name that the stack does not have.
    #[error("the stack has no task named {0:?}")]
    NoSuchTask(String),
    /// A NaN or infinite number in the input.
    #[error("non-finite value {value} in {what}")]
    NonFinite {
        /// Where it was found (e.g. `"Jacobian of level 0 (\"com\") at row 1, column 7"`).
        what: String,
        /// The value.
        value: f64,
    },
    /// A joint whose lower limit is above its upper limit.
    #[error("joint {joint}: lower limit {lower} is above upper limit {upper}")]
    InvertedLimits {
        /// Joint index.
        joint: usize,
        /// Lower limit (rad or m).
        lower: f64,
        /// Upper limit (rad or m).
        upper: f64,
    },
    /// An inequality row whose bounds admit no value: `lower > upper`, `lower = +∞` or
    /// `upper = −∞`.
    #[error(
        "inequality row {row} of level {level} ({name:?}): bounds [{lower}, {upper}] are empty"
    )]
    InvertedBounds {
        /// Level index.
        level: usize,
        /// Level name.
        name: String,
        /// Row within the level's inequality rows.
        row: usize,
        /// Lower bound (task velocity units).
        lower: f64,
        /// Upper bound (task velocity units).
        upper: f64,
    },
    /// A parameter outside its valid range (a negative velocity limit, a non-positive time step, …).
    #[error("invalid {name} = {value}: {reason}")]
    InvalidParameter {
        /// Parameter name.
        name: &'static str,
        /// The value given.
        value: f64,
        /// What the valid range is.
        reason: &'static str,
    },
}
