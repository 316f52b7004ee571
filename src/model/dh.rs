//! Loader of modified-DH tree tables (TOML, format `taskstack-dh/1`).
//!
//! Joint `j` connects its antecedent link `a(j)` to link `j` through (Khalil–Dombre)
//!
//! ```text
//! T(a(j) → j) = Rot(z, γ) · Trans(z, b) · Rot(x, α) · Trans(x, d) · Rot(z, θ_j) · Trans(z, r_j)
//! ```
//!
//! with `θ_j = θ + μ·q[k]` for a revolute joint, `r_j = r + μ·q[k]` for a prismatic one (both
//! constant for a fixed joint). Since `Rot(z, ·)` and `Trans(z, ·)` commute, this is the tree's
//! `P_j · M_j(μ·q[k])` with `P_j` the whole product at `q = 0` and motion axis `z_j`.
//!
//! The document (all lengths in metres, angles in radians, masses in kilograms):
//! `format = "taskstack-dh/1"`, optional `name`, `[units]` (exactly `length = "m"`,
//! `angle = "rad"`, `mass = "kg"`), `[base]` (`link`, `mass`, `com`), `[[variables]]` (`name`,
//! `lower`, `upper`, `velocity`), `[[joints]]` (`name`, `antecedent`, `link`, `type` =
//! `"revolute" | "prismatic" | "fixed"`, `gamma`, `b`, `alpha`, `d`, `theta`, `r`, `variable`
//! (not for fixed joints), optional `multiplier` (default 1, non-zero), `mass`, `com`) and
//! `[[frames]]` (`name`, `link`, `position`, optional `rpy` = roll, pitch, yaw with rotation
//! `Rz(yaw)·Ry(pitch)·Rx(roll)` as in URDF). Every field is checked (finite numbers, masses ≥ 0,
//! lower ≤ upper, unique names, known antecedents, no cycle, every variable used, no unknown
//! field, no magnitude above [`MAX_MAGNITUDE`](super::MAX_MAGNITUDE)); errors name the origin
//! (file path), the row (`joints[7] (RAnkleRoll)`) and the field.

use std::path::Path;

use nalgebra::{IsometryMatrix3, Rotation3, Translation3, Vector3};
use thiserror::Error;
use toml::{Table, Value};

use super::tree::{FrameSpec, JointSpec, TreeIssue, TreeSpec};
use super::{JointKind, Link, Model, Variable};

/// The only supported value of the `format` key.
pub const DH_FORMAT: &str = "taskstack-dh/1";

/// What is wrong with one field of a DH table.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum DhProblem {
    /// A required field is absent.
    #[error("missing")]
    Missing,
    /// The field has the wrong TOML type.
    #[error("expected {0}")]
    WrongType(&'static str),
    /// A number is NaN or infinite.
    #[error("not a finite number ({0})")]
    NonFinite(f64),
    /// A number above [`MAX_MAGNITUDE`](super::MAX_MAGNITUDE) in magnitude.
    #[error("magnitude above 1e6 ({0})")]
    TooLarge(f64),
    /// A mass or speed is negative.
    #[error("negative value ({0})")]
    Negative(f64),
    /// A field that the format does not define (a typo?).
    #[error("unknown field")]
    UnknownField,
    /// `format` is not [`DH_FORMAT`].
    #[error("unsupported format `{0}` (expected `taskstack-dh/1`)")]
    WrongFormat(String),
    /// A unit other than m, rad, kg.
    #[error("unit `{got}` not supported (expected `{expected}`)")]
    WrongUnit {
        /// The unit the format requires.
        expected: &'static str,
        /// The unit found.
        got: String,
    },
    /// `type` is not revolute, prismatic or fixed.
    #[error("unknown joint type `{0}` (expected revolute, prismatic or fixed)")]
    UnknownJointType(String),
    /// A name already used by an earlier row.
    #[error("duplicate name `{0}`")]
    Duplicate(String),
    /// The antecedent is neither the base link nor a row's link.
    #[error("unknown antecedent link `{0}`")]
    UnknownAntecedent(String),
    /// The antecedents of this row lead back to itself instead of to the base.
    #[error("antecedent `{0}` is part of a cycle that never reaches the base")]
    Cycle(String),
    /// A joint names a variable that is not declared.
    #[error("unknown variable `{0}`")]
    UnknownVariable(String),
    /// A declared variable drives no joint.
    #[error("variable `{0}` drives no joint")]
    UnusedVariable(String),
    /// A fixed joint names a variable.
    #[error("a fixed joint has no variable")]
    VariableOnFixed,
    /// The multiplier is zero (the joint would not follow its variable).
    #[error("multiplier must be non-zero")]
    ZeroMultiplier,
    /// `lower > upper`.
    #[error("lower limit {lower} is above upper limit {upper}")]
    LowerAboveUpper {
        /// Lower limit.
        lower: f64,
        /// Upper limit.
        upper: f64,
    },
    /// A frame names a link that does not exist.
    #[error("unknown link `{0}`")]
    UnknownLink(String),
}

/// Errors of the DH loader; each names the origin (file path or the given origin string).
#[derive(Debug, Clone, PartialEq, Error)]
pub enum DhError {
    /// The file could not be read.
    #[error("{origin}: cannot read: {message}")]
    Io {
        /// File path.
        origin: String,
        /// The I/O error.
        message: String,
    },
    /// The text is not valid TOML.
    #[error("{origin}: TOML syntax: {message}")]
    Syntax {
        /// File path or origin string.
        origin: String,
        /// Parser message (with line and column).
        message: String,
    },
    /// A field is missing or invalid.
    #[error("{origin}: {place}, field `{field}`: {problem}")]
    Invalid {
        /// File path or origin string.
        origin: String,
        /// Table or row, e.g. `joints[7] (RAnkleRoll)`, `base`, `units`, `document`.
        place: String,
        /// Field name.
        field: String,
        /// What is wrong.
        problem: DhProblem,
    },
}

impl DhError {
    /// The problem, when the error is about one field.
    pub fn problem(&self) -> Option<&DhProblem> {
        match self {
            DhError::Invalid { problem, .. } => Some(problem),
            _ => None,
        }
    }
}

impl Model {
    /// Builds a model from a DH table (see [`dh`](self)); `origin` names the text in errors
    /// (a path, or e.g. `"<embedded>"`).
    pub fn from_dh_str(text: &str, origin: &str) -> Result<Model, DhError> {
        let doc: Table = text.parse().map_err(|e: toml::de::Error| DhError::Syntax {
            origin: origin.to_owned(),
            message: e.to_string().trim_end().to_owned(),
        })?;
        Loader { origin }.load(&doc)
    }

    /// Reads and builds a DH table file (see [`Model::from_dh_str`]); errors name the path.
    pub fn from_dh_file(path: impl AsRef<Path>) -> Result<Model, DhError> {
        let path = path.as_ref();
        let origin = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|e| DhError::Io {
            origin: origin.clone(),
            message: e.to_string(),
        })?;
        Model::from_dh_str(&text, &origin)
    }
}

struct Loader<'a> {
    origin: &'a str,
}

/// The `[units]` table: metres, radians, kilograms.
fn check_units(units: &Row<'_>) -> Result<(), DhError> {
    units.allow(&["length", "angle", "mass"])?;
    for (field, expected) in [("length", "m"), ("angle", "rad"), ("mass", "kg")] {
        let got = units.string(field)?;
        if got != expected {
            let problem = DhProblem::WrongUnit {
                expected,
                got: got.to_owned(),
            };
            return Err(units.err(field, problem));
        }
    }
    Ok(())
}

/// A `[[variables]]` row.
fn variable(row: &Row<'_>) -> Result<Variable, DhError> {
    row.allow(&["name", "lower", "upper", "velocity"])?;
    let (lower, upper) = (row.number("lower")?, row.number("upper")?);
    if lower > upper {
        return Err(row.err("upper", DhProblem::LowerAboveUpper { lower, upper }));
    }
    Ok(Variable {
        name: row.string("name")?.to_owned(),
        lower,
        upper,
        velocity: row.mass("velocity")?,
        effort: f64::INFINITY,
    })
}

/// A `[[frames]]` row.
fn frame(row: &Row<'_>) -> Result<FrameSpec, DhError> {
    row.allow(&["name", "link", "position", "rpy"])?;
    let rpy = row.opt_vec3("rpy")?.unwrap_or_else(Vector3::zeros);
    Ok(FrameSpec {
        name: row.string("name")?.to_owned(),
        link: row.string("link")?.to_owned(),
        placement: IsometryMatrix3::from_parts(
            Translation3::from(row.vec3("position")?),
            Rotation3::from_euler_angles(rpy.x, rpy.y, rpy.z),
        ),
    })
}

/// The error naming the row and field of a tree-building issue of `spec`, whose variables,
/// joints and frames came from `rows`.
fn tree_issue_error(
    spec: &TreeSpec,
    [variables, joints, frames]: &[Vec<Row<'_>>; 3],
    issue: TreeIssue,
) -> DhError {
    let (row, field, problem) = match issue {
        TreeIssue::DuplicateVariable(i) => (
            &variables[i],
            "name",
            DhProblem::Duplicate(spec.variables[i].name.clone()),
        ),
        TreeIssue::UnusedVariable(i) => (
            &variables[i],
            "name",
            DhProblem::UnusedVariable(spec.variables[i].name.clone()),
        ),
        TreeIssue::DuplicateJoint(i) => (
            &joints[i],
            "name",
            DhProblem::Duplicate(spec.joints[i].name.clone()),
        ),
        TreeIssue::DuplicateLink(i) => (
            &joints[i],
            "link",
            DhProblem::Duplicate(spec.joints[i].link.name.clone()),
        ),
        TreeIssue::UnknownAntecedent(i) => (
            &joints[i],
            "antecedent",
            DhProblem::UnknownAntecedent(spec.joints[i].antecedent.clone()),
        ),
        TreeIssue::Cycle(i) => (
            &joints[i],
            "antecedent",
            DhProblem::Cycle(spec.joints[i].antecedent.clone()),
        ),
        TreeIssue::DuplicateFrame(i) => (
            &frames[i],
            "name",
            DhProblem::Duplicate(spec.frames[i].name.clone()),
        ),
        TreeIssue::UnknownFrameLink(i) => (
            &frames[i],
            "link",
            DhProblem::UnknownLink(spec.frames[i].link.clone()),
        ),
    };
    row.err(field, problem)
}

/// One TOML table being read, with its place for error messages.
struct Row<'a> {
    origin: &'a str,
    place: String,
    table: &'a Table,
}

impl Loader<'_> {
    fn load(&self, doc: &Table) -> Result<Model, DhError> {
        let top = Row {
            origin: self.origin,
            place: "document".into(),
            table: doc,
        };
        top.allow(&[
            "format",
            "name",
            "units",
            "base",
            "variables",
            "joints",
            "frames",
        ])?;
        let format = top.string("format")?;
        if format != DH_FORMAT {
            return Err(top.err("format", DhProblem::WrongFormat(format.to_owned())));
        }
        let name = top.opt_string("name")?.unwrap_or("").to_owned();
        check_units(&top.sub_table("units")?)?;
        let base_row = top.sub_table("base")?;
        base_row.allow(&["link", "mass", "com"])?;
        let base = Link {
            name: base_row.string("link")?.to_owned(),
            mass: base_row.mass("mass")?,
            com: base_row.vec3("com")?,
            inertia: None,
        };
        let rows = [
            top.rows("variables")?,
            top.rows("joints")?,
            top.rows("frames")?,
        ];
        let variables = rows[0]
            .iter()
            .map(variable)
            .collect::<Result<Vec<_>, _>>()?;
        let joints = rows[1]
            .iter()
            .map(|row| self.joint(row, &variables))
            .collect::<Result<_, _>>()?;
        let frames = rows[2].iter().map(frame).collect::<Result<_, _>>()?;
        let spec = TreeSpec {
            name,
            base,
            variables,
            joints,
            frames,
        };
        spec.clone()
            .build()
            .map_err(|issue| tree_issue_error(&spec, &rows, issue))
    }

    fn joint(&self, row: &Row<'_>, variables: &[Variable]) -> Result<JointSpec, DhError> {
        row.allow(&[
            "name",
            "antecedent",
            "link",
            "type",
            "gamma",
            "b",
            "alpha",
            "d",
            "theta",
            "r",
            "variable",
            "multiplier",
            "mass",
            "com",
        ])?;
        let kind = match row.string("type")? {
            "revolute" => JointKind::Revolute,
            "prismatic" => JointKind::Prismatic,
            "fixed" => JointKind::Fixed,
            other => return Err(row.err("type", DhProblem::UnknownJointType(other.to_owned()))),
        };
        let [gamma, b, alpha, d, theta, r] =
            ["gamma", "b", "alpha", "d", "theta", "r"].map(|f| row.number(f));
        let placement = IsometryMatrix3::from_parts(
            Translation3::identity(),
            Rotation3::from_axis_angle(&Vector3::z_axis(), gamma?),
        ) * Translation3::new(0.0, 0.0, b?)
            * Rotation3::from_axis_angle(&Vector3::x_axis(), alpha?)
            * Translation3::new(d?, 0.0, 0.0)
            * Rotation3::from_axis_angle(&Vector3::z_axis(), theta?)
            * Translation3::new(0.0, 0.0, r?);
        let variable = match (kind, row.opt_string("variable")?) {
            (JointKind::Fixed, None) => None,
            (JointKind::Fixed, Some(_)) => {
                return Err(row.err("variable", DhProblem::VariableOnFixed));
            }
            (_, None) => return Err(row.err("variable", DhProblem::Missing)),
            (_, Some(name)) => Some(
                variables
                    .iter()
                    .position(|v| v.name == name)
                    .ok_or_else(|| row.err("variable", DhProblem::UnknownVariable(name.into())))?,
            ),
        };
        let multiplier = row.opt_number("multiplier")?.unwrap_or(1.0);
        if multiplier == 0.0 {
            return Err(row.err("multiplier", DhProblem::ZeroMultiplier));
        }
        Ok(JointSpec {
            name: row.string("name")?.to_owned(),
            antecedent: row.string("antecedent")?.to_owned(),
            link: Link {
                name: row.string("link")?.to_owned(),
                mass: row.mass("mass")?,
                com: row.vec3("com")?,
                inertia: None,
            },
            placement,
            axis: Vector3::z_axis(),
            kind,
            variable,
            multiplier,
            offset: 0.0,
        })
    }
}

impl<'a> Row<'a> {
    fn err(&self, field: &str, problem: DhProblem) -> DhError {
        DhError::Invalid {
            origin: self.origin.to_owned(),
            place: self.place.clone(),
            field: field.to_owned(),
            problem,
        }
    }

    fn allow(&self, fields: &[&str]) -> Result<(), DhError> {
        match self.table.keys().find(|k| !fields.contains(&k.as_str())) {
            Some(unknown) => Err(self.err(unknown, DhProblem::UnknownField)),
            None => Ok(()),
        }
    }

    fn get(&self, field: &str) -> Result<&'a Value, DhError> {
        self.table
            .get(field)
            .ok_or_else(|| self.err(field, DhProblem::Missing))
    }

    fn opt_string(&self, field: &str) -> Result<Option<&'a str>, DhError> {
        self.table
            .get(field)
            .map(|v| {
                v.as_str()
                    .ok_or_else(|| self.err(field, DhProblem::WrongType("a string")))
            })
            .transpose()
    }

    fn string(&self, field: &str) -> Result<&'a str, DhError> {
        self.opt_string(field)?
            .ok_or_else(|| self.err(field, DhProblem::Missing))
    }

    fn finite(&self, field: &str, value: &Value) -> Result<f64, DhError> {
        let x = match value {
            Value::Float(x) => *x,
            // TOML integers (`b = 0`) are accepted as numbers; i64 → f64 is exact for lengths.
            Value::Integer(i) => *i as f64,
            _ => return Err(self.err(field, DhProblem::WrongType("a number"))),
        };
        if !x.is_finite() {
            Err(self.err(field, DhProblem::NonFinite(x)))
        } else if x.abs() > super::MAX_MAGNITUDE {
            Err(self.err(field, DhProblem::TooLarge(x)))
        } else {
            Ok(x)
        }
    }

    fn opt_number(&self, field: &str) -> Result<Option<f64>, DhError> {
        self.table
            .get(field)
            .map(|v| self.finite(field, v))
            .transpose()
    }

    fn number(&self, field: &str) -> Result<f64, DhError> {
        self.finite(field, self.get(field)?)
    }

    /// A finite number ≥ 0 (masses, speeds).
    fn mass(&self, field: &str) -> Result<f64, DhError> {
        let x = self.number(field)?;
        if x < 0.0 {
            return Err(self.err(field, DhProblem::Negative(x)));
        }
        Ok(x)
    }

    fn opt_vec3(&self, field: &str) -> Result<Option<Vector3<f64>>, DhError> {
        let Some(value) = self.table.get(field) else {
            return Ok(None);
        };
        let wrong = || self.err(field, DhProblem::WrongType("an array of 3 numbers"));
        let items = value.as_array().ok_or_else(wrong)?;
        if items.len() != 3 {
            return Err(wrong());
        }
        let mut v = Vector3::zeros();
        for (slot, item) in v.iter_mut().zip(items) {
            *slot = self.finite(field, item)?;
        }
        Ok(Some(v))
    }

    fn vec3(&self, field: &str) -> Result<Vector3<f64>, DhError> {
        self.opt_vec3(field)?
            .ok_or_else(|| self.err(field, DhProblem::Missing))
    }

    fn sub_table(&self, field: &str) -> Result<Row<'a>, DhError> {
        let table = self
            .get(field)?
            .as_table()
            .ok_or_else(|| self.err(field, DhProblem::WrongType("a table")))?;
        Ok(Row {
            origin: self.origin,
            place: field.to_owned(),
            table,
        })
    }

    /// The rows of an array of tables (absent = no rows), each placed as `field[i] (name)`.
    fn rows(&self, field: &str) -> Result<Vec<Row<'a>>, DhError> {
        let Some(value) = self.table.get(field) else {
            return Ok(Vec::new());
        };
        let items = value
            .as_array()
            .ok_or_else(|| self.err(field, DhProblem::WrongType("an array of tables")))?;
        items
            .iter()
            .enumerate()
            .map(|(i, item)| {
                let table = item
                    .as_table()
                    .ok_or_else(|| self.err(field, DhProblem::WrongType("an array of tables")))?;
                let place = match table.get("name").and_then(Value::as_str) {
                    Some(name) => format!("{field}[{i}] ({name})"),
                    None => format!("{field}[{i}]"),
                };
                Ok(Row {
                    origin: self.origin,
                    place,
                    table,
                })
            })
            .collect()
    }
}
