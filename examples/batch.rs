//! Batch retargeting of a folder of clips across cores (`taskstack::batch`).
//!
//! `cargo run --release --example batch -- [DIR_WITH_CLIPS] [--out DIR] [--threads N]`
//!
//! Retargets every `.bvh` and `.csv` clip of the folder (default: the bundled
//! `tests/data/mocap`) onto the NAO, writing `OUT/<clip>/joints.csv` and `OUT/<clip>/metrics.json`
//! (OUT defaults to `target/batch`), with N worker threads (default 0: one per core). Prints one
//! line per clip and the throughput in clips/s and frames/s.

use std::path::PathBuf;
use std::process::ExitCode;

use taskstack::batch::{BatchOptions, BatchSummary, clips_in, retarget_all};

const DEFAULT_DIR: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/mocap");

fn main() -> ExitCode {
    let mut dir = PathBuf::from(DEFAULT_DIR);
    let mut out = PathBuf::from("target/batch");
    let mut options = BatchOptions::default();
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--out" => match args.next() {
                Some(d) => out = d.into(),
                None => return usage(),
            },
            "--threads" => match args.next().and_then(|v| v.parse().ok()) {
                Some(n) => options.threads = n,
                None => return usage(),
            },
            _ if a.starts_with("--") => return usage(),
            _ => dir = a.into(),
        }
    }
    let summary = clips_in(&dir).and_then(|clips| retarget_all(&clips, &out, &options));
    match summary {
        Ok(summary) => {
            print_summary(&summary);
            if summary.succeeded().count() == summary.clips.len() {
                ExitCode::SUCCESS
            } else {
                ExitCode::FAILURE
            }
        }
        Err(e) => {
            eprintln!("batch: {e}");
            ExitCode::FAILURE
        }
    }
}

fn usage() -> ExitCode {
    eprintln!("usage: batch [DIR_WITH_CLIPS] [--out DIR] [--threads N]");
    ExitCode::from(2)
}

fn print_summary(s: &BatchSummary) {
    println!(
        "{:<48} {:>6} {:>7} {:>7} {:>5} {:>9} {:>5} {:>5} {:>9} {:>7} {:>7}",
        "clip",
        "frames",
        "dur s",
        "wall s",
        "supp",
        "CoM mrg m",
        "jlim",
        "vlim",
        "slip m",
        "lhand m",
        "rhand m"
    );
    let hand = |h: Option<f64>| h.map_or("-".to_string(), |v| format!("{v:.4}"));
    for c in &s.clips {
        let name = c.clip.file_name().unwrap_or_default().to_string_lossy();
        match &c.result {
            Ok(r) => println!(
                "{:<48} {:>6} {:>7.2} {:>7.2} {:>5} {:>9.4} {:>5} {:>5} {:>9.1e} {:>7} {:>7}",
                name,
                r.frames,
                r.duration,
                r.wall_time,
                r.robot_support_changes,
                r.min_com_margin,
                r.joint_limit_violations,
                r.velocity_limit_violations,
                r.max_support_slip,
                hand(r.hand_tracking_mean[0]),
                hand(r.hand_tracking_mean[1]),
            ),
            Err(e) => println!("{name:<48} FAILED: {e}"),
        }
    }
    println!(
        "{} clips ({} failed), {} frames in {:.2} s on {} threads: {:.2} clips/s, {:.0} frames/s",
        s.clips.len(),
        s.clips.len() - s.succeeded().count(),
        s.frames(),
        s.wall_time,
        s.threads,
        s.clips_per_second(),
        s.frames_per_second()
    );
    if let Some(c) = s.clips.first() {
        let out = c.output.parent().unwrap_or(&c.output);
        println!(
            "wrote {}/<clip>/{{joints.csv, metrics.json}}",
            out.display()
        );
    }
}
