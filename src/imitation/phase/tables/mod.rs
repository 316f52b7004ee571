//! Task tables (Poubel §II.B, §IV.B, Table I) as data: for each [`SupportPhase`], the model root,
//! the levels in priority order (balance first, then Cartesian tracking), the gradient
//! (optimization) tasks with their weights κ, and whether the clamping loop runs.
//!
//! # Task targets
//!
//! All coordinates are in the frame of the table's model root (the support sole: x forward, y
//! left, z up, origin on the ground under the ankle), in metres.
//!
//! * [`Task::ComXY`] — the CoM ground projection `X'_c = (x_c, y_c)`, 2 rows, with the goal
//!   ([`ComGoal`]) `[0, 0]` (under the support ankle, single support), `[λ, 0]` (λ toward the
//!   support foot's centre, while a foot is lifted or lowered), `p_A.xy / 2` (midway to the other
//!   ankle `A`, DS) or `p_A.xy + λ·x̂_A` (λ toward the other foot's centre along that sole's x
//!   axis, CoM moving to the foot that is not the model root).
//! * [`Task::Point`] — the selected coordinates ([`Axes`]) of a named robot frame, with the
//!   target ([`PointTarget`]) either the scaled human joint, or the frame "held": its horizontal
//!   position when the step began, at its rest height (its height when its foot is flat on the
//!   ground: 0 for a sole point, the ankle's height for an ankle) plus a lift (0 on the ground, ρ lifted).
//!
//! Gradient tasks add `κ_k ∇f_k(q)` in the null space of the equality levels (eq. 6): joint
//! limits `f_ℓ` (eq. 7, κ = −0.10) and human joint tracking `f_h` (eq. 8, κ = −0.02).
//!
//! # Paper choices and corrections
//!
//! The printed Table I has typos, corrected here: "Lift RFoot" and "Lower RFoot" (LFoot model)
//! track the right foot (`p_RA`, `z_RF`, `z_RT`), not `p_LA`; "zz_LT" is `z_LT`. `F` and `T`
//! are the sole's front (toe) and heel ("talon") points, `l_toe` / `l_heel` here. The "DS to LS,
//! CoM to LFoot" goal is the printed `[x_LA, y_LA]` shifted by λ toward the left foot's centre,
//! so the goal does not jump by λ when "Lift RFoot" (goal `[λ, 0]` in the LFoot model) follows;
//! §III.B asks for that offset whenever a foot is lifted or lowered. During transitions the hands
//! are free (§IV.B) and the moving foot is held horizontally: the paper lowers a foot straight
//! down and slides it to its scaled position once in DS (§IV.D).
//!
//! # Overriding
//!
//! Tables are plain data: read one with [`TaskTables::table`], clone, edit and put it back with
//! [`TaskTables::set`] (which validates it), e.g. to track the head as well in RS:
//!
//! ```
//! use taskstack::human::HumanJoint;
//! use taskstack::imitation::phase::SupportPhase;
//! use taskstack::imitation::phase::tables::{Axes, PointTarget, Task, TaskTables};
//! use taskstack::robots::nao;
//!
//! let mut tables = TaskTables::paper(&nao::profile());
//! let mut rs = tables.table(SupportPhase::Right).clone();
//! rs.levels[1].tasks.push(Task::Point {
//!     frame: "head".into(),
//!     offset: [0.0; 3],
//!     axes: Axes::XYZ,
//!     target: PointTarget::Scaled(HumanJoint::Head),
//! });
//! tables.set(rs)?;
//! let shape = tables.table(SupportPhase::Right).shape(23);
//! assert_eq!(shape.level_rows().collect::<Vec<_>>(), vec![2, 12]);
//! # Ok::<(), taskstack::imitation::phase::tables::TableError>(())
//! ```
//!
//! # Table I
//!
//! Generated from [`TaskTables::paper`] (`cargo run --example table1 > src/imitation/phase/tables/table1.md`;
//! a unit test keeps this copy equal to the data):
//!
#![doc = include_str!("table1.md")]

use std::collections::HashSet;
use std::fmt;

use crate::human::{HumanJoint, Side};
use crate::imitation::phase::{Landing, PhaseConfig, SupportPhase, TakeOff};
use crate::robots::BipedProfile;
use crate::solver::StackShape;

mod paper;
mod render;

pub(crate) use paper::self_collision_level;

/// Goal of the CoM ground projection, in the model root's frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ComGoal {
    /// `[0, 0]`: under the support (root) ankle.
    SupportAnkle,
    /// `[λ, 0]`: `lambda` metres forward of the support ankle, toward the foot's centre.
    SupportFootCentre {
        /// Offset λ (m).
        lambda: f64,
    },
    /// `p_A.xy / 2`: midway between the support ankle and the other ankle `A`.
    MidAnkles,
    /// `p_A.xy + λ·x̂_A`: `lambda` metres ahead of the other ankle along its sole's x axis.
    OtherFootCentre {
        /// Offset λ (m).
        lambda: f64,
    },
    /// A point fixed in the support (root) sole's frame, `[x, y]` in metres: the centre of that
    /// foot's contact area, say.
    SupportPoint([f64; 2]),
    /// A point fixed in the other sole's frame (`[x, y]`, m), so it moves and turns with that
    /// foot.
    OtherPoint([f64; 2]),
    /// Midway between a point of the support sole (`support`, in its frame) and a point of the
    /// other sole (`other`, in its frame): the middle of the two contact areas.
    BetweenPoints {
        /// The support sole's point (m, support sole frame).
        support: [f64; 2],
        /// The other sole's point (m, other sole frame).
        other: [f64; 2],
    },
}

impl ComGoal {
    /// Every number of the goal (for validation).
    fn numbers(&self) -> impl Iterator<Item = f64> {
        let values: [f64; 4] = match *self {
            ComGoal::SupportAnkle | ComGoal::MidAnkles => [0.0; 4],
            ComGoal::SupportFootCentre { lambda } | ComGoal::OtherFootCentre { lambda } => {
                [lambda, 0.0, 0.0, 0.0]
            }
            ComGoal::SupportPoint([x, y]) | ComGoal::OtherPoint([x, y]) => [x, y, 0.0, 0.0],
            ComGoal::BetweenPoints { support, other } => {
                [support[0], support[1], other[0], other[1]]
            }
        };
        values.into_iter()
    }
}

/// Which Cartesian coordinates of a frame are tracked.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Axes {
    /// Track x (forward).
    pub x: bool,
    /// Track y (left).
    pub y: bool,
    /// Track z (up).
    pub z: bool,
}

impl Axes {
    /// All three coordinates.
    pub const XYZ: Axes = Axes {
        x: true,
        y: true,
        z: true,
    };
    /// The horizontal coordinates.
    pub const XY: Axes = Axes {
        x: true,
        y: true,
        z: false,
    };
    /// The height only.
    pub const Z: Axes = Axes {
        x: false,
        y: false,
        z: true,
    };

    /// Number of tracked coordinates (task rows).
    pub const fn count(self) -> usize {
        self.x as usize + self.y as usize + self.z as usize
    }

    /// `""` for xyz, else `".xz"`-style suffix of the selected axes.
    fn suffix(self) -> String {
        if self == Axes::XYZ {
            return String::new();
        }
        let picked = [(self.x, 'x'), (self.y, 'y'), (self.z, 'z')];
        std::iter::once('.')
            .chain(picked.iter().filter(|(on, _)| *on).map(|&(_, c)| c))
            .collect()
    }
}

/// Target of a [`Task::Point`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PointTarget {
    /// The position of this joint of the scaled human (robot proportions, model root frame).
    Scaled(HumanJoint),
    /// The frame's horizontal position when the step began, at its rest height plus `lift`.
    Held {
        /// Height above the rest height (m): 0 on the ground, ρ for a lifted foot.
        lift: f64,
    },
    /// Where the frame is in the imitator's initial posture (both feet flat), in the model
    /// root's frame, lowered by `lower` metres: with [`Axes::Z`], a torso kept at its standing
    /// height or a little below it, so that the legs stay bent when the hips shift over one
    /// foot.
    Standing {
        /// How far below the initial posture (m).
        lower: f64,
    },
    /// Above the target footprint of the step the robot is taking ([`crate::imitation::walking::footsteps`]), at
    /// the frame's rest height plus `lift`: a swing foot carried to where it will land. Held
    /// where the step began when no step is planned.
    Footstep {
        /// Height above the rest height (m).
        lift: f64,
    },
    /// The contact point of the `Side` hand while it is placed on a surface or rests there as
    /// a support ([`crate::imitation::poubel::hand_support`]); the task has no effect (zero rows) while the hand
    /// is free.
    HandContact(Side),
    /// Where the walking pattern generator puts the frame this frame ([`crate::imitation::walking`]): the
    /// planned sole's ground point, at the frame's rest height plus the planned swing height. A
    /// sole on the floor or on its swing path.
    Planned,
}

/// Target of a [`Task::Orientation`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum OrientationTarget {
    /// Flat (the frame's z axis vertical) with the heading (yaw about the vertical) the frame
    /// had when the step began: 3 rows, the angular error as a rotation vector (rad). A foot on
    /// the ground, or carried parallel to it.
    HeldFlat,
    /// The frame's z axis vertical, or leaning `lean` rad sideways (about the root sole's x
    /// axis, positive toward the root frame's +y), its yaw free: 2 rows (the horizontal
    /// components of the rotation vector that turns z onto its target, rad). An upright torso,
    /// or one leaning a little over the foot the robot stands or is about to stand on.
    Upright {
        /// Sideways lean (rad, about the root sole's x axis; + toward +y).
        lean: f64,
    },
    /// Flat with the heading of the target footprint of the step the robot is taking (3 rows;
    /// the heading held when no step is planned).
    Footstep,
    /// The frame's z axis along the walk's planned up direction (2 rows, as `Upright`): a torso
    /// leaning over the stance hip as far as the walking pattern generator's CoM is from the
    /// middle of the feet ([`crate::imitation::walking`]).
    Leaning,
    /// As [`OrientationTarget::Upright`] (the z axis leaning `lean` rad about the root sole's
    /// x axis), with the x axis facing midway between the two soles' headings: 3 rows (the
    /// rotation vector to that orientation, rad). The hips of a robot with a waist
    /// ([`BipedProfile::chest`]): the hands then turn its upper body at the waist, not the
    /// whole robot on its feet.
    Facing {
        /// Sideways lean (rad, about the root sole's x axis; + toward +y).
        lean: f64,
    },
}

/// One tracked task of an equality level.
#[derive(Clone, Debug, PartialEq)]
pub enum Task {
    /// The CoM ground projection (2 rows). Like [`Task::ComHeight`] it moves only the joints
    /// that turn the torso, a sole or a hand: a joint that turns none of them (the NAO's head)
    /// moves the CoM by millimetres per radian and is left to the posture gradient.
    ComXY(ComGoal),
    /// The CoM's height above the root sole (1 row), at the walk's planned height
    /// ([`crate::imitation::walking`]): the cart-table's constant height.
    ComHeight,
    /// Coordinates of a point fixed to a named robot frame (see [`crate::robots::BipedProfile`]), 1–3
    /// rows.
    Point {
        /// Frame name, e.g. `"l_hand"`.
        frame: String,
        /// The point in that frame (m); zero for the frame's origin.
        offset: [f64; 3],
        /// The tracked coordinates.
        axes: Axes,
        /// Where they go.
        target: PointTarget,
    },
    /// The orientation of a named robot frame, 2 or 3 rows ([`OrientationTarget`]).
    Orientation {
        /// Frame name, e.g. `"l_sole"` or `"torso"`.
        frame: String,
        /// What the orientation should be.
        target: OrientationTarget,
    },
}

impl Task {
    /// The task's name in the stack: `"com_xy"`, the frame name, or the frame name with the axes
    /// (`"l_toe.z"`) when not all three are tracked; a hand support is `"<hand>.support"`.
    pub fn name(&self) -> String {
        match self {
            Task::ComXY(_) => "com_xy".to_owned(),
            Task::ComHeight => "com_z".to_owned(),
            Task::Point {
                frame,
                target: PointTarget::HandContact(_),
                ..
            } => format!("{frame}.support"),
            Task::Point { frame, axes, .. } => format!("{frame}{}", axes.suffix()),
            Task::Orientation {
                frame,
                target: OrientationTarget::HeldFlat | OrientationTarget::Footstep,
            } => format!("{frame}.rot"),
            Task::Orientation {
                frame,
                target: OrientationTarget::Upright { .. } | OrientationTarget::Leaning,
            } => format!("{frame}.upright"),
            Task::Orientation {
                frame,
                target: OrientationTarget::Facing { .. },
            } => format!("{frame}.facing"),
        }
    }

    /// Number of rows (tracked coordinates).
    pub fn rows(&self) -> usize {
        match self {
            Task::ComXY(_) => 2,
            Task::ComHeight => 1,
            Task::Point { axes, .. } => axes.count(),
            Task::Orientation {
                target:
                    OrientationTarget::HeldFlat
                    | OrientationTarget::Footstep
                    | OrientationTarget::Facing { .. },
                ..
            } => 3,
            Task::Orientation {
                target: OrientationTarget::Upright { .. } | OrientationTarget::Leaning,
                ..
            } => 2,
        }
    }
}

/// An inequality of a level: a row kept within bounds instead of driven to a target.
#[derive(Clone, Debug, PartialEq)]
pub enum Constraint {
    /// Two bodies of the profile's self-collision model
    /// ([`BipedProfile::self_collision`](crate::robots::BipedProfile::self_collision), by name)
    /// kept at least `margin` apart (m), 1 row.
    Distance {
        /// The first body's name, e.g. `"l_forearm"`.
        first: String,
        /// The second body's name, e.g. `"torso"`.
        second: String,
        /// Smallest surface-to-surface distance (m, ≥ 0).
        margin: f64,
    },
    /// The zero-moment point of the CoM and the arms' motion inside the support polygon (the
    /// root sole's contact area, with the other sole's where the phase stands on both),
    /// `margin` inside its edges, and the arms' vertical moment on the floor within
    /// `±max_yaw_moment`, over the frame's motion ([`ZmpTask`](crate::tasks::ZmpTask) seeing
    /// the arms' joints; [`TaskTables::add_zmp_balance`]): one row per polygon vertex
    /// (`vertices`, the most the polygon may have: both soles' outline points) and one for
    /// the moment.
    Zmp {
        /// Distance kept from the polygon's edges (m, ≥ 0).
        margin: f64,
        /// Largest vertical moment of the floor on the standing soles (N·m, > 0).
        max_yaw_moment: f64,
        /// The most vertices of the support polygon (≥ 4).
        vertices: usize,
    },
}

impl Constraint {
    /// The constraint's name in the stack: `"d(l_forearm,torso)"`.
    pub fn name(&self) -> String {
        match self {
            Constraint::Distance { first, second, .. } => format!("d({first},{second})"),
            Constraint::Zmp { .. } => "zmp".to_owned(),
        }
    }

    /// Number of rows.
    pub fn rows(&self) -> usize {
        match self {
            Constraint::Distance { .. } => 1,
            Constraint::Zmp { vertices, .. } => vertices + 1,
        }
    }
}

/// A level: tasks of equal priority, stacked in order, and the inequalities solved at the same
/// priority.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct Level {
    /// Level name (`"balance"`, `"tracking"`).
    pub name: String,
    /// The equality tasks.
    pub tasks: Vec<Task>,
    /// The inequalities.
    pub constraints: Vec<Constraint>,
}

impl Level {
    /// A level of equality tasks.
    pub fn of_tasks(name: &str, tasks: Vec<Task>) -> Self {
        Self {
            name: name.to_owned(),
            tasks,
            constraints: Vec::new(),
        }
    }

    /// Rows of the equality tasks and of the inequalities.
    pub(crate) fn rows(&self) -> usize {
        let tasks: usize = self.tasks.iter().map(Task::rows).sum();
        tasks + self.constraints.iter().map(Constraint::rows).sum::<usize>()
    }
}

/// An optimization (gradient) task.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum GradientKind {
    /// Stay near the middle of the joint ranges (eq. 7).
    JointLimits,
    /// Follow the human's joint angles (eq. 8).
    HumanJoints,
}

/// A gradient task and its weight κ (dimensionless; negative descends `f`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Gradient {
    /// Which function.
    pub kind: GradientKind,
    /// Weight κ.
    pub kappa: f64,
}

impl Gradient {
    /// The paper's gradients: joint limits (eq. 7, κ = −0.10), then the human's joint angles
    /// (eq. 8, κ = −0.02).
    pub const fn paper() -> [Gradient; 2] {
        [
            Gradient {
                kind: GradientKind::JointLimits,
                kappa: -0.10,
            },
            Gradient {
                kind: GradientKind::HumanJoints,
                kappa: -0.02,
            },
        ]
    }
}

/// Everything the IK solves in one phase.
#[derive(Clone, Debug, PartialEq)]
pub struct TaskTable {
    /// The phase this table is for.
    pub phase: SupportPhase,
    /// The sole the model is rooted at (all targets are in its frame).
    pub model_root: Side,
    /// Levels (equality tasks and inequalities), highest priority first.
    pub levels: Vec<Level>,
    /// Gradient tasks, summed in the null space of all levels.
    pub gradients: Vec<Gradient>,
    /// Whether the clamping loop (fix violating joints at their limit and re-solve) runs, as
    /// Table I describes the method. The [`Imitator`](crate::imitation::imitator::Imitator) always keeps the
    /// joint limits, whatever this says: its output is sent to a robot.
    pub clamping: bool,
}

/// Errors of a task table.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum TableError {
    /// The table has no equality level.
    #[error("task table {phase}: no equality level")]
    NoLevel {
        /// The table's phase.
        phase: SupportPhase,
    },
    /// A level has no rows.
    #[error("task table {phase}: level {level:?} has no rows")]
    EmptyLevel {
        /// The table's phase.
        phase: SupportPhase,
        /// The level's name.
        level: String,
    },
    /// A point task tracks no coordinate.
    #[error("task table {phase}: task {task:?} tracks no axis")]
    NoAxis {
        /// The table's phase.
        phase: SupportPhase,
        /// The task's name.
        task: String,
    },
    /// Two tasks share a name (the solver addresses tasks by name).
    #[error("task table {phase}: task {task:?} appears twice")]
    DuplicateTask {
        /// The table's phase.
        phase: SupportPhase,
        /// The task's name.
        task: String,
    },
    /// A number (κ, λ or lift) is NaN or infinite.
    #[error("task table {phase}: {field} of {task:?} is not finite")]
    NotFinite {
        /// The table's phase.
        phase: SupportPhase,
        /// The task's name (or the gradient kind).
        task: String,
        /// Which number.
        field: &'static str,
    },
    /// A constraint's margin is negative or not finite.
    #[error("task table {phase}: margin {margin} m of {constraint:?} is not finite and ≥ 0")]
    InvalidMargin {
        /// The table's phase.
        phase: SupportPhase,
        /// The constraint's name.
        constraint: String,
        /// The margin (m).
        margin: f64,
    },
    /// A ZMP constraint's moment bound is not finite and > 0, or its polygon has room for
    /// fewer than 4 vertices.
    #[error(
        "task table {phase}: ZMP bound {max_yaw_moment} N·m must be finite and > 0, with room for >= 4 vertices (has {vertices})"
    )]
    InvalidZmpBound {
        /// The table's phase.
        phase: SupportPhase,
        /// The moment bound (N·m).
        max_yaw_moment: f64,
        /// The polygon's room.
        vertices: usize,
    },
}

impl TaskTable {
    /// The solver stack shape over `dof` joints: one level per [`Level`], one named task (see
    /// [`Task::name`], [`Constraint::name`]) per [`Task`] and [`Constraint`].
    pub fn shape(&self, dof: usize) -> StackShape {
        self.levels
            .iter()
            .fold(StackShape::new(dof), |shape, level| {
                let tasks: Vec<(String, usize)> =
                    level.tasks.iter().map(|t| (t.name(), t.rows())).collect();
                let constraints: Vec<(String, usize)> = (level.constraints.iter())
                    .map(|c| (c.name(), c.rows()))
                    .collect();
                shape.with_mixed_level(&level.name, &borrowed(&tasks), &borrowed(&constraints))
            })
    }

    /// Checks the table: at least one level, every level with rows, every point task with an
    /// axis, task names unique, every number finite.
    // One function on purpose (~90 lines): one independent check after another, in the order
    // of the docs above.
    pub fn validate(&self) -> Result<(), TableError> {
        let phase = self.phase;
        if self.levels.is_empty() {
            return Err(TableError::NoLevel { phase });
        }
        let mut names = HashSet::new();
        for level in &self.levels {
            if level.rows() == 0 {
                return Err(TableError::EmptyLevel {
                    phase,
                    level: level.name.clone(),
                });
            }
            for task in &level.tasks {
                let name = task.name();
                let not_finite = |field| TableError::NotFinite {
                    phase,
                    task: name.clone(),
                    field,
                };
                match task {
                    Task::ComXY(goal) if goal.numbers().any(|v| !v.is_finite()) => {
                        return Err(not_finite("CoM goal"));
                    }
                    Task::Point { axes, .. } if axes.count() == 0 => {
                        return Err(TableError::NoAxis { phase, task: name });
                    }
                    Task::Point {
                        target: PointTarget::Held { lift } | PointTarget::Footstep { lift },
                        ..
                    } if !lift.is_finite() => return Err(not_finite("lift")),
                    Task::Point {
                        target: PointTarget::Standing { lower },
                        ..
                    } if !lower.is_finite() => return Err(not_finite("lower")),
                    Task::Orientation {
                        target:
                            OrientationTarget::Upright { lean } | OrientationTarget::Facing { lean },
                        ..
                    } if !lean.is_finite() => return Err(not_finite("lean")),
                    Task::Point { offset, .. } if offset.iter().any(|v| !v.is_finite()) => {
                        return Err(not_finite("offset"));
                    }
                    Task::ComXY(_)
                    | Task::ComHeight
                    | Task::Point { .. }
                    | Task::Orientation { .. } => {}
                }
                if !names.insert(name.clone()) {
                    return Err(TableError::DuplicateTask { phase, task: name });
                }
            }
            for constraint in &level.constraints {
                let name = constraint.name();
                let margin = match *constraint {
                    Constraint::Distance { margin, .. } => margin,
                    Constraint::Zmp {
                        margin,
                        max_yaw_moment,
                        vertices,
                    } => {
                        if !(max_yaw_moment.is_finite() && max_yaw_moment > 0.0 && vertices >= 4) {
                            return Err(TableError::InvalidZmpBound {
                                phase,
                                max_yaw_moment,
                                vertices,
                            });
                        }
                        margin
                    }
                };
                if !(margin.is_finite() && margin >= 0.0) {
                    return Err(TableError::InvalidMargin {
                        phase,
                        constraint: name,
                        margin,
                    });
                }
                if !names.insert(name.clone()) {
                    return Err(TableError::DuplicateTask { phase, task: name });
                }
            }
        }
        if let Some(g) = self.gradients.iter().find(|g| !g.kappa.is_finite()) {
            return Err(TableError::NotFinite {
                phase,
                task: format!("{:?}", g.kind),
                field: "kappa",
            });
        }
        Ok(())
    }
}

/// The name Table I gives a foot.
fn foot_name(foot: Side) -> &'static str {
    match foot {
        Side::Right => "RFoot",
        Side::Left => "LFoot",
    }
}

/// `(name, rows)` pairs with borrowed names, as [`StackShape`] takes them.
fn borrowed(named: &[(String, usize)]) -> Vec<(&str, usize)> {
    named.iter().map(|(n, r)| (n.as_str(), *r)).collect()
}

/// The task tables of all 11 phases.
#[derive(Clone, Debug, PartialEq)]
pub struct TaskTables {
    /// Indexed by [`SupportPhase::index`].
    tables: Vec<TaskTable>,
}

impl TaskTables {
    /// Table I for `profile` with the paper's λ = 15 mm and ρ = 30 mm.
    pub fn paper(profile: &BipedProfile) -> Self {
        Self::from_config(&PhaseConfig::default(), profile)
    }

    /// Table I for `profile` with λ and ρ from `config`.
    pub fn from_config(config: &PhaseConfig, profile: &BipedProfile) -> Self {
        Self::build(|phase| TaskTable::paper(phase, config, profile))
    }

    /// [`TaskTable::contact_first`] for every phase, with λ and ρ from `config`: the tables the
    /// imitator uses by default.
    pub fn contact_first(config: &PhaseConfig, profile: &BipedProfile) -> Self {
        Self::build(|phase| TaskTable::contact_first(phase, config, profile))
    }

    /// [`TaskTable::executable`] for every phase, with λ and ρ from `config`.
    pub fn executable(config: &PhaseConfig, profile: &BipedProfile) -> Self {
        Self::build(|phase| TaskTable::executable(phase, config, profile))
    }

    fn build(table: impl Fn(SupportPhase) -> TaskTable) -> Self {
        Self {
            tables: SupportPhase::ALL
                .iter()
                .map(|&phase| table(phase))
                .collect(),
        }
    }

    /// The table of `phase`.
    pub fn table(&self, phase: SupportPhase) -> &TaskTable {
        &self.tables[phase.index()]
    }

    /// Replaces the table of `table.phase` after validating it.
    pub fn set(&mut self, table: TaskTable) -> Result<(), TableError> {
        table.validate()?;
        let index = table.phase.index();
        self.tables[index] = table;
        Ok(())
    }

    /// Adds the hand supports of [`crate::imitation::poubel::hand_support`] to every table: a point task per hand
    /// ([`PointTarget::HandContact`]) in a `"hand contact"` level of their own, right below the
    /// feet's `"contact"` level (at the top when a table has none): a hand rests on a surface
    /// without ever pulling a standing foot off the ground, and above balance, so the CoM moves
    /// with the hands held.
    pub fn add_hand_supports(&mut self, profile: &BipedProfile) {
        for table in &mut self.tables {
            let tasks = Side::BOTH.map(|side| Task::Point {
                frame: profile.hands[side.index()].clone(),
                offset: [0.0; 3],
                axes: Axes::XYZ,
                target: PointTarget::HandContact(side),
            });
            let feet = table.levels.first().is_some_and(|l| l.name == "contact");
            let level = Level::of_tasks("hand contact", tasks.into());
            table.levels.insert(usize::from(feet), level);
        }
    }

    /// Adds balance that sees the arms' dynamics to every table: a `"dynamics"` level with a
    /// [`Constraint::Zmp`] right below the levels that place the feet and the CoM (`"contact"`,
    /// `"hand contact"`, `"balance"` and `"collision"`), above the posture, the swing foot and
    /// the hands. The CoM task keeps the statics, its reference shaped so that the cart-table
    /// ZMP stays near it ([`crate::imitation::shaping`]); this level bounds what the arms' motion adds:
    /// the ZMP of the CoM plus the arms' momentum rate stays inside the soles' contact area
    /// (margin 0: the profile's outline is already the area the robot can count on, the NAO's
    /// its pressure sensors' hull inside the real sole), and the arms' vertical moment within
    /// [`BipedProfile::max_floor_yaw_moment`]. A hand that would start or stop faster than
    /// that allows is held back by it.
    ///
    /// The rows see the arms' joints only (those that turn a hand but not the torso). Seeing
    /// every joint, the legs' frame-to-frame steps (contact settling, the active set's
    /// switches) read as large accelerations at 1/Δt², the level fought them, and the NAO's
    /// hands and steps came out later (CMU 07_04: hand lag 0.11 → 1.6 s), and fewer runs
    /// stood in the physics judge.
    pub fn add_zmp_balance(&mut self, profile: &BipedProfile) {
        let zmp = Constraint::Zmp {
            margin: 0.0,
            max_yaw_moment: profile.max_floor_yaw_moment(),
            vertices: profile.feet.iter().map(|f| f.outline.len()).sum(),
        };
        for table in &mut self.tables {
            let above = ["contact", "hand contact", "balance", "collision"];
            let at = (table.levels.iter())
                .position(|l| !above.contains(&l.name.as_str()))
                .unwrap_or(table.levels.len());
            let level = Level {
                name: "dynamics".to_owned(),
                tasks: Vec::new(),
                constraints: vec![zmp.clone()],
            };
            table.levels.insert(at, level);
        }
    }

    /// Adapts the executable tables to walking
    /// ([`FootstepConfig::follow`](crate::imitation::walking::footsteps::FootstepConfig::follow)): in single support
    /// and while a foot moves the CoM goes over the centre of the support sole's contact rectangle
    /// ([`BipedProfile::sole_centre`]) instead of near its inner edge, and the "collision" level
    /// moves above "balance". A walking step carries the swing foot across, and with the CoM 15 mm
    /// from the inner edge of the NAO's 53 mm-wide contact area (its margin then) the stance foot
    /// rocked onto that edge in the physics judge; over the centre it does not. The longer
    /// weight shift
    /// brings the torso nearer the arms, which balance, its goal inside a wide area, can make room
    /// for; without walking the shorter shift keeps the robot quick to follow short one-leg
    /// stances.
    pub fn centre_stances_for_walking(&mut self, profile: &BipedProfile) {
        for table in &mut self.tables {
            let root = table.model_root;
            let tasks = table.levels.iter_mut().flat_map(|l| l.tasks.iter_mut());
            for task in tasks {
                match task {
                    Task::ComXY(ComGoal::SupportPoint(p)) => *p = profile.sole_centre(root),
                    Task::ComXY(ComGoal::OtherPoint(p)) => *p = profile.sole_centre(root.other()),
                    _ => {}
                }
            }
            let at = |name: &str| table.levels.iter().position(|l| l.name == name);
            if let (Some(collision), Some(balance)) = (at("collision"), at("balance"))
                && collision > balance
            {
                let level = table.levels.remove(collision);
                table.levels.insert(balance, level);
            }
        }
    }

    /// All tables, in the row order of Table I ([`SupportPhase::ALL`]).
    pub fn iter(&self) -> impl Iterator<Item = &TaskTable> {
        self.tables.iter()
    }
}
