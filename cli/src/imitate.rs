//! `taskstack imitate`: one clip, one robot, one output folder.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Duration;

use anyhow::{Result, bail};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use serde_json::json;
use taskstack::batch::{HOLD_CAP, Hold};
use taskstack::imitation::metrics::ImitationMetrics;
use taskstack::imitation::metrics::travel::LATE_LAG;
use taskstack::imitation::reach::POSTURE_UNREACHABLE;

use crate::Report;
use crate::check::PhysicsModel;
use crate::options::{ClipOptions, ImitationOptions};
use crate::run::{Progress, Settings, default_out, imitate_into, output_files};

/// The clip imitated when none is given: CMU 05_02 (standing, arm gestures, small steps, a
/// stance on the right leg), bundled with the crate.
const BUNDLED_CLIP: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../tests/data/mocap/cmu_05_02_stand_arm_gestures_turn_single_leg.bvh"
);

/// Seconds of the last posture `--check` plays after the run (the run's own hold is in it).
const CHECK_HOLD: f64 = 1.0;

/// Imitate a motion clip with a humanoid robot, online, frame by frame.
///
/// Reads a BVH clip (CMU skeletons, or any skeleton through --skeleton) or a Kinect v2 CSV,
/// imitates it with the robot (Poubel et al.'s support phases: the robot stands on one leg when
/// the human does, and with --walk steps where the human steps), then holds the last pose for
/// --hold seconds. Writes into the output folder, as the frames come:
///
///   joints.csv     time (s) and the robot's joint angles (rad), one line per frame: what
///                  its position servos are told, the planned posture plus the servos'
///                  static sag when the profile states their stiffness (the G1), played
///                  through a shaper that leaves the robot's sway on one foot unexcited
///                  when it states that sway's period (the G1: 0.52 s later; see
///                  --no-sway-shaping)
///   motion.npz     for learning pipelines (numpy): fps, time (s), joint_names, dof_pos (rad),
///                  root_pos (m) and root_quat (x y z w) of the floating base (NAO torso, G1
///                  pelvis; world: z up, the first right sole at the origin), contacts (left,
///                  right sole on the floor); resampled to the clip's own rate or --fps
///   metrics.json   tracking errors (m), balance margins (m), limits, slip, travel, step times (µs);
///                  hand_reach: per hand the error over the clip and the part of it no arm
///                  posture within the joint limits removes (m); the rest is lateness or a
///                  poor arm posture
///   view.html      a 3D viewer of the robot and the scaled human (opens in any browser, offline)
///   effectors.svg  each hand's and ankle's distance to the scaled human over time, phases shaded
///   com.svg        the CoM ground path inside the footprints, seen from above
///   phases.svg     the human's support and the robot's phase over time
///   joints.svg     the right arm's joint angles against their limits
///   motion_unitree.csv  with --export unitree-csv (see --export)
///
/// Every file is written as NAME.partial and renamed when the run has succeeded: a failed run
/// leaves the folder as it was.
#[derive(Debug, Args)]
#[command(verbatim_doc_comment)]
pub(crate) struct ImitateArgs {
    /// The clip: a .bvh file or a Kinect v2 .csv. Default: the bundled CMU 05_02 clip.
    #[arg(value_name = "CLIP")]
    clip: Option<PathBuf>,
    /// Output folder (created if needed). Default: taskstack-out/<clip name> in the current
    /// folder.
    #[arg(long, short, value_name = "DIR")]
    out: Option<PathBuf>,
    #[command(flatten)]
    clip_options: ClipOptions,
    /// After the run, check it in physics on the nominal and the weak model (`taskstack
    /// check`: needs the Python package with its simulation extra); the exit status is then
    /// the check's (1 when a model fails it).
    #[arg(long)]
    check: bool,
    #[command(flatten)]
    options: ImitationOptions,
}

pub(crate) fn run(args: ImitateArgs, report: Report) -> Result<ExitCode> {
    // The bundled clip's path without the `cli/..` of its build-time spelling.
    let bundled = || {
        Path::new(BUNDLED_CLIP)
            .canonicalize()
            .unwrap_or_else(|_| BUNDLED_CLIP.into())
    };
    let clip = args.clip.clone().unwrap_or_else(bundled);
    if args.clip.is_none() && !clip.is_file() {
        bail!("the bundled clip is not at {}: give a CLIP", clip.display());
    }
    let out = args.out.clone().unwrap_or_else(|| default_out(&clip));
    let settings = Settings {
        profile: args.options.profile()?,
        config: args.options.imitator_config()?,
        hold: args.options.hold,
        setup: args.clip_options.setup(args.options.skeleton_map()?)?,
        exports: args.options.exports(),
    };
    let bar = ProgressBar::hidden();
    let mut progress = |event: Progress| match event {
        Progress::Start(total) if report.human() => {
            bar.set_draw_target(indicatif::ProgressDrawTarget::stderr());
            match total {
                Some(n) => bar.set_length(n),
                None => bar.set_style(
                    ProgressStyle::with_template("{spinner} {pos} frames")
                        .unwrap_or_else(|_| ProgressStyle::default_spinner()),
                ),
            }
            bar.enable_steady_tick(Duration::from_millis(200));
        }
        Progress::Start(_) => {}
        Progress::Frames(n) => bar.set_position(n),
    };
    let metrics = imitate_into(&clip, &out, &settings, &mut progress);
    bar.finish_and_clear();
    let metrics = metrics?;
    let mut text = String::new();
    if report.json {
        let value = json!({
            "clip": clip,
            "out": out,
            "files": output_files(settings.exports),
            "metrics": taskstack::batch::metrics_value(&metrics, &clip),
        });
        let _ = writeln!(text, "{value}");
    } else if !report.quiet {
        print_summary(&mut text, &metrics, &clip, &out, &settings);
    }
    crate::output(&text)?;
    if args.check {
        let robot = Some(args.options.robot.as_str());
        return crate::check::check(&[out], PhysicsModel::Both, CHECK_HOLD, robot, report);
    }
    Ok(ExitCode::SUCCESS)
}

/// The run's summary for the terminal, one line per concern: the clip and the hold, the hand
/// supports, the support changes, the tracking, the balance and limits, the travel and steps,
/// the solve time, the files written.
pub(crate) fn print_summary(
    text: &mut String,
    m: &ImitationMetrics,
    clip: &Path,
    out: &Path,
    settings: &Settings,
) {
    let hold_frames = m.frames - m.clip_frames;
    let _ = writeln!(
        text,
        "{} on {}: {} frames ({:.2} s) of the clip, then {} frames ({:.2} s) holding its last pose",
        clip.display(),
        settings.profile.name,
        m.clip_frames,
        m.clip_duration,
        hold_frames,
        m.duration - m.clip_duration
    );
    if !m.finished {
        let why = match settings.hold {
            Hold::UntilFinished => format!("the {HOLD_CAP} s cap of --hold auto"),
            Hold::Fixed(_) => "a longer --hold, or --hold auto, lets it finish".to_owned(),
        };
        let _ = writeln!(
            text,
            "the robot had not finished when the run ended: {} ({why})",
            unfinished(m)
        );
    }
    print_hand_supports(text, m);
    let _ = writeln!(
        text,
        "support changes: human {}, robot {} ({})",
        m.human_support_changes,
        m.robot_support_changes,
        m.robot_support_sequence.join(" → ")
    );
    print_tracking(text, m);
    print_balance(text, m);
    print_locomotion(text, m);
    let s = &m.solve_time_us;
    let _ = writeln!(
        text,
        "time per frame: median {:.0} µs, 99th percentile {:.0} µs",
        s.median, s.p99
    );
    let _ = writeln!(
        text,
        "wrote {}/{{{}}}",
        out.display(),
        output_files(settings.exports).join(", ")
    );
}

/// The hand supports' lines: the human's clock paused while hands were placed, each hand's
/// contacts.
fn print_hand_supports(text: &mut String, m: &ImitationMetrics) {
    if m.human_clock_pause > 0.0 {
        let _ = writeln!(
            text,
            "hand supports: the human's clock paused {:.2} s in all while hands were placed",
            m.human_clock_pause
        );
    }
    if let Some(hands) = &m.held_hands {
        let hand = |name: &str, h: &taskstack::imitation::metrics::HeldHand| match h.contacts {
            0 => format!("{name} never reached its contact"),
            n => format!(
                "{name} {n} contact(s), placed in {:.2} s (median), held {:.1} mm from its point (max {:.1})",
                h.time_to_place.median,
                h.held_distance.mean * 1000.0,
                h.held_distance.max * 1000.0
            ),
        };
        let _ = writeln!(
            text,
            "hand supports: {}; {}",
            hand("l_hand", &hands[0]),
            hand("r_hand", &hands[1])
        );
    }
}

/// The balance, joint limits, standing feet and self-collision lines.
fn print_balance(text: &mut String, m: &ImitationMetrics) {
    let _ = writeln!(
        text,
        "balance: CoM ground projection at least {:.1} mm inside the support polygon ({} frames outside)",
        m.min_com_margin * 1000.0,
        m.frames_com_outside
    );
    let _ = writeln!(
        text,
        "limits: {} joint-position and {} joint-velocity violations (joint × frame); {} frames \
         with a joint turning back at speed",
        m.joint_limit_violations, m.velocity_limit_violations, m.joint_reversal_frames
    );
    let _ = writeln!(
        text,
        "standing feet: slip {:.2} mm / turn {:.3}° (support foot), {:.2} mm / {:.3}° (other foot)",
        m.max_support_slip * 1000.0,
        m.max_support_turn.to_degrees(),
        m.max_held_foot_slip * 1000.0,
        m.max_held_foot_turn.to_degrees()
    );
    if let Some(c) = &m.self_clearance {
        let _ = writeln!(
            text,
            "self-collision: bodies at least {:.1} mm apart ({} and {}; margin {:.0} mm, {} frames closer)",
            c.min_distance * 1000.0,
            c.closest[0],
            c.closest[1],
            c.margin * 1000.0,
            c.frames_below_margin
        );
    }
}

/// The travel, walking and foot-lift lines.
fn print_locomotion(text: &mut String, m: &ImitationMetrics) {
    let t = &m.travel;
    let _ = writeln!(
        text,
        "travel: scaled human {:.3} m, robot {:.3} m, ending {:.3} m and {:.1}° from where the \
         scaled human stands; steps: human {}, robot {}",
        t.scaled_human_m,
        t.robot_m,
        t.error_m,
        t.heading_error_rad.to_degrees(),
        m.human_steps,
        m.robot_steps
    );
    if let Some(w) = &m.walking {
        let duration = w
            .step_duration_s
            .map_or("-".to_owned(), |d| format!("{d:.2} s"));
        let _ = writeln!(
            text,
            "walking: {} steps in {:.1} s, {:.3} m/s, median step {duration}, planned ZMP >= {:.1} mm inside the support",
            w.steps,
            w.walking_s,
            w.mean_speed_m_s,
            w.zmp_margin_min_m * 1e3
        );
    }
    if let Some(f) = &m.following {
        let catch_up = (f.catch_up_s).map_or("never".to_owned(), |s| format!("{s:.2} s after"));
        let _ = writeln!(
            text,
            "feet: robot lifted {} of the human's {} foot lifts, median {:.2} s after (landed {:.2} s after); its last landing {catch_up} the human's",
            f.matched_steps, f.human_steps, m.lift_lag.median, m.landing_lag.median
        );
    }
}

/// What the robot was still doing at the end of a run.
fn unfinished(m: &ImitationMetrics) -> String {
    match m.queued_steps_at_end {
        0 => "a support change under way".to_owned(),
        n => format!("{n} step(s) still to take"),
    }
}

/// The tracking table: per effector, mean and maximum distance to the scaled human (cm) in
/// single support, double support and the transitions, over the clip's frames whose phase
/// tracks it.
fn print_tracking(text: &mut String, m: &ImitationMetrics) {
    let frames = m.clip_support_frames;
    let _ = writeln!(
        text,
        "distance of each effector to the scaled human over the clip, while its phase tracks it (cm):"
    );
    let _ = writeln!(
        text,
        "  {:8} {:>22} {:>22} {:>22}",
        "",
        format!("single support ({})", frames.single),
        format!("double support ({})", frames.double),
        format!("transitions ({})", frames.transitions)
    );
    let _ = writeln!(
        text,
        "  {:8} {:>22} {:>22} {:>22}",
        "", "mean / max (frames)", "mean / max (frames)", "mean / max (frames)"
    );
    // An empty cell says why: the robot never stood that way, or its phase does not track it.
    let cell = |s: &taskstack::imitation::metrics::MeanMax, support_frames: usize| match s.count {
        0 if support_frames == 0 => "no frames".to_owned(),
        0 => "not tracked".to_owned(),
        n => format!("{:.1} / {:.1} ({n})", s.mean * 100.0, s.max * 100.0),
    };
    for e in &m.effectors_clip {
        let _ = writeln!(
            text,
            "  {:8} {:>22} {:>22} {:>22}",
            e.name,
            cell(&e.single_support, frames.single),
            cell(&e.double_support, frames.double),
            cell(&e.transitions, frames.transitions)
        );
    }
    print_reach(text, m);
    print_hand_timing(text, m);
}

/// Whether the hands are late: the best time shift, and how much of their error it removes.
fn print_hand_timing(text: &mut String, m: &ImitationMetrics) {
    let Some(t) = m.hand_timing() else {
        return;
    };
    let verdict = match t.late() {
        true => "late",
        false if t.lag_s < LATE_LAG => "on time",
        false => {
            "not late: the hands are off more in where than in when (slowed down cutting \
             corners, out of reach or at a limit, a robot not where the human is)"
        }
    };
    let _ = writeln!(
        text,
        "hands' timing: best aligned {:.2} s later, which takes their mean error from {:.1} to {:.1} cm ({:.0} %): {verdict}",
        t.lag_s,
        t.error_m * 100.0,
        t.lag_removed_error_m * 100.0,
        t.removed_share() * 100.0
    );
}

/// Per hand, the clip frames whose reference lay out of the arm's reach from the robot's
/// shoulder (beyond it, or nearer than the bent elbow brings the hand): error no speed can
/// remove.
fn print_reach(text: &mut String, m: &ImitationMetrics) {
    let Some(arms) = &m.hand_reach else {
        return;
    };
    let hand = |name: &str, a: &taskstack::imitation::reach::HandReach| match a.mean_shortfall_m {
        Some(mean) => format!(
            "{name} {} of {} frames (mean {:.1} cm, max {:.1} cm short)",
            a.unreachable_frames,
            a.frames,
            mean * 100.0,
            a.max_shortfall_m.unwrap_or(mean) * 100.0
        ),
        None => format!("{name} none of {} frames", a.frames),
    };
    let _ = writeln!(
        text,
        "out of the arm's reach ({:.1}–{:.1} cm) from the robot's shoulder: {}; {}",
        arms[0].min_reach_m * 100.0,
        arms[0].reach_m * 100.0,
        hand("l_hand", &arms[0]),
        hand("r_hand", &arms[1])
    );
    let split = |name: &str, a: &taskstack::imitation::reach::HandReach| match (
        a.mean_error_m,
        a.mean_least_error_m,
    ) {
        (Some(error), Some(least)) => format!(
            "{name} {:.1} cm, {:.1} cm of it ({} frames over {:.0} cm)",
            error * 100.0,
            least * 100.0,
            a.posture_unreachable_frames,
            POSTURE_UNREACHABLE * 100.0
        ),
        _ => format!("{name} no frames"),
    };
    let _ = writeln!(
        text,
        "mean hand error over the clip, and the part no arm posture within the joint limits removes: {}; {}",
        split("l_hand", &arms[0]),
        split("r_hand", &arms[1])
    );
}
