//! Imitation from Python: a whole clip (`imitate_clip`, the run of `taskstack imitate` with
//! the same settings and numbers) or live frames (`Imitator`).

use std::path::{Path, PathBuf};

use numpy::ndarray::{Array2, Array3};
use numpy::{IntoPyArray, PyArray1, PyArray2, PyArray3, PyReadonlyArray2};
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use taskstack::batch::{
    ClipSession, ClipSetup, Hold, LookAheadLeads, imitate_clip as run_clip, metrics_json,
};
use taskstack::export::{MotionRecorder, MotionTrack};
use taskstack::human::{CaptureSystem, HumanFrame, HumanJoint};
use taskstack::imitation::EFFECTORS;
use taskstack::imitation::ImitationMethod;
use taskstack::imitation::koenemann::{Calibration, FootRetargeting, KoenemannConfig};
use taskstack::imitation::poubel::PoubelConfig;
use taskstack::imitation::reference::support::SupportConfig;
use taskstack::io::clip::Clip;
use taskstack::robots::{BipedProfile, g1, nao};
use taskstack::{Imitator, ImitatorConfig, RobotFrame};

use crate::errors::{profile_error, to_py, value_error};
use crate::kinematics::matrix;

/// The robot named `robot`: `"nao"`, `"g1"` or the path of a biped profile (TOML).
pub(crate) fn profile(robot: &str) -> PyResult<BipedProfile> {
    match robot {
        "nao" => Ok(nao::profile()),
        "g1" => Ok(g1::profile()),
        path => BipedProfile::from_toml_file(path).map_err(|err| profile_error(path, err)),
    }
}

/// The imitator settings of the keyword arguments shared by `imitate_clip` and `Imitator`
/// (the options of `taskstack imitate`, with its defaults).
#[derive(Debug, Clone)]
pub(crate) struct Settings {
    method: String,
    walk: bool,
    dynamic_walk: bool,
    walking_arms: bool,
    step_distance: Option<f64>,
    step_heading: Option<f64>,
    step_pivot: Option<f64>,
    step_slide: Option<f64>,
    zmp_balance: Option<bool>,
    damping: Option<f64>,
    damping_momentum: f64,
    velocity_fraction: Option<f64>,
    upper_body_fraction: Option<f64>,
    task_speed: Option<f64>,
    swing_speed: Option<f64>,
    tracking_speed: Option<f64>,
    tracking_acceleration: Option<f64>,
    iterations: usize,
    calibration: String,
    retargeting: String,
    sway_shaping: bool,
}

impl Settings {
    /// The settings of the keyword arguments `kwargs` (the options of `taskstack imitate`,
    /// with its defaults); an unknown keyword is a `TypeError`, as Python's own are.
    pub(crate) fn from_kwargs(kwargs: Option<&Bound<'_, PyDict>>) -> PyResult<Self> {
        let mut s = Settings {
            method: "poubel".into(),
            walk: false,
            dynamic_walk: false,
            walking_arms: false,
            step_distance: None,
            step_heading: None,
            step_pivot: None,
            step_slide: None,
            zmp_balance: None,
            damping: None,
            damping_momentum: 0.0,
            velocity_fraction: None,
            upper_body_fraction: None,
            task_speed: None,
            swing_speed: None,
            tracking_speed: None,
            tracking_acceleration: None,
            iterations: 1,
            calibration: "auto".into(),
            retargeting: "shift-both-feet".into(),
            sway_shaping: true,
        };
        let Some(kwargs) = kwargs else {
            return Ok(s);
        };
        for (key, value) in kwargs.iter() {
            let key: String = key.extract()?;
            match key.as_str() {
                "method" => s.method = value.extract()?,
                "walk" => s.walk = value.extract()?,
                "dynamic_walk" => s.dynamic_walk = value.extract()?,
                "walking_arms" => s.walking_arms = value.extract()?,
                "step_distance" => s.step_distance = value.extract()?,
                "step_heading" => s.step_heading = value.extract()?,
                "step_pivot" => s.step_pivot = value.extract()?,
                "step_slide" => s.step_slide = value.extract()?,
                "zmp_balance" => s.zmp_balance = value.extract()?,
                "damping" => s.damping = value.extract()?,
                "damping_momentum" => s.damping_momentum = value.extract()?,
                "velocity_fraction" => s.velocity_fraction = value.extract()?,
                "upper_body_fraction" => s.upper_body_fraction = value.extract()?,
                "task_speed" => s.task_speed = value.extract()?,
                "swing_speed" => s.swing_speed = value.extract()?,
                "tracking_speed" => s.tracking_speed = value.extract()?,
                "tracking_acceleration" => s.tracking_acceleration = value.extract()?,
                "iterations" => s.iterations = value.extract()?,
                "calibration" => s.calibration = value.extract()?,
                "retargeting" => s.retargeting = value.extract()?,
                "sway_shaping" => s.sway_shaping = value.extract()?,
                other => {
                    return Err(PyTypeError::new_err(format!(
                        "unexpected keyword argument {other:?}"
                    )));
                }
            }
        }
        Ok(s)
    }

    /// The robot named `robot` (see [`profile`]), its commands played through its sway
    /// shaper unless `sway_shaping` is off (the CLI's `--no-sway-shaping`).
    pub(crate) fn profile(&self, robot: &str) -> PyResult<BipedProfile> {
        let mut profile = profile(robot)?;
        if !self.sway_shaping {
            profile.sway_period = None;
        }
        Ok(profile)
    }

    /// The imitator settings for a clip of `capture`: the shared ones here, the method's in
    /// [`Settings::poubel`] and [`Settings::koenemann`]; a keyword of the other method is a
    /// `ValueError`.
    pub(crate) fn config(&self, capture: CaptureSystem) -> PyResult<ImitatorConfig> {
        let (method, others) = match self.method.as_str() {
            "poubel" => (
                ImitationMethod::Poubel(self.poubel()?),
                self.koenemann_given(),
            ),
            "koenemann" => (
                ImitationMethod::Koenemann(self.koenemann()?),
                self.poubel_given(),
            ),
            other => {
                return Err(value_error(format!(
                    "method {other:?}: expected \"poubel\" or \"koenemann\""
                )));
            }
        };
        if let Some(key) = others.first() {
            return Err(value_error(format!(
                "{key}: not a setting of method {:?}",
                self.method
            )));
        }
        let fraction = |name: &str, value: Option<f64>| match value {
            Some(v) if !(v > 0.0 && v <= 1.0) => {
                Err(value_error(format!("{name} = {v}: must be in (0, 1]")))
            }
            v => Ok(v),
        };
        Ok(ImitatorConfig {
            method,
            velocity_fraction: fraction("velocity_fraction", self.velocity_fraction)?,
            upper_body_velocity_fraction: fraction(
                "upper_body_fraction",
                self.upper_body_fraction,
            )?,
            max_tracking_speed: positive("tracking_speed", self.tracking_speed)?,
            max_tracking_acceleration: positive(
                "tracking_acceleration",
                self.tracking_acceleration,
            )?,
            support: SupportConfig::for_capture(capture),
            ..ImitatorConfig::default()
        })
    }

    /// Poubel et al.'s settings of these keywords.
    fn poubel(&self) -> PyResult<PoubelConfig> {
        if self.walking_arms && !self.dynamic_walk {
            return Err(value_error(
                "walking_arms = True: the arms follow the human only in the dynamic walk \
                 (dynamic_walk = True)",
            ));
        }
        if !(1..=100).contains(&self.iterations) {
            return Err(value_error(format!(
                "iterations = {}: must be 1–100",
                self.iterations
            )));
        }
        if !(0.0..=1.0).contains(&self.damping_momentum) {
            return Err(value_error(format!(
                "damping_momentum = {}: must be in [0, 1]",
                self.damping_momentum
            )));
        }
        let mut poubel = PoubelConfig {
            max_task_speed: positive("task_speed", self.task_speed)?,
            iterations_per_frame: self.iterations,
            zmp_balance: self.zmp_balance,
            damping_momentum: self.damping_momentum,
            damping: positive("damping", self.damping)?,
            ..PoubelConfig::default()
        };
        let steps = &mut poubel.footsteps;
        steps.follow = self.walk || self.dynamic_walk;
        steps.dynamic = self.dynamic_walk;
        steps.walking_arms = self.walking_arms;
        // Out of range (NaN, < 0), the imitator refuses them by name.
        for (option, field) in [
            (self.step_distance, &mut steps.distance),
            (self.step_heading, &mut steps.heading),
            (self.step_pivot, &mut steps.pivot),
            (self.step_slide, &mut steps.slide),
        ] {
            if let Some(value) = option {
                *field = value;
            }
        }
        Ok(poubel)
    }

    /// The keywords of Poubel et al.'s method given away from their defaults.
    fn poubel_given(&self) -> Vec<&'static str> {
        [
            (self.walk, "walk"),
            (self.dynamic_walk, "dynamic_walk"),
            (self.walking_arms, "walking_arms"),
            (self.step_distance.is_some(), "step_distance"),
            (self.step_heading.is_some(), "step_heading"),
            (self.step_pivot.is_some(), "step_pivot"),
            (self.step_slide.is_some(), "step_slide"),
            (self.zmp_balance.is_some(), "zmp_balance"),
            (self.damping.is_some(), "damping"),
            (self.damping_momentum != 0.0, "damping_momentum"),
            (self.task_speed.is_some(), "task_speed"),
            (self.iterations != 1, "iterations"),
        ]
        .into_iter()
        .filter_map(|(given, name)| given.then_some(name))
        .collect()
    }

    /// The keywords of Koenemann et al.'s method given away from their defaults.
    fn koenemann_given(&self) -> Vec<&'static str> {
        [
            (self.calibration != "auto", "calibration"),
            (self.retargeting != "shift-both-feet", "retargeting"),
            (self.swing_speed.is_some(), "swing_speed"),
        ]
        .into_iter()
        .filter_map(|(given, name)| given.then_some(name))
        .collect()
    }

    /// Koenemann et al.'s settings of these keywords.
    fn koenemann(&self) -> PyResult<KoenemannConfig> {
        Ok(KoenemannConfig {
            calibration: match self.calibration.as_str() {
                "auto" => Calibration::Auto,
                "first-frame" => Calibration::FirstFrame,
                "ideal" => Calibration::Ideal,
                other => {
                    return Err(value_error(format!(
                        "calibration {other:?}: expected \"auto\", \"first-frame\" or \"ideal\""
                    )));
                }
            },
            retargeting: match self.retargeting.as_str() {
                "shift-both-feet" => FootRetargeting::ShiftBothFeet,
                "move-one-foot" => FootRetargeting::MoveOneFoot,
                other => {
                    return Err(value_error(format!(
                        "retargeting {other:?}: expected \"shift-both-feet\" or \"move-one-foot\""
                    )));
                }
            },
            swing_speed: positive("swing_speed", self.swing_speed)?,
            ..KoenemannConfig::default()
        })
    }
}

/// `value` if it is `None` or a finite number > 0; else a `ValueError` naming `name`.
fn positive(name: &str, value: Option<f64>) -> PyResult<Option<f64>> {
    match value {
        Some(v) if !(v.is_finite() && v > 0.0) => {
            Err(value_error(format!("{name} = {v}: must be a number > 0")))
        }
        v => Ok(v),
    }
}

/// `hold`: `None` or `"auto"` (until the robot has finished), or seconds.
fn hold(value: Option<&Bound<'_, PyAny>>) -> PyResult<Hold> {
    let Some(value) = value else {
        return Ok(Hold::UntilFinished);
    };
    if let Ok(text) = value.extract::<String>() {
        return match text.as_str() {
            "auto" => Ok(Hold::UntilFinished),
            other => Err(value_error(format!(
                "hold {other:?}: expected \"auto\" or seconds"
            ))),
        };
    }
    let seconds: f64 = value.extract()?;
    Hold::Fixed(seconds).validated().map_err(to_py)
}

/// Everything `imitate_clip` returns, gathered without the GIL.
struct ClipRun {
    track: MotionTrack,
    /// Each frame's servo targets (`joints.csv`'s rows), concatenated.
    servo_targets: Vec<f64>,
    phases: Vec<String>,
    metrics: String,
}

/// Runs `path` as `taskstack imitate` does: the clip's support defaults, offline look-ahead
/// when asked (the whole clip read first), the hold.
fn run(
    path: &Path,
    profile: BipedProfile,
    settings: &Settings,
    offline: bool,
    hold: Hold,
) -> PyResult<ClipRun> {
    let setup = ClipSetup {
        look_ahead: offline.then(LookAheadLeads::default),
        ..ClipSetup::default()
    };
    let session = ClipSession::open(path, &setup).map_err(to_py)?;
    let config = (session.config(&settings.config(session.clip().capture())?)).map_err(to_py)?;
    let mut imitator = Imitator::new(profile, config).map_err(to_py)?;
    let mut recorder = MotionRecorder::new(&imitator).map_err(to_py)?;
    let (mut phases, mut servo_targets) = (Vec::new(), Vec::new());
    let mut recorded = Ok(());
    let metrics = run_clip(path, session.into_clip(), &mut imitator, hold, |frame| {
        if recorded.is_ok() {
            recorded = recorder.record(frame);
        }
        servo_targets.extend_from_slice(&frame.servo_targets);
        phases.push(frame.phase.to_string());
    })
    .map_err(to_py)?;
    recorded.map_err(to_py)?;
    Ok(ClipRun {
        track: recorder.finish(),
        servo_targets,
        phases,
        metrics: metrics_json(&metrics, path),
    })
}

/// Imitates the clip at `path` (BVH or Kinect v2 CSV); see the Python docstring. `options`:
/// the keywords of [`Settings::from_kwargs`].
#[pyfunction]
#[pyo3(signature = (path, robot = "nao", hold = None, offline = false, **options))]
pub(crate) fn imitate_clip<'py>(
    py: Python<'py>,
    path: PathBuf,
    robot: &str,
    hold: Option<&Bound<'py, PyAny>>,
    offline: bool,
    options: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyDict>> {
    let settings = Settings::from_kwargs(options)?;
    let hold = self::hold(hold)?;
    let profile = settings.profile(robot)?;
    let run = py.detach(|| run(&path, profile, &settings, offline, hold))?;
    let joints = run.track.joint_count().max(1);
    let frames = run.servo_targets.len() / joints;
    let targets = Array2::from_shape_vec((frames, joints), run.servo_targets)
        .map_err(|e| value_error(e.to_string()))?;
    let out = track_dict(py, run.track)?;
    out.set_item("servo_targets", targets.into_pyarray(py))?;
    out.set_item("phase", PyList::new(py, run.phases)?)?;
    out.set_item("metrics_json", run.metrics)?;
    Ok(out)
}

/// A track's arrays: `time` (N), `q` (N × J), `joint_names`, `root_pos` (N × 3), `root_quat`
/// (N × 4), `contacts` (N × 2, bool).
fn track_dict(py: Python<'_>, track: MotionTrack) -> PyResult<Bound<'_, PyDict>> {
    let n = track.len();
    let j = track.joint_count();
    let rows = |data: Vec<f64>, cols: usize| -> PyResult<Bound<'_, PyArray2<f64>>> {
        let array =
            Array2::from_shape_vec((n, cols), data).map_err(|e| value_error(e.to_string()))?;
        Ok(array.into_pyarray(py))
    };
    let out = PyDict::new(py);
    out.set_item("time", PyArray1::from_vec(py, track.time))?;
    out.set_item("q", rows(track.dof_pos, j)?)?;
    out.set_item("joint_names", PyList::new(py, track.joint_names)?)?;
    out.set_item("root_pos", rows(track.root_pos.concat(), 3)?)?;
    out.set_item("root_quat", rows(track.root_quat.concat(), 4)?)?;
    let contacts: Vec<bool> = track.contacts.concat();
    let contacts =
        Array2::from_shape_vec((n, 2), contacts).map_err(|e| value_error(e.to_string()))?;
    out.set_item("contacts", contacts.into_pyarray(py))?;
    Ok(out)
}

/// A clip's frame times, human joint names and joint positions.
type ClipArrays<'py> = (
    Bound<'py, PyArray1<f64>>,
    Vec<&'static str>,
    Bound<'py, PyArray3<f64>>,
);

/// Reads the clip at `path`: its frame times (N, s), the human joint names (J) and their
/// positions (N, J, 3; m, world z up; NaN where a joint is missing).
#[pyfunction]
pub(crate) fn read_clip<'py>(py: Python<'py>, path: PathBuf) -> PyResult<ClipArrays<'py>> {
    let frames = py.detach(|| {
        let clip = Clip::open(&path).map_err(to_py)?;
        clip.collect::<Result<Vec<HumanFrame>, _>>().map_err(to_py)
    })?;
    let joints = HumanJoint::ALL;
    let times: Vec<f64> = frames.iter().map(|f| f.time).collect();
    let positions = Array3::from_shape_fn((frames.len(), joints.len(), 3), |(i, j, k)| {
        frames[i].get(joints[j]).map_or(f64::NAN, |p| p[k])
    });
    let names = joints.iter().map(|j| j.name()).collect();
    Ok((
        PyArray1::from_vec(py, times),
        names,
        positions.into_pyarray(py),
    ))
}

/// A live imitator: one human frame in, one robot frame out.
// Unsendable: the imitator's solvers keep scratch space in `RefCell`s (not `Sync`); an
// `Imitator` is used from the thread that made it (Python raises otherwise).
#[pyclass(name = "Imitator", module = "taskstack._taskstack", unsendable)]
pub(crate) struct PyImitator {
    imitator: Imitator,
    recorder: MotionRecorder,
    frame: HumanFrame,
}

#[pymethods]
impl PyImitator {
    #[new]
    #[pyo3(signature = (robot = "nao", capture = "optical", **options))]
    fn new(robot: &str, capture: &str, options: Option<&Bound<'_, PyDict>>) -> PyResult<Self> {
        let capture = match capture {
            "optical" => CaptureSystem::Optical,
            "kinect" | "depth" => CaptureSystem::DepthCamera,
            other => {
                return Err(value_error(format!(
                    "capture {other:?}: expected \"optical\" or \"kinect\""
                )));
            }
        };
        let settings = Settings::from_kwargs(options)?;
        let profile = settings.profile(robot)?;
        let imitator = Imitator::new(profile, settings.config(capture)?).map_err(to_py)?;
        let recorder = MotionRecorder::new(&imitator).map_err(to_py)?;
        Ok(Self {
            imitator,
            recorder,
            frame: HumanFrame::new(0.0),
        })
    }

    /// The robot's joint names, in the order of `q`.
    #[getter]
    fn joint_names(&self) -> Vec<String> {
        self.imitator.variable_names().map(str::to_owned).collect()
    }

    /// The human joint names a frame may hold.
    #[staticmethod]
    fn human_joint_names() -> Vec<&'static str> {
        HumanJoint::ALL.iter().map(|j| j.name()).collect()
    }

    #[pyo3(signature = (time, positions, names = None))]
    fn step<'py>(
        &mut self,
        py: Python<'py>,
        time: f64,
        positions: &Bound<'py, PyAny>,
        names: Option<Vec<String>>,
    ) -> PyResult<Bound<'py, PyDict>> {
        self.frame.clear(time);
        match names {
            Some(names) => {
                let array: PyReadonlyArray2<'py, f64> = positions.extract().map_err(|_| {
                    value_error("positions: with names, expected a float array of shape (J, 3)")
                })?;
                let array = array.as_array();
                if array.ncols() != 3 || array.nrows() != names.len() {
                    return Err(value_error(format!(
                        "positions of shape {:?} for {} names: expected ({}, 3)",
                        array.shape(),
                        names.len(),
                        names.len()
                    )));
                }
                for (name, row) in names.iter().zip(array.rows()) {
                    self.set(name, [row[0], row[1], row[2]])?;
                }
            }
            None => {
                let dict = positions.cast::<PyDict>().map_err(|_| {
                    value_error("positions: expected a dict of joint name -> (x, y, z), or an array with names")
                })?;
                for (key, value) in dict.iter() {
                    let name: String = key.extract()?;
                    let p: [f64; 3] = value.extract().map_err(|_| {
                        value_error(format!(
                            "joint {name}: expected three numbers (x, y, z) in metres"
                        ))
                    })?;
                    self.set(&name, p)?;
                }
            }
        }
        self.frame.derive_mid_hip();
        let frame = self.imitator.step(&self.frame).map_err(to_py)?;
        let (root_pos, root_quat) = self.recorder.base_pose(frame).map_err(to_py)?;
        robot_frame_dict(
            py,
            frame,
            root_pos,
            root_quat,
            self.recorder.contacts(frame),
        )
    }
}

impl PyImitator {
    fn set(&mut self, name: &str, p: [f64; 3]) -> PyResult<()> {
        let joint = HumanJoint::from_name(name).ok_or_else(|| {
            value_error(format!(
                "unknown human joint {name:?} (see Imitator.human_joint_names())"
            ))
        })?;
        if p.iter().all(|v| v.is_nan()) {
            return Ok(()); // NaN, NaN, NaN: the joint is missing in this frame
        }
        if !p.iter().all(|v| v.is_finite()) {
            return Err(value_error(format!(
                "joint {name}: position {p:?} is not finite"
            )));
        }
        self.frame.set(joint, Some(p.into()));
        Ok(())
    }
}

/// A robot frame as a dict (see the Python docstring of `Imitator.step`).
pub(crate) fn robot_frame_dict<'py>(
    py: Python<'py>,
    frame: &RobotFrame,
    root_pos: [f64; 3],
    root_quat: [f64; 4],
    contacts: [bool; 2],
) -> PyResult<Bound<'py, PyDict>> {
    let out = PyDict::new(py);
    out.set_item("time", frame.time)?;
    out.set_item("q", PyArray1::from_slice(py, &frame.q))?;
    out.set_item(
        "servo_targets",
        PyArray1::from_slice(py, &frame.servo_targets),
    )?;
    out.set_item("phase", frame.phase.to_string())?;
    out.set_item("root_pos", PyArray1::from_slice(py, &root_pos))?;
    out.set_item("root_quat", PyArray1::from_slice(py, &root_quat))?;
    out.set_item("left_sole", matrix(py, &frame.left_sole))?;
    out.set_item("right_sole", matrix(py, &frame.right_sole))?;
    out.set_item("com", PyArray1::from_slice(py, frame.com.as_slice()))?;
    out.set_item("contacts", contacts.to_vec())?;
    out.set_item("awaiting_contact", frame.awaiting_contact)?;
    // Hands and ankles, world frame, beside the scaled human's same joints.
    let effectors = PyDict::new(py);
    let reference = PyDict::new(py);
    for ((name, joint), position) in EFFECTORS.iter().zip(&frame.effectors) {
        let world = frame.world_t_root.transform_point(&(*position).into());
        effectors.set_item(*name, PyArray1::from_slice(py, world.coords.as_slice()))?;
        if let Some(p) = frame.reference[joint.index()] {
            let world = frame.world_t_root.transform_point(&p.into());
            reference.set_item(*name, PyArray1::from_slice(py, world.coords.as_slice()))?;
        }
    }
    out.set_item("effectors", effectors)?;
    out.set_item("human_effectors", reference)?;
    Ok(out)
}
