//! `taskstack solve`: a prioritized-IK benchmark problem solved frame by frame.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Context, Result};
use clap::Args;
use serde_json::json;
use taskstack::problem::{Problem, Runner};
use taskstack::solver::driver::StopReason;

use crate::Report;

/// Solve a prioritized-IK benchmark problem file frame by frame.
///
/// Reads a problem file (schema nao-prioritized-ik-benchmark/1: the robot's joint order and
/// limits, the initial posture, the task levels and a target trajectory), solves every frame
/// warm-started from the last, and prints a summary: the worst error of each task (m), limit
/// violations, iterations and the time per frame (µs). With --json, the full result: per frame
/// the posture (rad, in the file's joint order), each task's error, iterations and stop reason.
#[derive(Debug, Args)]
pub(crate) struct SolveArgs {
    /// The problem file (JSON).
    #[arg(value_name = "PROBLEM.json")]
    problem: PathBuf,
    /// Solve only the first N frames.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..))]
    frames: Option<u64>,
    /// Run the whole problem R times from its initial posture; the times pool all runs, the
    /// per-frame results are the last run's.
    #[arg(long, value_name = "R", default_value_t = 1, value_parser = clap::value_parser!(u64).range(1..=10_000))]
    repeats: u64,
}

pub(crate) fn run(args: SolveArgs, report: Report) -> Result<ExitCode> {
    let path = &args.problem;
    let in_file = || format!("problem {}", path.display());
    let source = std::fs::read_to_string(path).with_context(in_file)?;
    let problem = Problem::from_json(&source).with_context(in_file)?;
    let count = (args.frames.map_or(problem.frames, |n| n as usize)).min(problem.frames);
    let repeats = args.repeats as usize;
    let mut runs = solve_all(&problem, count, repeats, report.json).with_context(in_file)?;
    runs.times.sort_by(f64::total_cmp);
    let times = &runs.times;
    let at = |p: f64| {
        let rank = ((times.len().max(1) - 1) as f64 * p).round() as usize;
        times.get(rank).copied().unwrap_or(0.0)
    };
    let (median, p99, max) = (at(0.5), at(0.99), at(1.0));
    let names = problem.task_names();
    let mean_iterations = runs.iterations as f64 / count.max(1) as f64;
    let mut text = String::new();
    if report.json {
        let out = json!({
            "problem": problem.label,
            "joint_order": problem.joint_order,
            "levels": problem.level_names,
            "frames": runs.per_frame,
            "summary": {
                "frames": count, "repeats": repeats, "converged_frames": runs.converged,
                "mean_iterations": mean_iterations,
                "max_error_m": per_task(&names, |t| runs.worst[t]),
                "limit_violations": runs.violations,
                "time_per_frame_us": { "median": median, "p99": p99, "max": max },
            },
        });
        let _ = writeln!(text, "{out}");
    } else if !report.quiet {
        let _ = writeln!(
            text,
            "{}: {count} frames × {repeats} runs, {} frames converged, {mean_iterations:.2} iterations per frame, {} limit violations",
            problem.label, runs.converged, runs.violations
        );
        let _ = writeln!(text, "worst error per task (m):");
        for (name, w) in names.iter().zip(&runs.worst) {
            let _ = writeln!(text, "  {name:24} {w:.2e}");
        }
        let _ = writeln!(
            text,
            "time per frame: median {median:.1} µs, 99th percentile {p99:.1} µs, max {max:.1} µs"
        );
    }
    crate::output(&text)?;
    Ok(ExitCode::SUCCESS)
}

/// What solving a problem gave: the last run's per-frame results (when asked for) and totals,
/// the solve times of every run (µs).
struct Runs {
    per_frame: Vec<serde_json::Value>,
    worst: Vec<f64>,
    violations: usize,
    converged: usize,
    iterations: usize,
    times: Vec<f64>,
}

/// Solves the first `count` frames `repeats` times from the initial posture.
fn solve_all(problem: &Problem, count: usize, repeats: usize, per_frame: bool) -> Result<Runs> {
    let names = problem.task_names();
    let mut runner = Runner::new(problem)?;
    let mut runs = Runs {
        per_frame: Vec::new(),
        worst: vec![0.0; names.len()],
        violations: 0,
        converged: 0,
        iterations: 0,
        times: Vec::with_capacity(count * repeats),
    };
    for repeat in 0..repeats {
        let mut q = problem.q_init.clone();
        let last = repeat + 1 == repeats;
        for frame in 0..count {
            let result = runner
                .solve_frame(frame, &mut q)
                .with_context(|| format!("frame {frame}"))?;
            runs.times.push(result.micros);
            if !last {
                continue;
            }
            let bounds = problem.bounds.lower().iter().zip(problem.bounds.upper());
            runs.violations += q
                .iter()
                .zip(bounds)
                .filter(|(v, (lo, hi))| *v < lo || *v > hi)
                .count();
            for (w, e) in runs.worst.iter_mut().zip(&result.errors) {
                *w = w.max(*e);
            }
            runs.converged += usize::from(result.stop == StopReason::Converged);
            runs.iterations += result.iterations;
            if per_frame {
                runs.per_frame.push(json!({
                    "frame": frame,
                    "q": problem.to_joint_order(&q),
                    "errors": per_task(&names, |t| result.errors[t]),
                    "iterations": result.iterations,
                    "stop": format!("{:?}", result.stop).to_lowercase(),
                }));
            }
        }
    }
    Ok(runs)
}

/// Per-task values in a JSON object keyed by task name.
fn per_task(names: &[&str], values: impl Fn(usize) -> f64) -> BTreeMap<String, f64> {
    names
        .iter()
        .enumerate()
        .map(|(i, n)| (n.to_string(), values(i)))
        .collect()
}
