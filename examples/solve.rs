//! Solves a NAO benchmark problem file (`tests/data/bench/problem_*.json`, schema
//! `nao-prioritized-ik-benchmark/1`) frame by frame, warm-started, following the file's protocol,
//! and prints a JSON result: per frame the final q (in the file's `joint_order`), every task's
//! error (m), the iterations and the stop reason; overall the limit violations and the wall time
//! per frame (median/p99/max, µs; targets set + all iterations + stop test).
//!
//! `cargo run --release --example solve -- PROBLEM.json [--frames N] [--repeats R]`
//!
//! With `--repeats R` the whole run is repeated R times from `q_init`; timing statistics pool all
//! runs, the per-frame results are the last run's.

use std::collections::BTreeMap;
use std::process::ExitCode;

use serde_json::json;
use taskstack::problem::{Problem, Runner};
use taskstack::solver::driver::StopReason;

fn usage() -> ExitCode {
    eprintln!("usage: solve PROBLEM.json [--frames N] [--repeats R]");
    ExitCode::from(2)
}

fn main() -> ExitCode {
    let mut args = std::env::args().skip(1);
    let (mut path, mut frames, mut repeats) = (None, None, 1usize);
    while let Some(arg) = args.next() {
        match arg.as_str() {
            "--frames" => match args.next().and_then(|v| v.parse().ok()) {
                Some(n) if n > 0 => frames = Some(n),
                _ => return usage(),
            },
            "--repeats" => match args.next().and_then(|v| v.parse().ok()) {
                Some(r) if r > 0 => repeats = r,
                _ => return usage(),
            },
            _ if path.is_none() && !arg.starts_with("--") => path = Some(arg),
            _ => return usage(),
        }
    }
    let Some(path) = path else { return usage() };
    match run(&path, frames, repeats) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("solve: {path}: {e}");
            ExitCode::FAILURE
        }
    }
}

fn run(
    path: &str,
    frames: Option<usize>,
    repeats: usize,
) -> Result<(), Box<dyn std::error::Error>> {
    let problem = Problem::from_json(&std::fs::read_to_string(path)?)?;
    let count = frames.unwrap_or(problem.frames).min(problem.frames);
    let names = problem.task_names();
    let levels = problem.task_levels();
    let mut runner = Runner::new(&problem)?;
    let mut times = Vec::with_capacity(count * repeats);
    let mut per_frame = Vec::with_capacity(count);
    let mut violations = 0usize;
    let mut worst = vec![0.0_f64; names.len()];
    let (mut converged, mut iterations) = (0usize, 0usize);
    for repeat in 0..repeats {
        let mut q = problem.q_init.clone();
        let last = repeat + 1 == repeats;
        for frame in 0..count {
            let result = runner.solve_frame(frame, &mut q)?;
            times.push(result.micros);
            if !last {
                continue;
            }
            violations += q
                .iter()
                .zip(problem.bounds.lower().iter().zip(problem.bounds.upper()))
                .filter(|(v, (lo, hi))| *v < lo || *v > hi)
                .count();
            for (w, e) in worst.iter_mut().zip(&result.errors) {
                *w = w.max(*e);
            }
            converged += usize::from(result.stop == StopReason::Converged);
            iterations += result.iterations;
            per_frame.push(json!({
                "frame": frame,
                "q": problem.to_joint_order(&q),
                "errors": per_task(&names, |t| result.errors[t]),
                "iterations": result.iterations,
                "stop": format!("{:?}", result.stop).to_lowercase(),
            }));
        }
    }
    let (median, p99, max) = percentiles(&mut times);
    let top_level_worst = worst
        .iter()
        .zip(&levels)
        .filter(|(_, l)| **l == 0)
        .fold(0.0_f64, |m, (w, _)| m.max(*w));
    let out = json!({
        "problem": problem.label,
        "joint_order": problem.joint_order,
        "levels": problem.level_names,
        "frames": per_frame,
        "summary": {
            "frames": count,
            "repeats": repeats,
            "converged_frames": converged,
            "mean_iterations": iterations as f64 / count.max(1) as f64,
            "max_error_m": per_task(&names, |t| worst[t]),
            "max_error_top_level_m": top_level_worst,
            "limit_violations": violations,
            "time_per_frame_us": { "median": median, "p99": p99, "max": max },
        },
    });
    println!("{out}");
    Ok(())
}

/// Median, 99th percentile and maximum of `values` (sorted in place; not empty).
fn percentiles(values: &mut [f64]) -> (f64, f64, f64) {
    values.sort_by(f64::total_cmp);
    let at = |p: f64| values[((values.len() - 1) as f64 * p).round() as usize];
    (at(0.5), at(0.99), values[values.len() - 1])
}

/// Per-task statistics in a JSON object keyed by task name.
fn per_task(names: &[&str], values: impl Fn(usize) -> f64) -> BTreeMap<String, f64> {
    names
        .iter()
        .enumerate()
        .map(|(i, n)| (n.to_string(), values(i)))
        .collect()
}
