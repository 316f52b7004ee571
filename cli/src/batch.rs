//! `taskstack batch`: many clips, one output folder each, in parallel.

use std::collections::HashMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use clap::Args;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use serde_json::json;
use taskstack::batch::clips_in;
use taskstack::imitation::metrics::ImitationMetrics;

use crate::Report;
use crate::options::{ClipOptions, ImitationOptions};
use crate::run::{Settings, imitate_into};

/// Imitate many clips, each into its own folder OUT/<clip name>/, in parallel.
///
/// Every clip gets the outputs of `taskstack imitate` (joints.csv, motion.npz, metrics.json,
/// view.html and the SVG plots; motion_unitree.csv with --export unitree-csv), so a folder of
/// clips becomes a dataset in one command; a clip's files appear only when it succeeded. A clip that fails does not stop the others; the summary table says which
/// failed and why, and the exit status is 1 if any did.
#[derive(Debug, Args)]
pub(crate) struct BatchArgs {
    /// Clip files (.bvh, .csv) and folders; a folder stands for its .bvh and .csv files.
    #[arg(value_name = "DIR|FILE", required = true)]
    inputs: Vec<PathBuf>,
    /// Output folder: each clip writes into OUT/<clip file name without extension>/.
    #[arg(long, short, value_name = "OUT")]
    out: PathBuf,
    /// Clips imitated at once. Default: one per core.
    #[arg(long, short, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=1024))]
    jobs: Option<u32>,
    #[command(flatten)]
    clip_options: ClipOptions,
    #[command(flatten)]
    options: ImitationOptions,
}

struct Done {
    clip: PathBuf,
    out: PathBuf,
    result: Result<ImitationMetrics>,
    seconds: f64,
}

pub(crate) fn run(args: BatchArgs, report: Report) -> Result<ExitCode> {
    let clips = collect_clips(&args.inputs)?;
    let outputs = output_folders(&clips, &args.out)?;
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("output folder {}: cannot create it", args.out.display()))?;
    let settings = Settings {
        profile: args.options.profile()?,
        config: args.options.imitator_config()?,
        hold: args.options.hold,
        setup: args.clip_options.setup(args.options.skeleton_map()?)?,
        exports: args.options.exports(),
    };
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let jobs = (args.jobs.map_or(cores, |j| j as usize))
        .min(clips.len())
        .max(1);
    let bar = progress_bar(clips.len(), report);
    let start = Instant::now();
    let done = imitate_all(&clips, &outputs, &settings, jobs, &bar);
    bar.finish_and_clear();
    let seconds = start.elapsed().as_secs_f64();
    let mut text = String::new();
    if report.json {
        let _ = writeln!(text, "{}", batch_json(&done, jobs, seconds));
    } else {
        print_table(&mut text, &done, report, jobs, seconds);
    }
    crate::output(&text)?;
    let failed = done.iter().any(|d| d.result.is_err());
    Ok(if failed {
        ExitCode::FAILURE
    } else {
        ExitCode::SUCCESS
    })
}

/// Each clip's output folder, `out/<file stem>`; two clips with one folder are an error.
fn output_folders(clips: &[PathBuf], out: &Path) -> Result<Vec<PathBuf>> {
    let mut folders: HashMap<PathBuf, &PathBuf> = HashMap::new();
    let mut outputs = Vec::with_capacity(clips.len());
    for clip in clips {
        let folder = out.join(clip.file_stem().unwrap_or(clip.as_os_str()));
        if let Some(first) = folders.insert(folder.clone(), clip) {
            bail!(
                "clips {} and {} would both write into {}",
                first.display(),
                clip.display(),
                folder.display()
            );
        }
        outputs.push(folder);
    }
    Ok(outputs)
}

/// A bar counting clips, drawn on stderr for people only.
fn progress_bar(clips: usize, report: Report) -> ProgressBar {
    let bar = ProgressBar::with_draw_target(Some(clips as u64), ProgressDrawTarget::hidden());
    if report.human() {
        bar.set_draw_target(ProgressDrawTarget::stderr());
        bar.set_style(
            ProgressStyle::with_template("{bar:30} {pos}/{len} clips, {elapsed} {msg}")
                .unwrap_or_else(|_| ProgressStyle::default_bar()),
        );
    }
    bar
}

/// Imitates every clip into its folder on `jobs` threads, each taking the next clip when it is
/// free; the outcomes sorted by clip path.
fn imitate_all(
    clips: &[PathBuf],
    outputs: &[PathBuf],
    settings: &Settings,
    jobs: usize,
    bar: &ProgressBar,
) -> Vec<Done> {
    let next = AtomicUsize::new(0);
    let done = Mutex::new(Vec::with_capacity(clips.len()));
    std::thread::scope(|scope| {
        for _ in 0..jobs {
            scope.spawn(|| {
                loop {
                    let i = next.fetch_add(1, Ordering::Relaxed);
                    let (Some(clip), Some(out)) = (clips.get(i), outputs.get(i)) else {
                        break;
                    };
                    let began = Instant::now();
                    let result = imitate_into(clip, out, settings, &mut |_| {});
                    bar.set_message(format!("{}", clip.display()));
                    bar.inc(1);
                    let seconds = began.elapsed().as_secs_f64();
                    let outcome = Done {
                        clip: clip.clone(),
                        out: out.clone(),
                        result,
                        seconds,
                    };
                    done.lock().unwrap_or_else(|e| e.into_inner()).push(outcome);
                }
            });
        }
    });
    let mut done = done.into_inner().unwrap_or_else(|e| e.into_inner());
    done.sort_by(|a, b| a.clip.cmp(&b.clip));
    done
}

/// The clips of the inputs: files as given, folders' .bvh and .csv files sorted.
fn collect_clips(inputs: &[PathBuf]) -> Result<Vec<PathBuf>> {
    let mut clips = Vec::new();
    for input in inputs {
        if input.is_dir() {
            let found =
                clips_in(input).with_context(|| format!("input folder {}", input.display()))?;
            if found.is_empty() {
                bail!(
                    "input folder {}: no .bvh or .csv clip in it",
                    input.display()
                );
            }
            clips.extend(found);
        } else if input.is_file() {
            clips.push(input.clone());
        } else {
            bail!("clip {}: no such file or folder", input.display());
        }
    }
    Ok(clips)
}

fn hand_mean(m: &ImitationMetrics, name: &str) -> Option<f64> {
    m.effectors_clip.iter().find(|e| e.name == name)?.mean()
}

fn print_table(text: &mut String, done: &[Done], report: Report, jobs: usize, seconds: f64) {
    for d in done {
        if let Err(e) = &d.result {
            eprintln!("taskstack: error: {}", crate::describe(e));
        }
    }
    if report.quiet {
        return;
    }
    let _ = writeln!(
        text,
        "{:<48} {:>7} {:>7} {:>9} {:>13} {:>13} {:>8} {:>6} {:>7}",
        "clip",
        "frames",
        "clip s",
        "supports",
        "hands cm L/R",
        "of it reach",
        "CoM out",
        "limits",
        "wall s"
    );
    let cm = |v: Option<f64>| v.map_or("-".to_owned(), |v| format!("{:.1}", v * 100.0));
    for d in done {
        let name = d
            .clip
            .file_name()
            .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
        match &d.result {
            Ok(m) => {
                let _ = writeln!(
                    text,
                    "{:<48} {:>7} {:>7.1} {:>9} {:>13} {:>13} {:>8} {:>6} {:>7.1}",
                    name,
                    m.clip_frames,
                    m.clip_duration,
                    format!("{}→{}", m.human_support_changes, m.robot_support_changes),
                    format!(
                        "{}/{}",
                        cm(hand_mean(m, "l_hand")),
                        cm(hand_mean(m, "r_hand"))
                    ),
                    unremovable(m).map_or("-".to_owned(), |[l, r]| format!("{}/{}", cm(l), cm(r))),
                    m.frames_com_outside,
                    m.joint_limit_violations + m.velocity_limit_violations,
                    d.seconds
                );
            }
            Err(_) => {
                let _ = writeln!(text, "{name:<48} FAILED (see above)");
            }
        }
    }
    let ok = done.iter().filter(|d| d.result.is_ok()).count();
    let _ = writeln!(
        text,
        "{ok} of {} clips imitated in {seconds:.1} s on {jobs} threads; supports = human → robot support changes, of it reach = the part of the hand error no arm posture within the joint limits removes, CoM out = frames with the CoM outside the support polygon, limits = joint × frame violations",
        done.len()
    );
}

/// Each hand's mean error over the clip that no arm posture within the joint limits removes
/// (`[left, right]`, m; [`taskstack::imitation::reach`]); `None` when the profile maps no arms.
fn unremovable(m: &ImitationMetrics) -> Option<[Option<f64>; 2]> {
    m.hand_reach.map(|arms| arms.map(|a| a.mean_least_error_m))
}

fn batch_json(done: &[Done], jobs: usize, seconds: f64) -> serde_json::Value {
    let clips: Vec<_> = done
        .iter()
        .map(|d| match &d.result {
            Ok(m) => json!({
                "clip": d.clip, "out": d.out, "ok": true, "wall_time_s": d.seconds,
                "metrics": taskstack::batch::metrics_value(m, &d.clip),
            }),
            Err(e) => {
                json!({ "clip": d.clip, "out": d.out, "ok": false, "error": crate::describe(e) })
            }
        })
        .collect();
    json!({ "clips": clips, "threads": jobs, "wall_time_s": seconds })
}
