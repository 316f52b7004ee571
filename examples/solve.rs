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

use std::process::ExitCode;

use taskstack::problem::{Problem, solve_frames};

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
    let solution = solve_frames(&problem, frames.unwrap_or(problem.frames), repeats)?;
    println!("{}", solution.to_json(&problem, repeats));
    Ok(())
}
