//! `taskstack walk`: a robot walks to a goal with the pattern generator and the whole-body
//! solver.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Context, Result, bail};
use clap::Args;
use serde_json::json;
use taskstack::batch::JointsWriter;
use taskstack::human::Side;
use taskstack::locomotion::{
    GroundPose, SupportPolygon, WalkParams, WholeBodyWalker, goal_feet, plan_steps,
};

use crate::Report;
use crate::options::{non_negative, robot_profile};

/// Most steps a walk plans.
const MAX_STEPS: usize = 200;

/// Walk to a goal: footsteps within the robot's step envelope, a CoM from ZMP preview control,
/// joint angles from the whole-body solver.
///
/// The goal is the midpoint between the soles moved by --forward and --left (m) and turned by
/// --turn (rad), in the robot's starting frame (x forward, y left). Writes OUT/joints.csv (time
/// in s, joint angles in rad, 100 Hz; the format of `imitate`, playable by the physics check)
/// and OUT/walk.json (steps, duration, speed, the smallest margins of the plan's ZMP and CoM
/// inside the support polygon, the solver's largest foot and CoM errors).
#[derive(Debug, Args)]
#[command(verbatim_doc_comment)]
pub(crate) struct WalkArgs {
    /// The robot: nao, g1 or a biped profile file (TOML).
    #[arg(long, value_name = "nao|g1|PROFILE.toml", default_value = "nao")]
    robot: String,
    /// Distance to walk forward (m; negative: backward).
    #[arg(long, default_value_t = 0.5, allow_negative_numbers = true)]
    forward: f64,
    /// Distance to walk to the left (m; negative: to the right).
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    left: f64,
    /// Turn (rad, positive to the left).
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    turn: f64,
    /// Longest forward step (m, sole to sole); default: the robot profile's step envelope
    /// (NAO 0.05, G1 0.15).
    #[arg(long, value_parser = crate::options::positive)]
    step_length: Option<f64>,
    /// Seconds to stand still after the robot has stopped.
    #[arg(long, default_value_t = 1.0, value_parser = non_negative)]
    hold: f64,
    /// Output folder.
    #[arg(long, default_value = "taskstack-out/walk")]
    out: PathBuf,
}

pub(crate) fn run(args: WalkArgs, report: Report) -> Result<ExitCode> {
    if ![args.forward, args.left, args.turn]
        .iter()
        .all(|v| v.is_finite())
    {
        bail!("--forward, --left and --turn must be finite numbers");
    }
    let profile = robot_profile(&args.robot)?;
    let params = WalkParams::for_profile(&profile).context("deriving the walk settings")?;
    let timing = params.timing;
    let mut walker = WholeBodyWalker::new(&profile, params, GroundPose::new(0.0, 0.0, 0.0))?;
    let start = *walker.generator().standing_feet();
    let goal = goal_feet(&start, &GroundPose::new(args.forward, args.left, args.turn));
    let mut envelope = profile.step_envelope;
    if let Some(length) = args.step_length {
        envelope.x_max = length;
        envelope.x_min = envelope.x_min.min(length);
    }
    let steps = plan_steps(&start, &goal, &envelope, timing, MAX_STEPS);
    for step in &steps {
        walker.push(*step)?;
    }
    let outlines = Side::BOTH.map(|s| profile.foot(s).outline.as_slice());
    let mut polygon = SupportPolygon::new(outlines);
    let mut joints = JointsWriter::new(Vec::new());
    let names = profile.model(Side::Right).variables().iter();
    joints.header_names(names.map(|v| v.name.as_str()))?;
    joints.row(0.0, walker.q())?;
    let (mut zmp_margin, mut com_margin) = (f64::INFINITY, f64::INFINITY);
    let (mut foot_error, mut com_error) = (0.0_f64, 0.0_f64);
    let mut stopped_at = None;
    let mut plan = String::from("time,com_x,com_y,zmp_x,zmp_y,left_z,right_z\n");
    loop {
        let frame = *walker.tick()?;
        let w = &frame.walk;
        plan.push_str(&format!(
            "{:.3},{:.6},{:.6},{:.6},{:.6},{:.6},{:.6}\n",
            w.time,
            w.com.x,
            w.com.y,
            w.zmp.x,
            w.zmp.y,
            w.feet[0].position[2],
            w.feet[1].position[2]
        ));
        zmp_margin = zmp_margin.min(polygon.margin(&frame.walk, frame.walk.zmp));
        com_margin = com_margin.min(polygon.margin(&frame.walk, frame.walk.com.xy()));
        foot_error = foot_error.max(frame.foot_error);
        com_error = com_error.max(frame.com_error);
        joints.row(frame.walk.time, walker.q())?;
        let time = frame.walk.time;
        if walker.generator().is_stopped() && stopped_at.is_none() {
            stopped_at = Some(time);
        }
        if stopped_at.is_some_and(|t| time >= t + args.hold) {
            break;
        }
    }
    let end = walker.generator().standing_feet();
    let start_mid = (start[0].xy + start[1].xy) / 2.0;
    let end_mid = (end[0].xy + end[1].xy) / 2.0;
    let walk_time = stopped_at.unwrap_or(0.0);
    let summary = json!({
        "robot": profile.name,
        "steps": steps.len(),
        "step_duration_s": timing.duration(),
        "walk_time_s": walk_time,
        "travel_m": (end_mid - start_mid).norm(),
        "mean_speed_m_s": (end_mid - start_mid).norm() / walk_time.max(f64::MIN_POSITIVE),
        "heading_rad": taskstack::locomotion::footstep::wrap_angle(end[1].yaw - start[1].yaw),
        "zmp_margin_min_m": zmp_margin,
        "com_margin_min_m": com_margin,
        "foot_error_max": foot_error,
        "com_error_max_m": com_error,
        "com_height_m": walker.params().settings.com_height,
    });
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;
    let csv = joints.into_inner();
    let write = |name: &str, bytes: &[u8]| {
        std::fs::write(args.out.join(name), bytes)
            .with_context(|| format!("cannot write {}", args.out.join(name).display()))
    };
    write("joints.csv", &csv)?;
    write("plan.csv", plan.as_bytes())?;
    write(
        "walk.json",
        serde_json::to_string_pretty(&summary)?.as_bytes(),
    )?;
    if report.json {
        crate::output(&format!("{summary}\n"))?;
    } else if report.human() {
        crate::output(&format!(
            "{}: {} steps of {:.2} s, {:.3} m in {:.2} s ({:.3} m/s), ZMP >= {:.1} mm inside the support\nwrote {}\n",
            profile.name,
            steps.len(),
            timing.duration(),
            (end_mid - start_mid).norm(),
            walk_time,
            (end_mid - start_mid).norm() / walk_time.max(f64::MIN_POSITIVE),
            zmp_margin * 1e3,
            args.out.display()
        ))?;
    }
    Ok(ExitCode::SUCCESS)
}
