//! Where `Imitator::step`'s slow frames go: imitates a clip and prints the step's wall time (µs)
//! per support phase and per number of solver passes (`RobotFrame::solve_passes`; frames,
//! median, p99, max), the passes per frame, and the fifteen slowest frames with their phase,
//! the solver's levels (`rank/rows`, `s` when the level was scaled), clamped joints and passes
//! (marked when the solve did not converge). A step costs a fixed part plus one projection and
//! factorization of every level per pass, so the pass table shows what the tail is made of.
//!
//! `cargo run --release --example step_profile -- CLIP [g1] [koenemann] [--walk | --dynamic-walk]
//! [--max-passes N]` (default: the NAO, Poubel et al.'s method, standing in place, no budget of
//! passes: see `Settings::max_passes`). Koenemann et al.'s method reports no passes (its frames
//! run several IKs of their own), so its pass lines and the slowest frames' solves are left out.

use std::collections::BTreeMap;

use taskstack::human::HumanFrame;
use taskstack::imitation::config::ImitationMethod;
use taskstack::imitation::koenemann::KoenemannConfig;
use taskstack::imitation::output::RobotFrame;
use taskstack::imitation::reference::support::SupportConfig;
use taskstack::io::clip::Clip;
use taskstack::robots::{g1, nao};
use taskstack::{Imitator, ImitatorConfig};

/// One frame's time (µs), index and description.
type Frame = (f64, usize, String);

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let usage =
        "usage: step_profile CLIP [g1] [koenemann] [--walk | --dynamic-walk] [--max-passes N]";
    let clip_path = args.first().ok_or(usage)?;
    let has = |s: &str| args.iter().any(|a| a == s);
    // Koenemann's frames run several IKs of their own and report no solve of the tables.
    let koenemann = has("koenemann");
    let mut clip = Clip::open(clip_path)?;
    let mut config = ImitatorConfig {
        support: SupportConfig::for_capture(clip.capture()),
        ..ImitatorConfig::default()
    };
    if koenemann {
        config.method = ImitationMethod::Koenemann(KoenemannConfig::default());
    }
    if let Some(poubel) = config.poubel_mut() {
        poubel.footsteps.follow = has("--walk") || has("--dynamic-walk");
        poubel.footsteps.dynamic = has("--dynamic-walk");
        if let Some(at) = args.iter().position(|a| a == "--max-passes") {
            let budget = args.get(at + 1).and_then(|n| n.parse().ok()).ok_or(usage)?;
            poubel.solver.max_passes = Some(budget);
        }
    }
    let profile = if has("g1") {
        g1::profile()
    } else {
        nao::profile()
    };
    let mut imitator = Imitator::new(profile, config)?;

    let mut per_phase: BTreeMap<String, Vec<f64>> = BTreeMap::new();
    let mut per_passes: BTreeMap<usize, Vec<f64>> = BTreeMap::new();
    let mut passes: Vec<f64> = Vec::new();
    let mut frames: Vec<Frame> = Vec::new();
    let mut human = HumanFrame::new(0.0);
    while clip.read_frame(&mut human)? {
        let robot = imitator.step(&human)?;
        let phase = phase_name(robot);
        per_phase
            .entry(phase.clone())
            .or_default()
            .push(robot.micros);
        (per_passes.entry(robot.solve_passes).or_default()).push(robot.micros);
        passes.push(robot.solve_passes as f64);
        let solve = if koenemann {
            String::new()
        } else {
            solve(robot)
        };
        frames.push((robot.micros, frames.len(), format!("{phase:32} {solve}")));
    }
    let mut all: Vec<f64> = frames.iter().map(|f| f.0).collect();
    println!("{}", spread("all", &mut all));
    if koenemann {
        println!("solver passes: not reported by Koenemann et al.'s method");
    } else {
        println!("{}", spread("solver passes per frame", &mut passes));
    }
    for (phase, mut times) in per_phase {
        println!("{}", spread(&phase, &mut times));
    }
    if !koenemann {
        for (passes, mut times) in per_passes {
            println!("{}", spread(&format!("{passes} solver passes"), &mut times));
        }
    }
    frames.sort_by(|a, b| b.0.total_cmp(&a.0));
    for (micros, index, description) in frames.iter().take(15) {
        println!("{micros:8.1} µs  frame {index:5}  {description}");
    }
    Ok(())
}

/// The frame's phase, marked when the robot walks.
fn phase_name(robot: &RobotFrame) -> String {
    let walking = if robot.walk.is_some() { " walking" } else { "" };
    format!("{:?}{walking}", robot.phase)
}

/// The last solve: levels, clamped joints and the stop reason.
fn solve(robot: &RobotFrame) -> String {
    let levels: Vec<String> = (robot.levels[..robot.level_count].iter())
        .map(|l| {
            format!(
                "{}/{}{}",
                l.rank,
                l.rows,
                if l.scale < 1.0 { "s" } else { "" }
            )
        })
        .collect();
    format!(
        "levels {}  clamped {}  passes {}{}",
        levels.join(" "),
        robot.clamped_count,
        robot.solve_passes,
        if robot.solve_converged {
            ""
        } else {
            " (not converged)"
        }
    )
}

/// `label: frames, median, p99, max` of `times` (µs; sorted in place).
fn spread(label: &str, times: &mut [f64]) -> String {
    times.sort_by(f64::total_cmp);
    let at = |p: f64| times[((times.len() - 1) as f64 * p).round() as usize];
    format!(
        "{label:40} n {:5}  median {:7.1}  p99 {:7.1}  max {:7.1}",
        times.len(),
        at(0.5),
        at(0.99),
        at(1.0)
    )
}
