//! `taskstack solve`: a prioritized-IK benchmark problem solved frame by frame.

use std::fmt::Write as _;
use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Context, Result};
use clap::Args;
use taskstack::problem::{Problem, solve_frames};
use taskstack::solver::Method;

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
    /// How each iteration is solved: `prioritized` (strict priorities, what the problem files
    /// ask for) or `dls` (all levels as one damped least-squares problem with Chan & Dubey's
    /// weighted least-norm joint-limit avoidance; no priorities).
    #[arg(long, value_enum, default_value_t = SolveMethod::Prioritized)]
    method: SolveMethod,
    /// Damping factor λ of --method dls (m per rad).
    #[arg(long, value_name = "LAMBDA", default_value_t = 0.01, value_parser = crate::options::positive,
          allow_negative_numbers = true)]
    damping: f64,
    /// Solve the CoM task as an inequality instead of a target point: its ground projection
    /// inside the support polygon (the soles on the ground at the initial posture) shrunk by
    /// MARGIN metres, at the CoM task's level.
    #[arg(long, value_name = "MARGIN", value_parser = crate::options::non_negative)]
    com_polygon: Option<f64>,
}

/// The solver method of `taskstack solve`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum SolveMethod {
    /// Strict priorities by null-space projection.
    Prioritized,
    /// Weighted damped least squares (Chan & Dubey 1995).
    Dls,
}

pub(crate) fn run(args: SolveArgs, report: Report) -> Result<ExitCode> {
    let path = &args.problem;
    let in_file = || format!("problem {}", path.display());
    let source = std::fs::read_to_string(path).with_context(in_file)?;
    let mut problem = Problem::from_json(&source).with_context(in_file)?;
    problem.method = match args.method {
        SolveMethod::Prioritized => Method::Prioritized,
        SolveMethod::Dls => Method::WeightedDls {
            damping: args.damping,
        },
    };
    problem.com_polygon_margin = args.com_polygon;
    let count = args.frames.map_or(problem.frames, |n| n as usize);
    let repeats = args.repeats as usize;
    let solution = solve_frames(&problem, count, repeats).with_context(in_file)?;
    let mut text = String::new();
    if report.json {
        let _ = writeln!(text, "{}", solution.to_json(&problem, repeats));
    } else if !report.quiet {
        let frames = solution.frames.len();
        let _ = writeln!(
            text,
            "{}: {frames} frames × {repeats} runs, {} frames converged, {:.2} iterations per frame, {} limit violations",
            problem.label,
            solution.converged_frames,
            solution.iterations as f64 / frames.max(1) as f64,
            solution.limit_violations
        );
        let _ = writeln!(text, "worst error per task (m):");
        for (name, w) in problem.task_names().iter().zip(&solution.worst) {
            let _ = writeln!(text, "  {name:24} {w:.2e}");
        }
        let _ = writeln!(
            text,
            "time per frame: median {:.1} µs, 99th percentile {:.1} µs, max {:.1} µs",
            solution.time_quantile(0.5),
            solution.time_quantile(0.99),
            solution.time_quantile(1.0)
        );
    }
    crate::output(&text)?;
    Ok(ExitCode::SUCCESS)
}
