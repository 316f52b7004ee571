//! One clip imitated into one output folder, every output streamed as the frames come: the
//! shared work of `imitate` and `batch`.

use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use serde_json::json;
use taskstack::batch::{Hold, JointsWriter, imitate_clip, metrics_json};
use taskstack::imitation::metrics::ImitationMetrics;
use taskstack::imitation::support::SupportConfig;
use taskstack::io::skeleton_map::SkeletonMap;
use taskstack::robots::BipedProfile;
use taskstack::{Imitator, ImitatorConfig, RobotFrame};

use crate::options::open_clip;
use crate::plots::PlotRecorder;
use crate::view::ViewWriter;

/// The files each run writes into its output folder.
pub(crate) const OUTPUT_FILES: [&str; 7] = [
    "joints.csv",
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
    pub(crate) map: Option<SkeletonMap>,
}

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
    let source = open_clip(clip, settings.map.as_ref())?;
    let hold_frames = settings.hold.max_frames();
    progress(Progress::Start(
        source.declared_frames().map(|n| n + hold_frames),
    ));
    std::fs::create_dir_all(out)
        .with_context(|| format!("output folder {}: cannot create it", out.display()))?;
    let create = |name: &str| -> Result<BufWriter<File>> {
        let path = out.join(name);
        let file = File::create(&path)
            .with_context(|| format!("output folder {}: cannot write {name}", out.display()))?;
        Ok(BufWriter::new(file))
    };
    let mut joints = JointsWriter::new(create("joints.csv")?);
    let view_file = create("view.html")?;
    let config = ImitatorConfig {
        support: SupportConfig::for_capture(source.capture()),
        ..settings.config.clone()
    };
    let mut imitator = Imitator::new(settings.profile.clone(), config)
        .with_context(|| format!("robot {}", settings.profile.name))?;
    let title = clip
        .file_stem()
        .map_or_else(String::new, |s| s.to_string_lossy().into_owned());
    let mut view = ViewWriter::new(view_file, imitator.profile(), &title)?;
    let mut plots = PlotRecorder::new(&imitator);
    joints.header(&imitator)?;

    // Writing errors stop the outputs, not the loop; they are reported after it.
    let mut written: Result<()> = Ok(());
    let mut done = 0u64;
    let mut first_time = None;
    let each = |frame: &RobotFrame| {
        first_time.get_or_insert(frame.time);
        if written.is_ok() {
            written = joints
                .frame(frame)
                .map_err(anyhow::Error::from)
                .and_then(|()| view.frame(frame));
        }
        plots.record(frame);
        done += 1;
        if done.is_multiple_of(32) {
            progress(Progress::Frames(done));
        }
    };
    let metrics = imitate_clip(clip, source, &mut imitator, settings.hold, each)?;
    progress(Progress::Frames(done));
    let in_folder = || format!("output folder {}", out.display());
    written.with_context(in_folder)?;
    joints.finish().with_context(in_folder)?;
    let clip_end = first_time.unwrap_or(0.0) + metrics.clip_duration;
    let summary = json!({ "frames": metrics.frames, "clip_frames": metrics.clip_frames,
                          "robot_support_sequence": metrics.robot_support_sequence });
    view.finish(clip_end, summary).with_context(in_folder)?;
    write(out, "metrics.json", metrics_json(&metrics, clip))?;
    for (name, svg) in plots.render(&title) {
        write(out, name, svg)?;
    }
    Ok(metrics)
}

fn write(out: &Path, name: &str, text: String) -> Result<()> {
    std::fs::write(out.join(name), text)
        .with_context(|| format!("output folder {}: cannot write {name}", out.display()))
}

/// The default output folder of a clip: `taskstack-out/<clip file stem>`.
pub(crate) fn default_out(clip: &Path) -> PathBuf {
    let stem = clip.file_stem().unwrap_or(clip.as_os_str());
    Path::new("taskstack-out").join(stem)
}
