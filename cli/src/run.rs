//! One clip imitated into one output folder, every output streamed as the frames come: the
//! shared work of `imitate` and `batch`.
//!
//! Outputs appear whole or not at all: every file is written as `NAME.partial` and renamed to
//! `NAME` only when the whole run has succeeded; a failed run removes its partial files, so a
//! folder holds either the complete outputs of one run or those of an earlier one.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use serde_json::json;
use taskstack::batch::{ClipSession, ClipSetup, Hold, imitate_clip_measured, metrics_json};
use taskstack::export::JointsWriter;
use taskstack::export::{MotionRecorder, MotionTrack, write_motion_npz, write_unitree_csv};
use taskstack::imitation::metrics::{ImitationMetrics, MetricsRecorder};
use taskstack::io::FrameSource;
use taskstack::robots::BipedProfile;
use taskstack::{Imitator, ImitatorConfig, RobotFrame};

use crate::options::Exports;
use crate::plots::PlotRecorder;
use crate::view::ViewWriter;

/// The files each run writes into its output folder (and `motion_unitree.csv` with
/// `--export unitree-csv`).
pub(crate) const OUTPUT_FILES: [&str; 8] = [
    "joints.csv",
    "motion.npz",
    "metrics.json",
    "view.html",
    "effectors.svg",
    "com.svg",
    "phases.svg",
    "joints.svg",
];

/// What every clip of a run shares.
#[derive(Debug, Clone)]
pub(crate) struct Settings {
    pub(crate) profile: BipedProfile,
    pub(crate) config: ImitatorConfig,
    pub(crate) hold: Hold,
    pub(crate) setup: ClipSetup,
    pub(crate) exports: Exports,
}

/// The files a run with `exports` writes.
pub(crate) fn output_files(exports: Exports) -> Vec<&'static str> {
    let unitree = exports.unitree_csv.then_some("motion_unitree.csv");
    OUTPUT_FILES.into_iter().chain(unitree).collect()
}

/// The frame rate of Unitree's retargeted LAFAN1 dataset (Hz).
const UNITREE_FPS: f64 = 30.0;

/// Progress of a run: the frames expected (clip header + hold; `None` when the clip does not
/// say), then the frames done so far.
pub(crate) enum Progress {
    Start(Option<u64>),
    Frames(u64),
}

/// Imitates `clip` into `out` (created if needed): see [`OUTPUT_FILES`]. The clip is opened
/// and the folder and its files created before the first frame is imitated, so a bad input or
/// an unwritable folder fails at once, naming the culprit.
pub(crate) fn imitate_into(
    clip: &Path,
    out: &Path,
    settings: &Settings,
    progress: &mut dyn FnMut(Progress),
) -> Result<ImitationMetrics> {
    if clip.is_dir() {
        anyhow::bail!("clip {}: is a folder, not a clip file", clip.display());
    }
    let session = ClipSession::open(clip, &settings.setup)?;
    let hold_frames = settings.hold.max_frames();
    progress(Progress::Start(
        session.clip().declared_frames().map(|n| n + hold_frames),
    ));
    let config = session.config(&settings.config)?;
    let mut run = Run {
        name: clip,
        config,
        settings,
        commands: None,
        on_frame: None,
    };
    staged_run(out, |staged| {
        let metrics = run.imitate(session.into_clip(), staged, progress)?;
        staged.write("metrics.json", metrics_json(&metrics, clip))?;
        Ok(metrics)
    })
}

/// One run: its name (the clip's path; a live session's input), its imitator settings, a
/// second `joints.csv` stream of the commands as they come and what else sees each frame (a
/// live session's view).
pub(crate) struct Run<'a> {
    pub(crate) name: &'a Path,
    pub(crate) config: ImitatorConfig,
    pub(crate) settings: &'a Settings,
    pub(crate) commands: Option<&'a mut dyn Write>,
    pub(crate) on_frame: Option<&'a mut dyn FnMut(&RobotFrame)>,
}

/// Runs `imitate` into the output folder `out` (created if needed) with its files staged:
/// committed when it succeeds, discarded when it fails.
pub(crate) fn staged_run(
    out: &Path,
    imitate: impl FnOnce(&mut Staged) -> Result<ImitationMetrics>,
) -> Result<ImitationMetrics> {
    std::fs::create_dir_all(out)
        .with_context(|| format!("output folder {}: cannot create it", out.display()))?;
    let mut staged = Staged::new(out);
    let result = imitate(&mut staged);
    match result {
        Ok(metrics) => staged.commit().map(|()| metrics),
        Err(err) => {
            staged.discard();
            Err(err)
        }
    }
}

impl Run<'_> {
    /// The run itself, every file but `metrics.json` written through `staged`.
    pub(crate) fn imitate(
        &mut self,
        source: impl FrameSource,
        staged: &mut Staged,
        progress: &mut dyn FnMut(Progress),
    ) -> Result<ImitationMetrics> {
        let settings = self.settings;
        let mut joints = JointsWriter::new(staged.create("joints.csv")?);
        let view_file = staged.create("view.html")?;
        let mut imitator = Imitator::new(settings.profile.clone(), self.config.clone())
            .with_context(|| format!("robot {}", settings.profile.name))?;
        let title =
            (self.name.file_stem()).map_or_else(String::new, |s| s.to_string_lossy().into_owned());
        let mut view = ViewWriter::new(view_file, imitator.profile(), &title)?;
        let mut plots = PlotRecorder::new(&imitator);
        let mut motion = MotionRecorder::new(&imitator)?;
        joints.header(&imitator)?;
        let mut commands = self.commands.as_mut().map(|w| JointsWriter::new(&mut **w));
        if let Some(commands) = commands.as_mut() {
            commands.header(&imitator).context("the commands' output")?;
        }

        // Writing errors stop the outputs, not the loop; they are reported after it.
        let mut written: Result<()> = Ok(());
        let mut done = 0u64;
        let mut first_time = None;
        let each = |frame: &RobotFrame, measured: &MetricsRecorder| {
            first_time.get_or_insert(frame.time);
            if written.is_ok() {
                written = joints
                    .frame(frame)
                    .map_err(anyhow::Error::from)
                    .and_then(|()| view.frame(frame))
                    .and_then(|()| Ok(motion.record(frame)?));
            }
            // A live consumer that goes away does not stop the session.
            if let Some(out) = commands.as_mut() {
                let _ = out.frame(frame);
            }
            if let Some(on_frame) = self.on_frame.as_mut() {
                on_frame(frame);
            }
            plots.record(frame, measured.last_least_hand_errors());
            done += 1;
            if done.is_multiple_of(32) {
                progress(Progress::Frames(done));
            }
        };
        let metrics = imitate_clip_measured(self.name, source, &mut imitator, settings.hold, each)?;
        progress(Progress::Frames(done));
        let in_folder = || format!("output folder {}", staged.out.display());
        written.with_context(in_folder)?;
        joints.finish().with_context(in_folder)?;
        let clip_end = first_time.unwrap_or(0.0) + metrics.clip_duration;
        let summary = json!({ "frames": metrics.frames, "clip_frames": metrics.clip_frames,
                              "robot_support_sequence": metrics.robot_support_sequence });
        view.finish(clip_end, summary).with_context(in_folder)?;
        write_exports(
            staged,
            &motion.finish(),
            metrics.clip_frames,
            settings.exports,
        )?;
        for (name, svg) in plots.render(&title) {
            staged.write(name, svg)?;
        }
        Ok(metrics)
    }
}

/// `motion.npz`, and the Unitree CSV when asked, of `track` (the clip its first
/// `clip_frames`).
fn write_exports(
    staged: &mut Staged,
    track: &MotionTrack,
    clip_frames: usize,
    exports: Exports,
) -> Result<()> {
    let folder = staged.out.clone();
    let in_folder = || format!("output folder {}", folder.display());
    let rate = exports
        .fps
        .or_else(|| track.nominal_rate(clip_frames))
        .unwrap_or(UNITREE_FPS);
    write_motion_npz(staged.create("motion.npz")?, track, rate).with_context(in_folder)?;
    if exports.unitree_csv {
        let file = staged.create("motion_unitree.csv")?;
        write_unitree_csv(file, track, exports.fps.unwrap_or(UNITREE_FPS))
            .with_context(in_folder)?;
    }
    Ok(())
}

/// The files of one run, written as `NAME.partial` until [`Staged::commit`].
pub(crate) struct Staged {
    out: PathBuf,
    names: Vec<String>,
}

impl Staged {
    fn new(out: &Path) -> Self {
        Self {
            out: out.to_path_buf(),
            names: Vec::new(),
        }
    }

    fn partial(&self, name: &str) -> PathBuf {
        self.out.join(format!("{name}.partial"))
    }

    /// A new staged file `name`.
    fn create(&mut self, name: &str) -> Result<BufWriter<File>> {
        let file = File::create(self.partial(name)).with_context(|| {
            format!("output folder {}: cannot write {name}", self.out.display())
        })?;
        self.names.push(name.to_owned());
        Ok(BufWriter::new(file))
    }

    /// A new staged file `name` holding `text`.
    pub(crate) fn write(&mut self, name: &str, text: String) -> Result<()> {
        std::fs::write(self.partial(name), text).with_context(|| {
            format!("output folder {}: cannot write {name}", self.out.display())
        })?;
        self.names.push(name.to_owned());
        Ok(())
    }

    /// Renames every staged file to its name, replacing an earlier run's; the Unitree CSV of
    /// an earlier run that this one did not write goes, so the folder describes one run.
    fn commit(self) -> Result<()> {
        for name in &self.names {
            let path = self.out.join(name);
            std::fs::rename(self.partial(name), &path).with_context(|| {
                format!("output folder {}: cannot write {name}", self.out.display())
            })?;
        }
        if !self.names.iter().any(|n| n == "motion_unitree.csv") {
            let _ = std::fs::remove_file(self.out.join("motion_unitree.csv"));
        }
        Ok(())
    }

    /// Removes every staged file (a failed run leaves nothing behind).
    fn discard(self) {
        for name in &self.names {
            let _ = std::fs::remove_file(self.partial(name));
        }
    }
}

/// The default output folder of a clip: `taskstack-out/<clip file stem>`.
pub(crate) fn default_out(clip: &Path) -> PathBuf {
    let stem = clip.file_stem().unwrap_or(clip.as_os_str());
    Path::new("taskstack-out").join(stem)
}
