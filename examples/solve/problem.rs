//! The NAO prioritized-IK benchmark problems of `tests/data/bench/` (schema
//! `nao-prioritized-ik-benchmark/1`): reading a file, and solving it frame by frame with the
//! position-level driver following the file's protocol. Shared by the `solve` example and the
//! `bench_problems` benchmark.

use std::collections::BTreeMap;
use std::time::Instant;

use nalgebra::Vector3;
use serde_json::Value;
use taskstack::model::{Axis, Model};
use taskstack::robots::nao;
use taskstack::solver::driver::{DriverSettings, PositionDriver, StopReason};
use taskstack::solver::{JointBounds, Solver};
use taskstack::tasks::{self, ComTask, PositionTask, TaskSet};

/// Gain of the posture task (lowest priority, a gradient task): each iteration moves this
/// fraction of the way to `q_ref` inside the null space of every level.
const POSTURE_GAIN: f64 = 0.1;

type Error = Box<dyn std::error::Error>;

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
struct Task {
    name: String,
    /// Point: frame name and offset in it (m); `None` for the CoM.
    point: Option<(String, Vector3<f64>)>,
    axes: Vec<Axis>,
    target: Target,
    /// Level index.
    level: usize,
}

/// A benchmark problem, ready to solve.
pub struct Problem {
    /// `problem` and `variant` fields, e.g. "RS main".
    pub label: String,
    pub joint_order: Vec<String>,
    /// Index in `joint_order` of each model variable (RHipYawPitch maps to LHipYawPitch).
    order_to_variable: Vec<usize>,
    pub q_init: Vec<f64>,
    q_ref: Vec<f64>,
    pub bounds: JointBounds,
    pub frames: usize,
    pub settings: DriverSettings,
    tasks: Vec<Task>,
    /// Name of each level, for the report.
    pub level_names: Vec<String>,
    model: Model,
}

fn floats(v: &Value, what: &str) -> Result<Vec<f64>, Error> {
    v.as_array()
        .ok_or_else(|| format!("{what}: expected an array"))?
        .iter()
        .map(|x| {
            x.as_f64()
                .ok_or_else(|| format!("{what}: expected numbers").into())
        })
        .collect()
}

fn strings(v: &Value, what: &str) -> Result<Vec<String>, Error> {
    v.as_array()
        .ok_or_else(|| format!("{what}: expected an array"))?
        .iter()
        .map(|x| {
            x.as_str()
                .map(str::to_owned)
                .ok_or_else(|| format!("{what}: expected strings").into())
        })
        .collect()
}

fn axis(name: &str) -> Result<Axis, Error> {
    match name {
        "x" => Ok(Axis::X),
        "y" => Ok(Axis::Y),
        "z" => Ok(Axis::Z),
        _ => Err(format!("unknown axis {name:?}").into()),
    }
}

impl Problem {
    /// Reads a problem file. The robot is the built-in DH NAO rooted at the right sole (the
    /// benchmark's world frame); points given as URDF link + offset map to the named frames of
    /// the same name, whose orientation is the URDF link's.
    pub fn from_json(text: &str) -> Result<Self, Error> {
        let doc: Value = serde_json::from_str(text)?;
        if doc["schema"] != "nao-prioritized-ik-benchmark/1" {
            return Err(format!("unsupported schema {}", doc["schema"]).into());
        }
        let model = nao::rfoot();
        let joint_order = strings(&doc["joint_order"], "joint_order")?;
        let index_of = |name: &str| joint_order.iter().position(|j| j == name);
        let mut order_to_variable = Vec::new();
        for name in &joint_order {
            let variable = if name == "RHipYawPitch" {
                "LHipYawPitch"
            } else {
                name
            };
            order_to_variable.push(model.variable_index(variable)?);
        }
        let lower = floats(&doc["joint_limits"]["lower"], "joint_limits.lower")?;
        let upper = floats(&doc["joint_limits"]["upper"], "joint_limits.upper")?;
        let to_model = |values: &[f64]| -> Result<Vec<f64>, Error> {
            nao::VARIABLES
                .iter()
                .map(|v| {
                    index_of(v)
                        .map(|i| values[i])
                        .ok_or_else(|| format!("joint_order lacks {v}").into())
                })
                .collect()
        };
        let bounds = JointBounds::new(&to_model(&lower)?, &to_model(&upper)?)?;
        let q_init = to_model(&floats(&doc["q_init"], "q_init")?)?;
        let q_ref = to_model(&floats(&doc["q_ref"], "q_ref")?)?;
        let frames = doc["frames"]["count"]
            .as_u64()
            .ok_or("frames.count missing")? as usize;

        let points = &doc["points"];
        let point = |name: &str| -> Result<(String, Vector3<f64>), Error> {
            let p = &points[name];
            let link = p["link"]
                .as_str()
                .ok_or_else(|| format!("point {name}: no link"))?;
            let offset = floats(&p["offset"], "point offset")?;
            Ok((
                link.to_owned(),
                Vector3::new(offset[0], offset[1], offset[2]),
            ))
        };
        let per_frame = |name: &str| -> Result<Vec<[f64; 3]>, Error> {
            doc["frames"]["targets"][name]
                .as_array()
                .ok_or_else(|| format!("no per-frame targets for {name}"))?
                .iter()
                .map(|t| {
                    let v = floats(t, "target")?;
                    Ok([v[0], v[1], v[2]])
                })
                .collect()
        };

        let mut tasks = Vec::new();
        let mut level_names = Vec::new();
        let mut level_defs: Vec<&Value> = doc["tasks"]
            .as_array()
            .ok_or("tasks missing")?
            .iter()
            .collect();
        level_defs.sort_by_key(|t| t["priority"].as_u64().unwrap_or(u64::MAX));
        for def in level_defs {
            let name = def["name"].as_str().unwrap_or("level").to_owned();
            let level = level_names.len();
            let mut level_tasks = Vec::new();
            match def["kind"].as_str() {
                Some("com") => {
                    let t = floats(&def["target"], "com target")?;
                    level_tasks.push(Task {
                        name: name.clone(),
                        point: None,
                        axes: vec![Axis::X, Axis::Y],
                        target: Target::Com([t[0], t[1]]),
                        level,
                    });
                }
                Some("points") if def["rows"].is_array() => {
                    for row in def["rows"].as_array().into_iter().flatten() {
                        let p = row["point"].as_str().ok_or("row without point")?;
                        let axes = strings(&row["axes"], "axes")?
                            .iter()
                            .map(|a| axis(a))
                            .collect::<Result<_, _>>()?;
                        level_tasks.push(Task {
                            name: p.to_owned(),
                            point: Some(point(p)?),
                            axes,
                            target: Target::Fixed(floats(&row["target"], "row target")?),
                            level,
                        });
                    }
                }
                Some("points") => {
                    let axes: Vec<Axis> = strings(&def["axes"], "axes")?
                        .iter()
                        .map(|a| axis(a))
                        .collect::<Result<_, _>>()?;
                    for p in strings(&def["points"], "points")? {
                        level_tasks.push(Task {
                            name: p.clone(),
                            point: Some(point(&p)?),
                            axes: axes.clone(),
                            target: Target::PerFrame(per_frame(&p)?),
                            level,
                        });
                    }
                }
                // The posture task is the lowest priority: a joint-tracking gradient task.
                Some("posture") => continue,
                other => return Err(format!("unknown task kind {other:?}").into()),
            }
            level_names.push(name);
            tasks.extend(level_tasks);
        }

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
            tasks,
            level_names,
            model,
        })
    }

    /// Task names in stack order (the order of `FrameResult::errors`).
    pub fn task_names(&self) -> Vec<&str> {
        self.tasks.iter().map(|t| t.name.as_str()).collect()
    }

    /// Level of each task.
    pub fn task_levels(&self) -> Vec<usize> {
        self.tasks.iter().map(|t| t.level).collect()
    }

    /// `q` (model variables) in the file's `joint_order`.
    pub fn to_joint_order(&self, q: &[f64]) -> Vec<f64> {
        self.order_to_variable.iter().map(|&v| q[v]).collect()
    }
}

/// The solver side of a problem: its tasks as a [`TaskSet`], solver and driver.
pub struct Runner<'p> {
    problem: &'p Problem,
    set: TaskSet<'p>,
    solver: Solver,
    driver: PositionDriver,
}

/// Outcome of one frame.
pub struct FrameResult {
    pub iterations: usize,
    pub stop: StopReason,
    /// Error norm of every task, in `Problem::task_names` order (m).
    pub errors: Vec<f64>,
    /// Wall time: targets set + all iterations + stop test (µs).
    pub micros: f64,
}

/// The ready-made task of a problem task, at its first frame's target.
fn ready_made(model: &Model, task: &Task) -> Result<Box<dyn tasks::Task>, Error> {
    let target = match &task.target {
        Target::Com(xy) => return Ok(Box::new(ComTask::ground(model, *xy)?)),
        Target::Fixed(values) => {
            let mut target = Vector3::zeros();
            for (&axis, &v) in task.axes.iter().zip(values) {
                target[axis as usize] = v;
            }
            target
        }
        Target::PerFrame(targets) => Vector3::from(*targets.first().ok_or("no frames")?),
    };
    let (frame, offset) = task.point.as_ref().ok_or("a point task without a point")?;
    let point = PositionTask::new(model, frame, target)?
        .with_offset(*offset)?
        .axes(&task.axes)
        .named(&task.name);
    Ok(Box::new(point))
}

impl<'p> Runner<'p> {
    pub fn new(problem: &'p Problem) -> Result<Self, Error> {
        let model = &problem.model;
        let mut set = TaskSet::new(model);
        for (level, name) in problem.level_names.iter().enumerate() {
            let tasks = problem
                .tasks
                .iter()
                .filter(|t| t.level == level)
                .map(|t| ready_made(model, t))
                .collect::<Result<_, _>>()?;
            set = set.level(name, tasks);
        }
        let set = set.posture_gradient(POSTURE_GAIN, &problem.q_ref)?;
        let solver = Solver::new(&set.shape())?;
        let driver = PositionDriver::new(&solver, problem.settings)?;
        Ok(Self {
            problem,
            set,
            solver,
            driver,
        })
    }

    /// Solves frame `frame`, warm-started from `q` (updated in place).
    pub fn solve_frame(&mut self, frame: usize, q: &mut [f64]) -> Result<FrameResult, Error> {
        let start = Instant::now();
        for task in &self.problem.tasks {
            if let Target::PerFrame(targets) = &task.target {
                let target = targets.get(frame).ok_or("frame out of range")?;
                self.set.task_mut::<PositionTask>(&task.name)?.target = Vector3::from(*target);
            }
        }
        let report = self
            .driver
            .run(&mut self.solver, &mut self.set, q, &self.problem.bounds)?;
        let micros = start.elapsed().as_secs_f64() * 1e6;
        Ok(FrameResult {
            iterations: report.iterations,
            stop: report.stop,
            errors: report.task_errors().to_vec(),
            micros,
        })
    }
}

/// Median, 99th percentile and maximum of `values` (sorted in place).
pub fn percentiles(values: &mut [f64]) -> (f64, f64, f64) {
    values.sort_by(f64::total_cmp);
    let at = |p: f64| values[((values.len() - 1) as f64 * p).round() as usize];
    (at(0.5), at(0.99), values[values.len() - 1])
}

/// Per-task statistics in a JSON object keyed by task name.
pub fn per_task(names: &[&str], values: impl Fn(usize) -> f64) -> BTreeMap<String, f64> {
    names
        .iter()
        .enumerate()
        .map(|(i, n)| (n.to_string(), values(i)))
        .collect()
}
