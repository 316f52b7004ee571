//! Online imitation of a motion clip by a biped (the README's main job).
//!
//! `cargo run --release --example imitate -- [CLIP.bvh|CLIP.csv] [--robot nao|g1|PROFILE.toml] [--out DIR] [--velocity-fraction F] [--hold S]`
//!
//! With no clip, a bundled real clip with a support change (CMU 05_02: standing, arm gestures,
//! small steps, then a stance on the right leg). Writes into DIR (default `target/imitate`):
//! `joints.csv` (time in s + the robot's joint angles in rad, named as its model's variables), `metrics.json` (see
//! `taskstack::imitation::metrics`), and the plots `effectors.svg` (Poubel Fig. 6), `com.svg`
//! (Fig. 8) and `phases.svg`; prints a summary. `--velocity-fraction` is the share of the rated
//! joint velocities the robot may use (default 0.1, as in the paper). After the clip the human's
//! last pose is held for `--hold` seconds (default 5) so the robot can finish the step it is
//! taking; those frames are in the outputs too. `--task-speed` (m/s, default the profile's: 0.15 for both robots) and
//! `--iterations` (per frame, default 1) set `ImitatorConfig::max_task_speed` and
//! `iterations_per_frame`. `--walk` lets the robot's feet follow the human's footprints
//! (`FootstepConfig::follow`): it walks where the human walks. `--robot` picks the robot: the
//! built-in NAO (default) or Unitree G1, or a biped profile file (`BipedProfile::from_toml_file`).
//! `--skeleton MAP.toml` reads a BVH clip whose joints do not carry the CMU names through a
//! skeleton map (`taskstack::io::skeleton_map`). `--tracking-speed` (m/s) and
//! `--upper-body-fraction` set `ImitatorConfig::max_tracking_speed` and
//! `upper_body_velocity_fraction`.

mod plots;

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use taskstack::batch::{imitate_clip, joints_header, metrics_json, push_joints_line};
use taskstack::human::Side;
use taskstack::imitation::imitator::{Imitator, ImitatorConfig, RobotFrame};
use taskstack::imitation::metrics::{CONTACT_HEIGHT, EFFECTORS, ImitationMetrics};
use taskstack::imitation::support::HumanSupport;
use taskstack::imitation::support::SupportConfig;
use taskstack::io::clip::Clip;
use taskstack::io::skeleton_map::SkeletonMap;
use taskstack::robots::{BipedProfile, g1, nao};

const DEFAULT_CLIP: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/tests/data/mocap/cmu_05_02_stand_arm_gestures_turn_single_leg.bvh"
);

fn main() -> ExitCode {
    let mut clip = PathBuf::from(DEFAULT_CLIP);
    let mut out = PathBuf::from("target/imitate");
    let mut fraction = ImitatorConfig::default().velocity_fraction;
    let mut hold = 5.0;
    let mut config = ImitatorConfig::default();
    let mut robot = "nao".to_owned();
    let mut skeleton: Option<PathBuf> = None;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--out" => match args.next() {
                Some(d) => out = d.into(),
                None => return usage(),
            },
            "--hold" => match args
                .next()
                .and_then(|v| v.parse::<f64>().ok())
                .filter(|h| h.is_finite() && *h >= 0.0)
            {
                Some(h) => hold = h,
                None => return usage(),
            },
            "--walk" => config.footsteps.follow = true,
            "--skeleton" => match args.next() {
                Some(m) => skeleton = Some(PathBuf::from(m)),
                None => return usage(),
            },
            "--robot" => match args.next() {
                Some(r) => robot = r,
                None => return usage(),
            },
            "--velocity-fraction" => match args.next().and_then(|v| v.parse().ok()) {
                Some(f) => fraction = f,
                None => return usage(),
            },
            "--task-speed" => match args.next().and_then(|v| v.parse().ok()) {
                Some(v) => config.max_task_speed = Some(v),
                None => return usage(),
            },
            "--tracking-speed" => match args.next().and_then(|v| v.parse().ok()) {
                Some(v) => config.max_tracking_speed = Some(v),
                None => return usage(),
            },
            "--upper-body-fraction" => match args.next().and_then(|v| v.parse().ok()) {
                Some(v) => config.upper_body_velocity_fraction = Some(v),
                None => return usage(),
            },
            "--iterations" => match args.next().and_then(|v| v.parse().ok()) {
                Some(n) => config.iterations_per_frame = n,
                None => return usage(),
            },
            _ if a.starts_with("--") => return usage(),
            _ => clip = a.into(),
        }
    }
    config.velocity_fraction = fraction;
    let profile = match robot.as_str() {
        "nao" => nao::profile(),
        "g1" => g1::profile(),
        path => match BipedProfile::from_toml_file(path) {
            Ok(p) => p,
            Err(e) => {
                eprintln!("imitate: --robot {path}: {e}");
                return ExitCode::FAILURE;
            }
        },
    };
    let source = match &skeleton {
        None => Clip::open(&clip).map_err(|e| e.to_string()),
        Some(map) => SkeletonMap::from_toml_file(map)
            .map_err(|e| format!("--skeleton {e}"))
            .and_then(|map| Clip::open_mapped(&clip, &map).map_err(|e| e.to_string())),
    };
    let source = match source {
        Ok(source) => source,
        Err(e) => {
            eprintln!("imitate: {}: {e}", clip.display());
            return ExitCode::FAILURE;
        }
    };
    match run(source, &clip, &out, profile, config, hold) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("imitate: {}: {e}", clip.display());
            ExitCode::FAILURE
        }
    }
}

fn usage() -> ExitCode {
    eprintln!(
        "usage: imitate [CLIP.bvh|CLIP.csv] [--out DIR] [--velocity-fraction F] [--hold S] [--task-speed V] [--iterations N] [--walk] [--robot nao|g1|PROFILE.toml] [--skeleton MAP.toml] [--tracking-speed V] [--upper-body-fraction F]"
    );
    ExitCode::from(2)
}

fn run(
    clip: Clip,
    path: &Path,
    out: &Path,
    profile: BipedProfile,
    config: ImitatorConfig,
    hold: f64,
) -> Result<(), Box<dyn std::error::Error>> {
    let config = ImitatorConfig {
        support: SupportConfig::for_capture(clip.capture()),
        ..config
    };
    let mut imitator = Imitator::new(profile, config)?;
    let mut joints = joints_header(&imitator);
    let mut samples = Vec::new();
    let profile = imitator.profile().clone();
    // The plotted effectors: the first three of EFFECTORS (hands, left ankle).
    let plotted: Vec<&str> = EFFECTORS[..3].iter().map(|(name, _)| *name).collect();
    let metrics = imitate_clip(path, clip, &mut imitator, hold, |r| {
        push_joints_line(&mut joints, r);
        samples.push(sample(r, &profile, plotted.len()));
    })?;
    std::fs::create_dir_all(out)?;
    std::fs::write(out.join("joints.csv"), joints)?;
    std::fs::write(out.join("metrics.json"), metrics_json(&metrics, path))?;
    std::fs::write(
        out.join("effectors.svg"),
        plots::effectors(&samples, &plotted),
    )?;
    std::fs::write(out.join("com.svg"), plots::com_and_feet(&samples))?;
    std::fs::write(out.join("phases.svg"), plots::phases(&samples))?;
    print_summary(&metrics, path, out);
    Ok(())
}

fn print_summary(m: &ImitationMetrics, clip: &Path, out: &Path) {
    println!(
        "clip {}: {} frames, {:.2} s (clip and hold; tracking below over the clip's frames)",
        clip.display(),
        m.frames,
        m.duration
    );
    println!(
        "support changes: human {}, robot {} ({})",
        m.human_support_changes,
        m.robot_support_changes,
        m.robot_support_sequence.join(" → ")
    );
    let t = &m.transition_durations;
    println!(
        "transitions: {} (min {:.2} s, median {:.2} s, max {:.2} s)",
        t.count, t.min, t.median, t.max
    );
    for e in &m.effectors_clip {
        println!(
            "tracking {:8}: single support mean {:.4} m max {:.4} m ({} frames); double support mean {:.4} m max {:.4} m ({} frames)",
            e.name,
            e.single_support.mean,
            e.single_support.max,
            e.single_support.count,
            e.double_support.mean,
            e.double_support.max,
            e.double_support.count
        );
    }
    println!(
        "CoM margin in the support polygon: min {:.4} m ({} frames outside); limit violations: joints {}, velocities {}",
        m.min_com_margin,
        m.frames_com_outside,
        m.joint_limit_violations,
        m.velocity_limit_violations
    );
    for e in &m.hands_clip_lag_removed {
        println!(
            "tracking {:8} with the lag of {:.2} s removed: single support mean {:.4} m; double support mean {:.4} m",
            e.name, m.hand_lag_s, e.single_support.mean, e.double_support.mean
        );
    }
    println!(
        "standing feet: support foot slip {:.2e} m, {:.2e} rad; other foot slip {:.2e} m, {:.2e} rad",
        m.max_support_slip, m.max_support_turn, m.max_held_foot_slip, m.max_held_foot_turn
    );
    let t = &m.travel;
    println!(
        "travel: scaled human {:.3} m, robot {:.3} m, heading error {:.3} rad; steps: human {}, robot {}, queued at the end {}; catch-up after the clip: {}",
        t.scaled_human_m,
        t.robot_m,
        t.heading_error_rad,
        m.human_steps,
        m.robot_steps,
        m.queued_steps_at_end,
        m.catch_up_s
            .map_or("never".to_owned(), |s| format!("{s:.2} s"))
    );
    let s = &m.solve_time_us;
    println!(
        "time per frame: median {:.1} µs, p99 {:.1} µs, max {:.1} µs",
        s.median, s.p99, s.max
    );
    println!(
        "wrote {}/{{joints.csv, metrics.json, effectors.svg, com.svg, phases.svg}}",
        out.display()
    );
}

/// The plotted quantities of robot frame `r` (world frame, m): the first `plotted` effectors of
/// `EFFECTORS` and their references, the CoM, the soles on the ground, the phases.
fn sample(r: &RobotFrame, profile: &BipedProfile, plotted: usize) -> plots::Sample {
    let world = |p: &nalgebra::Vector3<f64>| {
        let w = r.world_t_root.transform_point(&(*p).into());
        [w.x, w.y, w.z]
    };
    let effectors = EFFECTORS[..plotted]
        .iter()
        .zip(&r.effectors)
        .map(|((_, joint), robot)| (world(robot), r.reference[joint.index()].as_ref().map(world)))
        .collect();
    let footprints = [(Side::Right, r.right_sole), (Side::Left, r.left_sole)]
        .into_iter()
        .filter_map(|(foot, sole)| {
            let outline: Vec<_> = (profile.foot(foot).outline.iter())
                .map(|&[x, y]| sole.transform_point(&nalgebra::Point3::new(x, y, 0.0)))
                .collect();
            outline
                .iter()
                .all(|p| p.z.abs() <= CONTACT_HEIGHT)
                .then(|| (foot, outline.iter().map(|p| [p.x, p.y]).collect()))
        })
        .collect();
    plots::Sample {
        time: r.time,
        effectors,
        com: [r.com.x, r.com.y],
        footprints,
        human: match r.human_support {
            HumanSupport::Double => "Double",
            HumanSupport::Right => "Right",
            HumanSupport::Left => "Left",
            HumanSupport::Airborne => "Airborne",
        },
        robot: r.phase.to_string(),
    }
}
