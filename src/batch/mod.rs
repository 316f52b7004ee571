//! Batch retargeting: many clips, one output folder per clip, a summary of the batch.
//!
//! Each clip is an independent job: the robot ([`BatchOptions::robot`], a [`BipedProfile`]) is
//! built once and cloned into each job, which then owns its [`Imitator`] (all the solver and kinematics workspaces) and
//! its [`MetricsRecorder`], so jobs share nothing mutable. With the cargo feature `parallel` (on by
//! default) the jobs run on a rayon thread pool of [`BatchOptions::threads`] threads; without it
//! they run one after the other, with the same API and the same results: a clip's output does not
//! depend on which thread ran it or on the other clips.
//!
//! For a clip `name.bvh` (or `name.csv`) the job writes into `OUT/name/`:
//!
//! * `joints.csv`: a header `time,<the robot's joint names>`, then per frame the time (s) and the
//!   joint angles (rad) to command, six decimals
//!   ([`RobotFrame::servo_targets`](crate::imitation::output::RobotFrame::servo_targets));
//! * `metrics.json`: the [`ImitationMetrics`] of the run (lengths in m, angles in rad, times in
//!   s, solve time in µs; a non-finite value is written as `null`).
//!
//! A clip that fails (unreadable file, an error in a frame) does not stop the batch: its
//! [`ClipOutcome`] holds the error, which names the file and the frame.

use std::collections::HashSet;
use std::path::{Path, PathBuf};
use std::time::Instant;

use serde_json::{Value, json};
use thiserror::Error;

use crate::human::HumanFrame;
use crate::imitation::metrics::travel::StepFollowing;
use crate::imitation::metrics::{
    EffectorError, ImitationMetrics, MeanMax, MetricsRecorder, Spread,
};
use crate::imitation::poubel::hand_support::HandSupportError;
use crate::imitation::walking::look_ahead::LookAheadError;
use crate::imitation::{ImitationError, Imitator, ImitatorConfig, RobotFrame};
use crate::io::FrameSource;
use crate::io::clip::ClipError;
use crate::robots::{BipedProfile, nao};

mod session;

pub use session::{ClipSession, ClipSetup, LookAheadLeads};

// The old path of `export::JointsWriter`; kept for one release.
#[doc(hidden)]
pub use crate::export::JointsWriter;

/// Errors of a batch or of one of its clips. Each names the clip file.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum BatchError {
    /// The clip could not be opened or read (the reader's message names the clip and line).
    #[error("{source}")]
    Clip {
        /// The clip file.
        path: PathBuf,
        /// The reader's error.
        source: ClipError,
    },
    /// The clip holds no frame of motion.
    #[error("{}: the clip has no frame of motion", path.display())]
    EmptyClip {
        /// The clip file.
        path: PathBuf,
    },
    /// The imitator could not be built or refused a frame.
    #[error("{}: frame {frame}: {source}", path.display())]
    Imitation {
        /// The clip file.
        path: PathBuf,
        /// Index of the frame (0 = first frame of captured motion).
        frame: usize,
        /// The imitator's error.
        source: ImitationError,
    },
    /// Reading a folder or writing an output file failed.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file or folder.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// Two clips have the same file stem, so they would write into the same output folder.
    #[error("clips {} and {} would both write into {}", first.display(), second.display(), output.display())]
    DuplicateOutput {
        /// The first clip.
        first: PathBuf,
        /// The second clip.
        second: PathBuf,
        /// Their common output folder.
        output: PathBuf,
    },
    /// The thread pool could not be started.
    #[error("cannot start a pool of {threads} threads: {message}")]
    ThreadPool {
        /// Requested number of threads.
        threads: usize,
        /// The pool's error message.
        message: String,
    },
    /// The human's foot lifts of an offline run could not be read off the clip.
    #[error("{}: foot lifts: {source}", path.display())]
    LookAhead {
        /// The clip file.
        path: PathBuf,
        /// The look-ahead's error.
        source: LookAheadError,
    },
    /// The hand contacts with the scene could not be found in the clip.
    #[error("{}: hand contacts: {source}", path.display())]
    HandSupports {
        /// The clip file.
        path: PathBuf,
        /// The hand supports' error.
        source: HandSupportError,
    },
    /// An offline look-ahead or a scene asked of a method without support phases and task
    /// tables (Koenemann et al.'s): only Poubel et al.'s method has them.
    #[error("{}: {what} needs Poubel et al.'s method (support phases and task tables)", path.display())]
    NeedsPoubel {
        /// The clip file.
        path: PathBuf,
        /// What was asked: `the offline look-ahead` or `a scene`.
        what: &'static str,
    },
    /// A fixed hold that is not a number of seconds in `0..=`[`MAX_HOLD`].
    #[error("hold of {0} s: must be a number of seconds within 0–{MAX_HOLD} s")]
    Hold(f64),
}

/// Options of a batch. The default: the NAO, one thread per core, default imitator settings.
#[derive(Debug, Clone)]
pub struct BatchOptions {
    /// The robot every clip is retargeted to.
    pub robot: BipedProfile,
    /// Worker threads; 0 means one per core. Ignored (always 1) without the `parallel` feature.
    pub threads: usize,
    /// Imitator settings shared by every clip, except `support`, which each clip replaces by the
    /// defaults of its kind of source ([`SupportConfig::for_capture`](crate::imitation::reference::support::SupportConfig::for_capture) of [`Clip::capture`](crate::io::clip::Clip::capture): optical mocap or Kinect).
    pub imitator: ImitatorConfig,
    /// After each clip, the human's last pose is held (frames 1/120 s apart) so that the robot
    /// can finish the step it is taking; those frames are in the outputs too. Default: until
    /// the robot has finished ([`Hold::UntilFinished`]).
    pub hold: Hold,
    /// What each clip gives its run beyond its frames: a skeleton map, the offline look-ahead
    /// of the feet, a scene for the hands ([`ClipSession`]). Default: none.
    pub setup: ClipSetup,
}

impl Default for BatchOptions {
    fn default() -> Self {
        Self {
            robot: nao::profile(),
            threads: 0,
            imitator: ImitatorConfig::default(),
            hold: Hold::UntilFinished,
            setup: ClipSetup::default(),
        }
    }
}

/// What one clip's run gave.
#[derive(Debug, Clone, PartialEq)]
pub struct ClipSummary {
    /// Frames imitated.
    pub frames: usize,
    /// Time from the first to the last frame of the clip (s).
    pub duration: f64,
    /// Wall time of the job: reading, imitating, measuring and writing (s).
    pub wall_time: f64,
    /// Changes of the robot's continuous phase (DS, RS, LS).
    pub robot_support_changes: usize,
    /// Smallest signed distance of the CoM ground projection to the support polygon's edge (m,
    /// positive inside; −∞ if some frame had no support polygon, +∞ with no frame).
    pub min_com_margin: f64,
    /// Frames whose CoM projection was outside the support polygon.
    pub frames_com_outside: usize,
    /// Joint positions outside their limits (joint × frame).
    pub joint_limit_violations: usize,
    /// Joint velocities above the allowed fraction of the rated velocity (joint × frame).
    pub velocity_limit_violations: usize,
    /// Largest move of the support foot between frames it stood on (m).
    pub max_support_slip: f64,
    /// Largest move of the other standing foot (m), see
    /// [`ImitationMetrics::max_held_foot_slip`].
    pub max_held_foot_slip: f64,
    /// Mean distance of the left and right hand to their scaled references over the frames
    /// where they were tracked, single and double support together (m); `None` if never tracked.
    pub hand_tracking_mean: [Option<f64>; 2],
    /// All the metrics of the run (also written to `metrics.json`).
    pub metrics: ImitationMetrics,
}

/// One clip of a batch and how it went.
#[derive(Debug)]
pub struct ClipOutcome {
    /// The clip file.
    pub clip: PathBuf,
    /// Its output folder.
    pub output: PathBuf,
    /// The summary, or why the clip failed.
    pub result: Result<ClipSummary, BatchError>,
}

/// The outcome of a batch.
#[derive(Debug)]
pub struct BatchSummary {
    /// One entry per clip, in the order the clips were given.
    pub clips: Vec<ClipOutcome>,
    /// Threads that ran the jobs.
    pub threads: usize,
    /// Wall time of the whole batch (s).
    pub wall_time: f64,
}

impl BatchSummary {
    /// Clips that were retargeted without error.
    pub fn succeeded(&self) -> impl Iterator<Item = &ClipSummary> {
        self.clips.iter().filter_map(|c| c.result.as_ref().ok())
    }

    /// Frames imitated over the batch (successful clips).
    pub fn frames(&self) -> usize {
        self.succeeded().map(|c| c.frames).sum()
    }

    /// Clips per second of wall time (all clips, failed ones included).
    pub fn clips_per_second(&self) -> f64 {
        self.clips.len() as f64 / self.wall_time.max(f64::MIN_POSITIVE)
    }

    /// Frames per second of wall time.
    pub fn frames_per_second(&self) -> f64 {
        self.frames() as f64 / self.wall_time.max(f64::MIN_POSITIVE)
    }
}

/// The clips in `dir`: files ending in `.bvh` or `.csv` (any case), sorted by path.
pub fn clips_in(dir: &Path) -> Result<Vec<PathBuf>, BatchError> {
    let io = |source| BatchError::Io {
        path: dir.to_path_buf(),
        source,
    };
    let mut clips = Vec::new();
    for entry in std::fs::read_dir(dir).map_err(io)? {
        let path = entry.map_err(io)?.path();
        let is_clip = path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("bvh") || e.eq_ignore_ascii_case("csv"));
        if is_clip && path.is_file() {
            clips.push(path);
        }
    }
    clips.sort();
    Ok(clips)
}

/// Retargets every clip of `clips` into its folder under `out` (see the module docs), in
/// parallel with the `parallel` feature. Fails as a whole, before any work, only when
/// `options.hold` is out of range ([`Hold::validated`]), the output folders would collide or
/// the thread pool cannot start; a clip's own failure is in its [`ClipOutcome`].
pub fn retarget_all(
    clips: &[PathBuf],
    out: &Path,
    options: &BatchOptions,
) -> Result<BatchSummary, BatchError> {
    options.hold.validated()?;
    let mut outputs: Vec<PathBuf> = Vec::with_capacity(clips.len());
    let mut seen = HashSet::new();
    for (i, clip) in clips.iter().enumerate() {
        let output = out.join(clip.file_stem().unwrap_or(clip.as_os_str()));
        if !seen.insert(output.clone()) {
            let first = outputs.iter().position(|o| *o == output).unwrap_or(i);
            return Err(BatchError::DuplicateOutput {
                first: clips[first].clone(),
                second: clip.clone(),
                output,
            });
        }
        outputs.push(output);
    }
    let start = Instant::now();
    let job = |(clip, output): (&PathBuf, &PathBuf)| ClipOutcome {
        clip: clip.clone(),
        output: output.clone(),
        result: retarget_clip(options, clip, output),
    };
    let (clips, threads) = run_jobs(clips, &outputs, options.threads, job)?;
    Ok(BatchSummary {
        clips,
        threads,
        wall_time: start.elapsed().as_secs_f64(),
    })
}

#[cfg(feature = "parallel")]
fn run_jobs<F>(
    clips: &[PathBuf],
    outputs: &[PathBuf],
    threads: usize,
    job: F,
) -> Result<(Vec<ClipOutcome>, usize), BatchError>
where
    F: Fn((&PathBuf, &PathBuf)) -> ClipOutcome + Send + Sync,
{
    use rayon::prelude::*;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| BatchError::ThreadPool {
            threads,
            message: e.to_string(),
        })?;
    // One clip per task: clips are long (10^3–10^4 frames), so no finer split is needed.
    let outcomes = pool.install(|| {
        clips
            .par_iter()
            .zip(outputs.par_iter())
            .with_max_len(1)
            .map(job)
            .collect()
    });
    Ok((outcomes, pool.current_num_threads()))
}

#[cfg(not(feature = "parallel"))]
fn run_jobs<F>(
    clips: &[PathBuf],
    outputs: &[PathBuf],
    _threads: usize,
    job: F,
) -> Result<(Vec<ClipOutcome>, usize), BatchError>
where
    F: Fn((&PathBuf, &PathBuf)) -> ClipOutcome,
{
    Ok((clips.iter().zip(outputs).map(job).collect(), 1))
}

/// Time step of the held frames after a clip (s).
pub const HOLD_STEP: f64 = 1.0 / 120.0;

/// The longest hold of [`Hold::UntilFinished`] (s).
pub const HOLD_CAP: f64 = 60.0;

/// The longest fixed hold (s): an hour of the last pose is more than any step needs.
pub const MAX_HOLD: f64 = 3600.0;

/// How long [`Hold::UntilFinished`] waits with the robot finished before it ends the run (s):
/// the CoM's last motion toward its goal settles. A robot whose profile states its sway period
/// ([`BipedProfile::sway_period`](crate::robots::BipedProfile::sway_period)) waits that much
/// longer: its shaped servo commands arrive that long after the plan.
pub const SETTLE_TIME: f64 = 1.0;

/// How long the human's last pose is held after a clip.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Hold {
    /// This long (s, ≥ 0).
    Fixed(f64),
    /// Until the robot has finished ([`RobotFrame::has_finished`]) for [`SETTLE_TIME`], at
    /// most [`HOLD_CAP`]: a robot still stepping toward where the human stands, or still on
    /// one leg, is not cut off.
    UntilFinished,
}

impl From<f64> for Hold {
    fn from(seconds: f64) -> Self {
        Hold::Fixed(seconds)
    }
}

impl Hold {
    /// This hold if it is [`Hold::UntilFinished`] or a fixed hold within `0..=`[`MAX_HOLD`].
    ///
    /// # Errors
    /// [`BatchError::Hold`] otherwise (NaN, negative, infinite or longer).
    pub fn validated(self) -> Result<Self, BatchError> {
        match self {
            Hold::Fixed(seconds) if !(0.0..=MAX_HOLD).contains(&seconds) => {
                Err(BatchError::Hold(seconds))
            }
            hold => Ok(hold),
        }
    }

    /// Whether the hold is over after `held` frames, the robot finished for the last
    /// `finished` of them and settled after `settle` seconds of that.
    fn is_over(self, held: u64, finished: u64, settle: f64) -> bool {
        match self {
            Hold::Fixed(seconds) => held > hold_frames(seconds),
            Hold::UntilFinished => held > hold_frames(HOLD_CAP) || finished > hold_frames(settle),
        }
    }

    /// The most frames the hold can take.
    pub fn max_frames(self) -> u64 {
        hold_frames(match self {
            Hold::Fixed(seconds) => seconds,
            Hold::UntilFinished => HOLD_CAP,
        })
    }
}

/// Frames of a hold of `hold` seconds ([`HOLD_STEP`] apart): counted, not accumulated in
/// floating point, so 0.5 s is 60 frames.
pub fn hold_frames(hold: f64) -> u64 {
    (hold / HOLD_STEP + 1e-6).floor() as u64
}

/// Imitates every frame of `source` (read from `path`, named in errors) with `imitator`, then
/// holds the human's last pose ([`Hold`]: a number of seconds, or until the robot has
/// finished; frames 1/120 s apart) so that the robot can finish the step it is taking. A frame the imitator asks for again
/// ([`RobotFrame::awaiting_contact`]: a hand being placed before its contact) is fed again, so
/// the human's clock pauses while the robot's runs on. Calls `each` with every robot frame, in
/// order; returns the
/// metrics of the run, the clip's end marked before the hold
/// ([`MetricsRecorder::mark_clip_end`]). The one clip loop of batch retargeting and of the
/// `imitate` example.
///
/// # Errors
/// [`BatchError::Hold`] for a hold out of range (before any frame), [`BatchError::Clip`] for a
/// read error, [`BatchError::EmptyClip`] when the clip has no frame, [`BatchError::Imitation`]
/// naming the frame.
pub fn imitate_clip(
    path: &Path,
    source: impl FrameSource,
    imitator: &mut Imitator,
    hold: impl Into<Hold>,
    mut each: impl FnMut(&RobotFrame),
) -> Result<ImitationMetrics, BatchError> {
    imitate_clip_measured(path, source, imitator, hold, |frame, _| each(frame))
}

/// [`imitate_clip`], calling `each` with every robot frame and the metrics recorded so far
/// (that frame's included): for outputs that show a frame's metrics as the run goes, such as
/// the part of each hand's error no arm posture removes
/// ([`MetricsRecorder::last_least_hand_errors`]).
///
/// # Errors
/// As [`imitate_clip`].
pub fn imitate_clip_measured(
    path: &Path,
    mut source: impl FrameSource,
    imitator: &mut Imitator,
    hold: impl Into<Hold>,
    mut each: impl FnMut(&RobotFrame, &MetricsRecorder),
) -> Result<ImitationMetrics, BatchError> {
    let hold = hold.into().validated()?;
    let settle = SETTLE_TIME + imitator.profile().sway_period.unwrap_or(0.0);
    let mut recorder = MetricsRecorder::new(imitator);
    let mut frame = HumanFrame::new(0.0);
    let mut last: Option<HumanFrame> = None;
    let (mut held_frames, mut finished_frames) = (0, 0);
    let mut clip_end = None;
    let mut again = false;
    let mut index = 0;
    loop {
        let more = again
            || (source.read_frame(&mut frame)).map_err(|source| BatchError::Clip {
                path: path.to_path_buf(),
                source,
            })?;
        index += usize::from(!again);
        if more {
            last = Some(frame);
        } else {
            // The clip is over: the human holds the last pose while the robot finishes.
            let Some(held) = last.as_mut() else {
                return Err(BatchError::EmptyClip {
                    path: path.to_path_buf(),
                });
            };
            let end = *clip_end.get_or_insert_with(|| {
                recorder.mark_clip_end();
                held.time
            });
            held_frames += 1;
            if hold.is_over(held_frames, finished_frames, settle) {
                break;
            }
            held.time = end + held_frames as f64 * HOLD_STEP;
            frame = *held;
        }
        let robot = imitator
            .step(&frame)
            .map_err(|source| BatchError::Imitation {
                path: path.to_path_buf(),
                frame: index - 1,
                source,
            })?;
        again = robot.awaiting_contact;
        finished_frames = if robot.has_finished() && clip_end.is_some() {
            finished_frames + 1
        } else {
            0
        };
        recorder.record(robot);
        each(robot, &recorder);
    }
    Ok(recorder.finish())
}

/// Retargets one clip to `options.robot` and writes `joints.csv` and `metrics.json` into
/// `output` (created once the clip is open, before any frame is imitated). `joints.csv` is
/// written as the frames come, so memory stays flat however long the clip. Both are written
/// as `NAME.partial` and renamed when the run has succeeded; a failed run removes them and
/// leaves an earlier run's files as they were. The clip is prepared by [`ClipSession`] with
/// `options.setup` (`options.imitator.support` is replaced by the clip's defaults).
pub fn retarget_clip(
    options: &BatchOptions,
    clip: &Path,
    output: &Path,
) -> Result<ClipSummary, BatchError> {
    let start = Instant::now();
    let io = |file: &Path| {
        let file = file.to_path_buf();
        move |source| BatchError::Io { path: file, source }
    };
    let session = ClipSession::open(clip, &options.setup)?;
    std::fs::create_dir_all(output).map_err(io(output))?;
    let joints_path = output.join("joints.csv");
    let metrics_path = output.join("metrics.json");
    let [joints_partial, metrics_partial] = [&joints_path, &metrics_path].map(|p| partial(p));
    let result = write_clip(options, clip, session, &joints_partial, &metrics_partial);
    let result = result.and_then(|summary| {
        std::fs::rename(&joints_partial, &joints_path).map_err(io(&joints_path))?;
        std::fs::rename(&metrics_partial, &metrics_path).map_err(io(&metrics_path))?;
        Ok(summary)
    });
    if result.is_err() {
        let _ = std::fs::remove_file(&joints_partial);
        let _ = std::fs::remove_file(&metrics_partial);
    }
    let mut summary = result?;
    summary.wall_time = start.elapsed().as_secs_f64();
    Ok(summary)
}

/// `path` with `.partial` appended: where an output is written until its run has succeeded.
fn partial(path: &Path) -> PathBuf {
    let mut name = path.as_os_str().to_owned();
    name.push(".partial");
    PathBuf::from(name)
}

/// The run of [`retarget_clip`], writing `joints.csv` and `metrics.json` to the given paths.
fn write_clip(
    options: &BatchOptions,
    clip: &Path,
    session: ClipSession,
    joints_path: &Path,
    metrics_path: &Path,
) -> Result<ClipSummary, BatchError> {
    let path = || clip.to_path_buf();
    let io = |file: &Path| {
        let file = file.to_path_buf();
        move |source| BatchError::Io { path: file, source }
    };
    let file = std::fs::File::create(joints_path).map_err(io(joints_path))?;
    let mut joints = JointsWriter::new(std::io::BufWriter::new(file));
    let config = session.config(&options.imitator)?;
    let robot = options.robot.clone();
    let mut imitator = Imitator::new(robot, config).map_err(|source| BatchError::Imitation {
        path: path(),
        frame: 0,
        source,
    })?;
    joints.header(&imitator).map_err(io(joints_path))?;
    let mut written = Ok(());
    let each = |frame: &RobotFrame| {
        if written.is_ok() {
            written = joints.frame(frame);
        }
    };
    let metrics = imitate_clip(clip, session.into_clip(), &mut imitator, options.hold, each)?;
    written
        .and_then(|()| joints.finish())
        .map_err(io(joints_path))?;
    std::fs::write(metrics_path, metrics_json(&metrics, clip)).map_err(io(metrics_path))?;
    let hand = |name: &str| {
        let e = metrics.effectors.iter().find(|e| e.name == name)?;
        e.mean()
    };
    Ok(ClipSummary {
        frames: metrics.frames,
        duration: metrics.duration,
        wall_time: 0.0,
        robot_support_changes: metrics.robot_support_changes,
        min_com_margin: metrics.min_com_margin,
        frames_com_outside: metrics.frames_com_outside,
        joint_limit_violations: metrics.joint_limit_violations,
        velocity_limit_violations: metrics.velocity_limit_violations,
        max_support_slip: metrics.max_support_slip,
        max_held_foot_slip: metrics.max_held_foot_slip,
        hand_tracking_mean: [hand("l_hand"), hand("r_hand")],
        metrics,
    })
}

/// The metrics of a run of `clip` as pretty-printed JSON: [`metrics_value`].
pub fn metrics_json(m: &ImitationMetrics, clip: &Path) -> String {
    // A `Value` built by `json!` always serialises.
    serde_json::to_string_pretty(&metrics_value(m, clip)).unwrap_or_default() + "\n"
}

/// The metrics of a run of `clip` as a JSON value (the fields of [`ImitationMetrics`] with
/// their units in the key names; non-finite numbers become `null`).
// One function on purpose (~105 lines): the layout of `metrics.json` in one place, one key per
// line, as a reader of the file sees it.
pub fn metrics_value(m: &ImitationMetrics, clip: &Path) -> Value {
    // A cell with no samples has no mean or maximum: `null`, not a 0 that reads as perfect.
    let some = |count: usize, v: f64| (count > 0).then_some(v);
    let mean_max = |m: &MeanMax| json!({ "mean": some(m.count, m.mean), "max": some(m.count, m.max), "frames": m.count });
    let spread = |s: &Spread| {
        let v = |x| some(s.count, x);
        json!({ "min": v(s.min), "median": v(s.median), "p99": v(s.p99), "max": v(s.max), "count": s.count })
    };
    let effector_map = |effectors: &[EffectorError]| -> serde_json::Map<String, Value> {
        effectors
            .iter()
            .map(|e| {
                let value = json!({
                    "single_support_m": mean_max(&e.single_support),
                    "double_support_m": mean_max(&e.double_support),
                    "transitions_m": mean_max(&e.transitions),
                });
                (e.name.to_string(), value)
            })
            .collect()
    };
    let effectors = effector_map(&m.effectors);
    json!({
        "clip": clip.file_name().map(|f| f.to_string_lossy().into_owned()),
        "frames": m.frames,
        "duration_s": m.duration,
        "clip_frames": m.clip_frames,
        "clip_duration_s": m.clip_duration,
        "human_clock_pause_s": m.human_clock_pause,
        "held_hands": m.held_hands.map(|hands| {
            let hand = |h: &crate::imitation::metrics::HeldHand| json!({
                "contacts": h.contacts,
                "time_to_place_s": spread(&h.time_to_place),
                "held_distance_m": mean_max(&h.held_distance),
            });
            json!({ "l_hand": hand(&hands[0]), "r_hand": hand(&hands[1]) })
        }),
        "hold_s": m.duration - m.clip_duration,
        "finished": m.finished,
        "human_support_changes": m.human_support_changes,
        "robot_support_changes": m.robot_support_changes,
        "robot_support_sequence": m.robot_support_sequence,
        "transition_durations_s": spread(&m.transition_durations),
        "tracking_error": effectors,
        "min_com_margin_m": m.min_com_margin,
        "frames_com_outside_support": m.frames_com_outside,
        "joint_limit_violations": m.joint_limit_violations,
        "velocity_limit_violations": m.velocity_limit_violations,
        "joint_reversal_frames": m.joint_reversal_frames,
        "max_support_foot_slip_m": m.max_support_slip,
        "max_support_foot_turn_rad": m.max_support_turn,
        "max_held_foot_slip_m": m.max_held_foot_slip,
        "max_held_foot_turn_rad": m.max_held_foot_turn,
        "solve_time_us": spread(&m.solve_time_us),
        "self_clearance": m.self_clearance.as_ref().map(|c| json!({
            "min_distance_m": c.min_distance,
            "closest": c.closest,
            "margin_m": c.margin,
            "frames_below_margin": c.frames_below_margin,
        })),
        "tracking_error_clip": effector_map(&m.effectors_clip),
        "clip_support_frames": {
            "single": m.clip_support_frames.single,
            "double": m.clip_support_frames.double,
            "transitions": m.clip_support_frames.transitions,
        },
        "tracking_error_clip_lag_removed": effector_map(&m.hands_clip_lag_removed),
        "hand_lag_s": m.hand_lag_s,
        "hand_timing": m.hand_timing().map(|t| json!({
            "lag_s": t.lag_s,
            "error_m": t.error_m,
            "lag_removed_error_m": t.lag_removed_error_m,
            "removed_share": t.removed_share(),
            "late": t.late(),
        })),
        "hand_reach": m.hand_reach.map(|arms| {
            let arm = |r: &crate::imitation::reach::HandReach| json!({
                "reach_m": r.reach_m,
                "min_reach_m": r.min_reach_m,
                "frames": r.frames,
                "unreachable_frames": r.unreachable_frames,
                "shortfall_m": { "mean": r.mean_shortfall_m, "max": r.max_shortfall_m },
                "error_m": r.mean_error_m,
                "least_error_m": { "mean": r.mean_least_error_m, "max": r.max_least_error_m },
                "posture_unreachable_frames": r.posture_unreachable_frames,
            });
            json!({ "l_hand": arm(&arms[0]), "r_hand": arm(&arms[1]) })
        }),
        "travel": {
            "scaled_human_m": m.travel.scaled_human_m,
            "robot_m": m.travel.robot_m,
            "heading_error_rad": m.travel.heading_error_rad,
            "error_m": m.travel.error_m,
        },
        "steps": {
            "human": m.human_steps,
            "robot": m.robot_steps,
            "queued_at_end": m.queued_steps_at_end,
        },
        "catch_up_s": m.catch_up_s,
        "foot_lag_s": {
            "lift": spread(&m.lift_lag),
            "landing": spread(&m.landing_lag),
            "human_lifts": m.human_lifts,
        },
        "walking": walking_value(m),
    })
}

/// `metrics.json`'s `walking`: how the robot followed the human's steps (when the human
/// stepped) and what its walks did (when it walked with the pattern generator; `null` fields
/// otherwise); `null` when neither.
fn walking_value(m: &ImitationMetrics) -> Value {
    if m.walking.is_none() && m.following.is_none() {
        return Value::Null;
    }
    let w = m.walking.as_ref();
    let f = m.following.as_ref();
    json!({
        "steps": w.map(|w| w.steps),
        "mean_speed_m_s": w.map(|w| w.mean_speed_m_s),
        "step_duration_s": w.and_then(|w| w.step_duration_s),
        "zmp_margin_min_m": w.map(|w| w.zmp_margin_min_m),
        "walking_s": w.map(|w| w.walking_s),
        "human_steps": f.map(|f| f.human_steps),
        "matched_steps": f.map(|f| f.matched_steps),
        "matched_share": f.map(StepFollowing::matched_share),
        "catch_up_s": f.and_then(|f| f.catch_up_s),
        "travel_error_m": m.travel.error_m,
        "heading_error_deg": m.travel.heading_error_rad.to_degrees(),
    })
}
