//! Prioritized-IK benchmark problems (schema `nao-prioritized-ik-benchmark/1`, the files of
//! `tests/data/bench/` in the repository): reading a problem file ([`Problem::from_json`]) and
//! solving it frame by frame with the position-level driver following the file's protocol
//! ([`Runner`]). Used by the `solve` example, the benchmark test and the `bench_problems`
//! benchmark.
//!
//! A problem names the NAO's joints in NAOqi order, its joint limits, a start and a reference
//! posture, priority levels of tasks (the CoM ground projection, points on links with some axes
//! fixed or following per-frame targets, and a posture task that becomes the lowest-priority
//! joint-tracking gradient) and the driver's stopping rule. Positions are metres in the right
//! sole's frame (the benchmark's world), angles radians.
//!
//! ```
//! use taskstack::problem::{Problem, Runner};
//!
//! let path = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/bench/problem_rs.json");
//! let problem = Problem::from_json(&std::fs::read_to_string(path)?)?;
//! let mut runner = Runner::new(&problem)?;
//! let mut q = problem.q_init.clone();
//! let result = runner.solve_frame(0, &mut q)?;
//! assert!(result.errors.iter().all(|e| *e <= 1e-4)); // metres
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use std::time::Instant;

use nalgebra::{Point3, Vector3};
use serde_json::Value;
use thiserror::Error;

use crate::human::Side;
use crate::model::{Axis, Model, ModelError};
use crate::robots::nao;
use crate::solver::driver::{DriverSettings, PositionDriver, StopReason};
use crate::solver::{JointBounds, Method, Settings, Solver, SolverError};
use crate::tasks::{self, ComPolygonTask, ComTask, PositionTask, TaskError, TaskSet, convex_hull};

/// The schema this module reads.
pub const SCHEMA: &str = "nao-prioritized-ik-benchmark/1";

/// Gain of the posture task (lowest priority, a gradient task): each iteration moves this
/// fraction of the way to `q_ref` inside the null space of every level.
const POSTURE_GAIN: f64 = 0.1;

/// Errors of reading or solving a problem.
#[derive(Debug, Error)]
pub enum ProblemError {
    /// The text is not JSON.
    #[error("not JSON: {0}")]
    Json(#[from] serde_json::Error),
    /// A field is missing, of the wrong type or out of range.
    #[error("`{field}`: {reason}")]
    Invalid {
        /// Path of the field, e.g. `points.l_hand.offset`.
        field: String,
        /// What is wrong with it.
        reason: String,
    },
    /// A joint or frame the problem names is not in the model.
    #[error(transparent)]
    Model(#[from] ModelError),
    /// Building or updating a task failed.
    #[error(transparent)]
    Task(#[from] TaskError),
    /// The solver refused the stack or the bounds.
    #[error(transparent)]
    Solver(#[from] SolverError),
}

fn invalid(field: impl Into<String>, reason: impl Into<String>) -> ProblemError {
    ProblemError::Invalid {
        field: field.into(),
        reason: reason.into(),
    }
}

/// What a task row block tracks.
#[derive(Debug, Clone)]
enum Target {
    /// CoM ground projection (x, y), m.
    Com([f64; 2]),
    /// A point's constrained axes at a fixed target, m.
    Fixed(Vec<f64>),
    /// A point's x, y, z at a per-frame target, m.
    PerFrame(Vec<[f64; 3]>),
}

#[derive(Debug, Clone)]
struct ProblemTask {
    name: String,
    /// Point: frame name and offset in it (m); `None` for the CoM.
    point: Option<(String, Vector3<f64>)>,
    axes: Vec<Axis>,
    target: Target,
    /// Level index.
    level: usize,
}

/// A benchmark problem, ready to solve.
#[derive(Debug, Clone)]
pub struct Problem {
    /// `problem` and `variant` fields, e.g. "RS main".
    pub label: String,
    /// The file's joint order (NAOqi names, both hip yaw-pitch joints).
    pub joint_order: Vec<String>,
    /// Index in `joint_order` of each model variable (RHipYawPitch maps to LHipYawPitch).
    order_to_variable: Vec<usize>,
    /// Start posture, one entry per model variable (rad).
    pub q_init: Vec<f64>,
    q_ref: Vec<f64>,
    /// The file's joint limits, per model variable (rad).
    pub bounds: JointBounds,
    /// Number of frames to solve.
    pub frames: usize,
    /// Driver settings from the file's stopping rule.
    pub settings: DriverSettings,
    /// How each iteration's stack is solved: strict priorities (default, what the files ask
    /// for) or weighted damped least squares, to compare the two.
    pub method: Method,
    /// Solve the CoM task as an inequality instead (`None`, what the files ask for, by default):
    /// its ground projection inside the support polygon shrunk by this margin (m), at the CoM
    /// task's level. The support polygon is the convex hull of the outlines of the soles on the
    /// ground (within 1 mm) at `q_init`.
    pub com_polygon_margin: Option<f64>,
    tasks: Vec<ProblemTask>,
    /// Name of each level, highest priority first.
    pub level_names: Vec<String>,
    model: Model,
}

fn floats(v: &Value, field: &str) -> Result<Vec<f64>, ProblemError> {
    let numbers = v
        .as_array()
        .ok_or_else(|| invalid(field, "expected an array of numbers"))?
        .iter()
        .map(|x| x.as_f64().filter(|x| x.is_finite()))
        .collect::<Option<Vec<f64>>>();
    numbers.ok_or_else(|| invalid(field, "expected finite numbers"))
}

fn floats_n<const N: usize>(v: &Value, field: &str) -> Result<[f64; N], ProblemError> {
    let values = floats(v, field)?;
    values
        .try_into()
        .map_err(|v: Vec<f64>| invalid(field, format!("{} numbers, expected {N}", v.len())))
}

fn strings(v: &Value, field: &str) -> Result<Vec<String>, ProblemError> {
    let names = v
        .as_array()
        .ok_or_else(|| invalid(field, "expected an array of strings"))?
        .iter()
        .map(|x| x.as_str().map(str::to_owned))
        .collect::<Option<Vec<String>>>();
    names.ok_or_else(|| invalid(field, "expected strings"))
}

fn axes(v: &Value, field: &str) -> Result<Vec<Axis>, ProblemError> {
    strings(v, field)?
        .iter()
        .map(|name| match name.as_str() {
            "x" => Ok(Axis::X),
            "y" => Ok(Axis::Y),
            "z" => Ok(Axis::Z),
            _ => Err(invalid(field, format!("unknown axis {name:?}"))),
        })
        .collect()
}

/// `values` (in the file's joint order `names`, read from `field`) as one entry per model
/// variable.
fn to_model(names: &[String], values: &[f64], field: &str) -> Result<Vec<f64>, ProblemError> {
    if values.len() != names.len() {
        let reason = format!("{} values for {} joints", values.len(), names.len());
        return Err(invalid(field, reason));
    }
    nao::VARIABLES
        .iter()
        .map(|v| {
            let i = names.iter().position(|j| j == v);
            i.map(|i| values[i])
                .ok_or_else(|| invalid("joint_order", format!("lacks {v}")))
        })
        .collect()
}

impl Problem {
    /// Reads a problem file. The robot is the built-in DH NAO rooted at the right sole (the
    /// benchmark's world frame); points given as URDF link + offset map to the named frames of
    /// the same name, whose orientation is the URDF link's.
    ///
    /// # Errors
    /// [`ProblemError`] naming the field at fault: another schema, a missing or mistyped field,
    /// lists of the wrong length, unknown joints, frames, axes or task kinds, bad limits.
    pub fn from_json(text: &str) -> Result<Self, ProblemError> {
        let doc: Value = serde_json::from_str(text)?;
        if doc["schema"] != SCHEMA {
            return Err(invalid(
                "schema",
                format!("{} is not {SCHEMA}", doc["schema"]),
            ));
        }
        let model = nao::rfoot();
        let joint_order = strings(&doc["joint_order"], "joint_order")?;
        let order_to_variable = joint_order
            .iter()
            .map(|name| match name.as_str() {
                "RHipYawPitch" => model.variable_index("LHipYawPitch"),
                name => model.variable_index(name),
            })
            .collect::<Result<_, _>>()?;
        let read =
            |field: &str, value: &Value| to_model(&joint_order, &floats(value, field)?, field);
        let lower = read("joint_limits.lower", &doc["joint_limits"]["lower"])?;
        let upper = read("joint_limits.upper", &doc["joint_limits"]["upper"])?;
        let bounds = JointBounds::new(&lower, &upper)?;
        let q_init = read("q_init", &doc["q_init"])?;
        let q_ref = read("q_ref", &doc["q_ref"])?;
        let frames = doc["frames"]["count"]
            .as_u64()
            .ok_or_else(|| invalid("frames.count", "expected a count"))?;
        let frames = usize::try_from(frames).map_err(|_| invalid("frames.count", "too large"))?;
        let (tasks, level_names) = read_levels(&doc, frames)?;
        let stop = &doc["protocol"]["stop"];
        let settings = DriverSettings {
            tolerance: stop["task_tol_m"].as_f64().unwrap_or(1e-4),
            stall_tolerance: stop["stall_tol_m"].as_f64().unwrap_or(1e-7),
            max_iterations: stop["max_iter"].as_u64().unwrap_or(50) as usize,
            ..DriverSettings::default()
        };
        Ok(Self {
            label: format!(
                "{} {}",
                doc["problem"].as_str().unwrap_or("?"),
                doc["variant"].as_str().unwrap_or("")
            ),
            joint_order,
            order_to_variable,
            q_init,
            q_ref,
            bounds,
            frames,
            settings,
            method: Method::Prioritized,
            com_polygon_margin: None,
            tasks,
            level_names,
            model,
        })
    }

    /// Task names in stack order (the order of [`FrameResult::errors`]).
    pub fn task_names(&self) -> Vec<&str> {
        self.tasks.iter().map(|t| t.name.as_str()).collect()
    }

    /// Level of each task (0 is the highest priority), in stack order.
    pub fn task_levels(&self) -> Vec<usize> {
        self.tasks.iter().map(|t| t.level).collect()
    }

    /// `q` (one entry per model variable) in the file's `joint_order`.
    pub fn to_joint_order(&self, q: &[f64]) -> Vec<f64> {
        self.order_to_variable.iter().map(|&v| q[v]).collect()
    }
}

/// The file's point `name`: link and offset in it (m).
fn point(doc: &Value, name: &str) -> Result<(String, Vector3<f64>), ProblemError> {
    let p = &doc["points"][name];
    let field = format!("points.{name}");
    let link = p["link"]
        .as_str()
        .ok_or_else(|| invalid(format!("{field}.link"), "expected a link name"))?;
    let offset = floats_n::<3>(&p["offset"], &format!("{field}.offset"))?;
    Ok((link.to_owned(), Vector3::from(offset)))
}

/// The per-frame targets of point `name` (m), at least `frames` of them.
fn per_frame(doc: &Value, name: &str, frames: usize) -> Result<Vec<[f64; 3]>, ProblemError> {
    let field = format!("frames.targets.{name}");
    let targets = doc["frames"]["targets"][name]
        .as_array()
        .ok_or_else(|| invalid(&field, "expected one target per frame"))?
        .iter()
        .map(|t| floats_n::<3>(t, &field))
        .collect::<Result<Vec<_>, _>>()?;
    match targets.len() >= frames.max(1) {
        true => Ok(targets),
        false => Err(invalid(
            field,
            format!("{} targets for {frames} frames", targets.len()),
        )),
    }
}

/// The tasks of one level definition `def` (level `level`); `None` for the posture task.
fn read_level(
    doc: &Value,
    def: &Value,
    level: usize,
    frames: usize,
) -> Result<Option<Vec<ProblemTask>>, ProblemError> {
    let name = def["name"].as_str().unwrap_or("level").to_owned();
    let field = format!("tasks.{name}");
    let task = |name: &str, point, axes, target| ProblemTask {
        name: name.to_owned(),
        point,
        axes,
        target,
        level,
    };
    Ok(Some(match def["kind"].as_str() {
        Some("com") => {
            let xy = floats_n::<2>(&def["target"], &format!("{field}.target"))?;
            vec![task(&name, None, vec![Axis::X, Axis::Y], Target::Com(xy))]
        }
        Some("points") if def["rows"].is_array() => {
            let rows = def["rows"].as_array().into_iter().flatten();
            rows.map(|row| {
                let p = row["point"]
                    .as_str()
                    .ok_or_else(|| invalid(format!("{field}.rows"), "a row without a point"))?;
                let axes = axes(&row["axes"], &format!("{field}.rows.{p}.axes"))?;
                let values = floats(&row["target"], &format!("{field}.rows.{p}.target"))?;
                if values.len() != axes.len() {
                    let reason = format!("{} values for {} axes", values.len(), axes.len());
                    return Err(invalid(format!("{field}.rows.{p}.target"), reason));
                }
                Ok(task(p, Some(point(doc, p)?), axes, Target::Fixed(values)))
            })
            .collect::<Result<_, _>>()?
        }
        Some("points") => {
            let axes = axes(&def["axes"], &format!("{field}.axes"))?;
            strings(&def["points"], &format!("{field}.points"))?
                .iter()
                .map(|p| {
                    let target = Target::PerFrame(per_frame(doc, p, frames)?);
                    Ok(task(p, Some(point(doc, p)?), axes.clone(), target))
                })
                .collect::<Result<_, ProblemError>>()?
        }
        // The posture task is the lowest priority: a joint-tracking gradient task.
        Some("posture") => return Ok(None),
        other => {
            return Err(invalid(
                format!("{field}.kind"),
                format!("unknown kind {other:?}"),
            ));
        }
    }))
}

/// Every task of the file in priority order, and the name of each level.
fn read_levels(
    doc: &Value,
    frames: usize,
) -> Result<(Vec<ProblemTask>, Vec<String>), ProblemError> {
    let mut defs: Vec<&Value> = doc["tasks"]
        .as_array()
        .ok_or_else(|| invalid("tasks", "expected an array of levels"))?
        .iter()
        .collect();
    defs.sort_by_key(|t| t["priority"].as_u64().unwrap_or(u64::MAX));
    let mut tasks = Vec::new();
    let mut level_names = Vec::new();
    for def in defs {
        if let Some(level) = read_level(doc, def, level_names.len(), frames)? {
            level_names.push(def["name"].as_str().unwrap_or("level").to_owned());
            tasks.extend(level);
        }
    }
    Ok((tasks, level_names))
}

/// The solver side of a problem: its tasks as a [`TaskSet`], the solver and the driver.
#[derive(Debug)]
pub struct Runner<'p> {
    problem: &'p Problem,
    set: TaskSet<'p>,
    solver: Solver,
    driver: PositionDriver,
}

/// Outcome of one frame.
#[derive(Debug, Clone)]
pub struct FrameResult {
    /// Driver iterations used.
    pub iterations: usize,
    /// Why the driver stopped.
    pub stop: StopReason,
    /// Error norm of every task, in [`Problem::task_names`] order (m).
    pub errors: Vec<f64>,
    /// Wall time: targets set + all iterations + stop test (µs).
    pub micros: f64,
}

/// The ready-made task of a problem task, at its first frame's target.
fn ready_made(model: &Model, task: &ProblemTask) -> Result<Box<dyn tasks::Task>, ProblemError> {
    let target = match &task.target {
        Target::Com(xy) => return Ok(Box::new(ComTask::ground(model, *xy)?)),
        Target::Fixed(values) => {
            let mut target = Vector3::zeros();
            for (&axis, &v) in task.axes.iter().zip(values) {
                target[axis as usize] = v;
            }
            target
        }
        // `per_frame` checked that there is at least one target.
        Target::PerFrame(targets) => Vector3::from(targets[0]),
    };
    let point = match &task.point {
        Some((frame, offset)) => PositionTask::new(model, frame, target)?
            .with_offset(*offset)?
            .axes(&task.axes)
            .named(&task.name),
        None => return Err(invalid(&task.name, "a point task without a point")),
    };
    Ok(Box::new(point))
}

/// The CoM kept inside the convex hull of the outlines of the soles on the ground at the
/// problem's start posture, shrunk by `margin` (m).
fn support_polygon_task(problem: &Problem, margin: f64) -> Result<ComPolygonTask, ProblemError> {
    let model = &problem.model;
    let mut data = model.new_data();
    model.forward_kinematics(&mut data, &problem.q_init)?;
    let mut corners = Vec::new();
    for side in [Side::Left, Side::Right] {
        let sole = model.frame_id(nao::sole(side))?;
        let placement = model.placement_in_world(&data, &Default::default(), sole)?;
        if placement.translation.vector.z.abs() > 1e-3 {
            continue;
        }
        for [x, y] in nao::sole_outline(side) {
            let p = placement.transform_point(&Point3::new(x, y, 0.0));
            corners.push([p.x, p.y]);
        }
    }
    let mut hull = Vec::new();
    convex_hull(&mut corners, &mut hull);
    Ok(ComPolygonTask::new(
        model,
        hull.len().max(3),
        &hull,
        margin,
    )?)
}

impl<'p> Runner<'p> {
    /// The task set, solver and driver of `problem`.
    ///
    /// # Errors
    /// [`ProblemError`] when a task names a frame the model lacks or the solver refuses the
    /// stack.
    pub fn new(problem: &'p Problem) -> Result<Self, ProblemError> {
        let model = &problem.model;
        let mut set = TaskSet::new(model);
        for (level, name) in problem.level_names.iter().enumerate() {
            let in_level = || problem.tasks.iter().filter(move |t| t.level == level);
            // With a polygon margin, the CoM task becomes the polygon inequality.
            let as_polygon = |t: &&ProblemTask| {
                matches!(t.target, Target::Com(_)) && problem.com_polygon_margin.is_some()
            };
            let tasks = in_level()
                .filter(|t| !as_polygon(t))
                .map(|t| ready_made(model, t))
                .collect::<Result<_, _>>()?;
            let mut inequalities: Vec<Box<dyn tasks::InequalityTask>> = Vec::new();
            if let Some(margin) = problem.com_polygon_margin
                && in_level().any(|t| as_polygon(&t))
            {
                inequalities.push(Box::new(support_polygon_task(problem, margin)?));
            }
            set = set.mixed_level(name, tasks, inequalities);
        }
        let set = set.posture_gradient(POSTURE_GAIN, &problem.q_ref)?;
        let settings = Settings {
            method: problem.method,
            ..Settings::default()
        };
        let solver = Solver::with_settings(&set.shape(), settings)?;
        let driver = PositionDriver::new(&solver, problem.settings)?;
        Ok(Self {
            problem,
            set,
            solver,
            driver,
        })
    }

    /// Solves frame `frame` (0-based), warm-started from `q` (one entry per model variable,
    /// rad; updated in place).
    ///
    /// # Errors
    /// [`ProblemError::Invalid`] when `frame` is not below [`Problem::frames`]; the driver's
    /// errors (wrong `q` length, non-finite values).
    pub fn solve_frame(
        &mut self,
        frame: usize,
        q: &mut [f64],
    ) -> Result<FrameResult, ProblemError> {
        let start = Instant::now();
        if frame >= self.problem.frames {
            let reason = format!("frame {frame} of {}", self.problem.frames);
            return Err(invalid("frames.count", reason));
        }
        for task in &self.problem.tasks {
            if let Target::PerFrame(targets) = &task.target {
                // `per_frame` checked that there are `frames` targets.
                self.set.task_mut::<PositionTask>(&task.name)?.target =
                    Vector3::from(targets[frame]);
            }
        }
        let report = self
            .driver
            .run(&mut self.solver, &mut self.set, q, &self.problem.bounds)?;
        Ok(FrameResult {
            iterations: report.iterations,
            stop: report.stop,
            errors: report.task_errors().to_vec(),
            micros: start.elapsed().as_secs_f64() * 1e6,
        })
    }
}

/// A problem solved over its frames, possibly several times ([`solve_frames`]).
#[derive(Debug, Clone)]
pub struct ProblemSolution {
    /// Per frame of the last run: the posture (rad, in [`Problem::joint_order`]) and the
    /// frame's result.
    pub frames: Vec<(Vec<f64>, FrameResult)>,
    /// Largest error of each task over the last run (m), in [`Problem::task_names`] order.
    pub worst: Vec<f64>,
    /// Joint positions outside their limits over the last run (joint × frame).
    pub limit_violations: usize,
    /// Frames of the last run whose driver converged.
    pub converged_frames: usize,
    /// Driver iterations over the last run.
    pub iterations: usize,
    /// Wall time of every frame of every run (µs), ascending.
    pub times: Vec<f64>,
}

impl ProblemSolution {
    /// The time of rank `round((n − 1) p)` in [`ProblemSolution::times`] (µs; 0 without frames).
    pub fn time_quantile(&self, p: f64) -> f64 {
        let rank = ((self.times.len().max(1) - 1) as f64 * p).round() as usize;
        self.times.get(rank).copied().unwrap_or(0.0)
    }

    /// The result document of `problem` solved `repeats` times: per frame the posture, every
    /// task's error (m), the iterations and the stop reason; a summary with the worst errors,
    /// the limit violations and the time per frame (median, p99, max, µs).
    pub fn to_json(&self, problem: &Problem, repeats: usize) -> Value {
        let names = problem.task_names();
        let per_task = |values: &[f64]| -> serde_json::Map<String, Value> {
            (names.iter().zip(values))
                .map(|(n, v)| (n.to_string(), Value::from(*v)))
                .collect()
        };
        let frames: Vec<Value> = (self.frames.iter().enumerate())
            .map(|(frame, (q, result))| {
                serde_json::json!({
                    "frame": frame,
                    "q": q,
                    "errors": per_task(&result.errors),
                    "iterations": result.iterations,
                    "stop": format!("{:?}", result.stop).to_lowercase(),
                })
            })
            .collect();
        let top_level_worst = (self.worst.iter().zip(problem.task_levels()))
            .filter(|(_, level)| *level == 0)
            .fold(0.0_f64, |m, (w, _)| m.max(*w));
        let count = self.frames.len();
        serde_json::json!({
            "problem": problem.label,
            "joint_order": problem.joint_order,
            "levels": problem.level_names,
            "frames": frames,
            "summary": {
                "frames": count,
                "repeats": repeats,
                "converged_frames": self.converged_frames,
                "mean_iterations": self.iterations as f64 / count.max(1) as f64,
                "max_error_m": per_task(&self.worst),
                "max_error_top_level_m": top_level_worst,
                "limit_violations": self.limit_violations,
                "time_per_frame_us": {
                    "median": self.time_quantile(0.5),
                    "p99": self.time_quantile(0.99),
                    "max": self.time_quantile(1.0),
                },
            },
        })
    }
}

/// Solves the first `count` frames of `problem` (all of them if fewer) `repeats` times, each run
/// warm-started frame by frame from [`Problem::q_init`]; the times pool all runs, the rest is
/// the last run's.
///
/// # Errors
/// [`Runner::new`]'s and [`Runner::solve_frame`]'s.
pub fn solve_frames(
    problem: &Problem,
    count: usize,
    repeats: usize,
) -> Result<ProblemSolution, ProblemError> {
    let count = count.min(problem.frames);
    let mut runner = Runner::new(problem)?;
    let mut solution = ProblemSolution {
        frames: Vec::with_capacity(count),
        worst: vec![0.0; problem.task_names().len()],
        limit_violations: 0,
        converged_frames: 0,
        iterations: 0,
        times: Vec::with_capacity(count * repeats),
    };
    for repeat in 0..repeats {
        let mut q = problem.q_init.clone();
        let last = repeat + 1 == repeats;
        for frame in 0..count {
            let result = runner.solve_frame(frame, &mut q)?;
            solution.times.push(result.micros);
            if !last {
                continue;
            }
            let bounds = problem.bounds.lower().iter().zip(problem.bounds.upper());
            solution.limit_violations += (q.iter().zip(bounds))
                .filter(|(v, (lo, hi))| *v < lo || *v > hi)
                .count();
            for (w, e) in solution.worst.iter_mut().zip(&result.errors) {
                *w = w.max(*e);
            }
            solution.converged_frames += usize::from(result.stop == StopReason::Converged);
            solution.iterations += result.iterations;
            solution.frames.push((problem.to_joint_order(&q), result));
        }
    }
    solution.times.sort_by(f64::total_cmp);
    Ok(solution)
}
