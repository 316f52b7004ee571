//! `taskstack walk`: a robot walks to a goal with the pattern generator and the whole-body
//! solver.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, Result, bail};
use clap::Args;
use serde_json::json;
use taskstack::export::JointsWriter;
use taskstack::human::HumanJoint;
use taskstack::human::Side;
use taskstack::imitation::phase::SupportPhase;
use taskstack::imitation::reference::support::HumanSupport;
use taskstack::locomotion::footstep::wrap_angle;
use taskstack::locomotion::{
    Footstep, GroundPose, StepTiming, Support, SupportPolygon, WalkParams, WalkState, WalkerFrame,
    WholeBodyWalker, goal_feet, plan_steps,
};
use taskstack::nalgebra::Translation3;
use taskstack::robots::BipedProfile;
use taskstack::{IsometryMatrix3, Rotation3, Vector3};

use crate::Report;
use crate::options::{non_negative, robot_profile};
use crate::view::{ViewFrame, ViewWriter};

/// Most steps a walk plans (a NAO walks 50 m in them; the summary's travel says when the goal
/// was farther).
const MAX_STEPS: usize = 1000;

/// Walk to a goal with the pattern generator and the whole-body solver.
///
/// Footsteps within the robot's step envelope, a CoM from ZMP preview control, joint angles
/// from the whole-body solver.
///
/// The goal is the midpoint between the soles moved by --forward and --left (m) and turned by
/// --turn (rad), in the robot's starting frame (x forward, y left). Writes OUT/joints.csv (time
/// in s, joint angles in rad, 100 Hz; the format of `imitate`, playable by the physics check:
/// the angles plus their servos' static sag when the profile states the servos' stiffness),
/// OUT/plan.csv (the plan's CoM, cart-table ZMP and sole heights, and the whole body's ZMP of
/// the solved joint angles: swing leg, arms and torso included; m), OUT/view.html (the 3D
/// viewer) and OUT/walk.json (steps, duration, speed, the smallest margins of the plan's ZMP,
/// the whole body's ZMP and the CoM inside the support polygon, the solver's largest foot and
/// CoM errors).
///
/// Played on the MuJoCo robots of CI's physics check, the NAO's walks stand on both of its
/// models; the G1's fall a few seconds in (the README's "Physics check").
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
    /// Double support of every step (s, > 0): both feet on the floor while the ZMP moves onto
    /// the next stance sole. Default: the robot's derived timing
    /// (`taskstack::locomotion::params`; NAO 0.50 s).
    #[arg(long, value_name = "SECONDS", value_parser = crate::options::positive)]
    double_support: Option<f64>,
    /// Single support of every step (s, > 0): the swing foot in the air. Default: the robot's
    /// derived timing (NAO 0.58 s).
    #[arg(long, value_name = "SECONDS", value_parser = crate::options::positive)]
    single_support: Option<f64>,
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
    let mut params = WalkParams::for_profile(&profile).context("deriving the walk settings")?;
    if args.double_support.is_some() || args.single_support.is_some() {
        let timing = StepTiming {
            double_support: args.double_support.unwrap_or(params.timing.double_support),
            single_support: args.single_support.unwrap_or(params.timing.single_support),
        };
        params = params.with_timing(timing);
    }
    let timing = params.timing;
    let com_height = params.settings.com_height;
    let walker = WholeBodyWalker::new(&profile, params, GroundPose::new(0.0, 0.0, 0.0))?;
    let start = *walker.generator().standing_feet();
    let goal = goal_feet(&start, &GroundPose::new(args.forward, args.left, args.turn));
    let mut envelope = profile.step_envelope;
    if let Some(length) = args.step_length {
        envelope.x_max = length;
        envelope.x_min = envelope.x_min.min(length);
    }
    let steps = plan_steps(&start, &goal, &envelope, timing, MAX_STEPS);
    let (recorder, stopped_at, end) = walk_steps(walker, &profile, &steps, args.hold)?;
    let travel = ((end[0].xy + end[1].xy) - (start[0].xy + start[1].xy)).norm() / 2.0;
    let walk_time = stopped_at.unwrap_or(0.0);
    let summary = json!({
        "robot": profile.name,
        "steps": steps.len(),
        "step_duration_s": timing.duration(),
        "walk_time_s": walk_time,
        "travel_m": travel,
        "mean_speed_m_s": travel / walk_time.max(f64::MIN_POSITIVE),
        "heading_rad": wrap_angle(end[1].yaw - start[1].yaw),
        "zmp_margin_min_m": recorder.zmp_margin,
        "body_zmp_margin_min_m": recorder.body_zmp_margin,
        "com_margin_min_m": recorder.com_margin,
        "foot_error_max": recorder.foot_error,
        "com_error_max_m": recorder.com_error,
        "com_height_m": com_height,
    });
    let (zmp_margin, body_zmp_margin) = (recorder.zmp_margin, recorder.body_zmp_margin);
    recorder.write(&args.out, walk_time, &summary)?;
    if report.json {
        crate::output(&format!("{summary}\n"))?;
    } else if report.human() {
        crate::output(&format!(
            "{}: {} steps of {:.2} s, {travel:.3} m in {walk_time:.2} s ({:.3} m/s), ZMP >= {:.1} mm inside the support (the whole body's: {:.1} mm)\nwrote {}\n",
            profile.name,
            steps.len(),
            timing.duration(),
            travel / walk_time.max(f64::MIN_POSITIVE),
            zmp_margin * 1e3,
            body_zmp_margin * 1e3,
            args.out.display()
        ))?;
    }
    Ok(ExitCode::SUCCESS)
}

/// `walker` (standing, with `profile`) walks `steps` and stands `hold` s after it stops: the
/// outputs, when it stopped (s) and where the soles ended.
fn walk_steps(
    mut walker: WholeBodyWalker<'_>,
    profile: &BipedProfile,
    steps: &[Footstep],
    hold: f64,
) -> Result<(Recorder, Option<f64>, [GroundPose; 2])> {
    // The generator's queue is bounded: steps are fed as they land.
    let capacity = walker.generator().settings().capacity;
    let mut pending = steps.iter();
    let mut recorder = Recorder::new(profile, walker.servo_targets())?;
    let mut stopped_at = None;
    loop {
        while walker.generator().queued() < capacity
            && let Some(step) = pending.next()
        {
            walker.push(*step)?;
        }
        let frame = *walker.tick()?;
        let footsteps: Vec<Footstep> = (walker.generator().queued_steps())
            .map(|(_, _, step)| *step)
            .collect();
        recorder.record(&frame, walker.q(), walker.servo_targets(), &footsteps)?;
        let time = frame.walk.time;
        if walker.generator().is_stopped() && pending.len() == 0 && stopped_at.is_none() {
            stopped_at = Some(time);
        }
        if stopped_at.is_some_and(|t| time >= t + hold) {
            break;
        }
    }
    Ok((recorder, stopped_at, *walker.generator().standing_feet()))
}

/// The outputs of a walk, built as the ticks come, and the plan's margins and solver errors.
struct Recorder {
    polygon: SupportPolygon,
    joints: JointsWriter<Vec<u8>>,
    plan: String,
    view: ViewWriter<Vec<u8>>,
    zmp_margin: f64,
    /// The whole body's ZMP's least margin (it lags a tick: [`WalkerFrame::previous_zmp`]).
    body_zmp_margin: f64,
    /// The last tick's state and its `plan.csv` row, waiting for its whole-body ZMP.
    pending: Option<(WalkState, String)>,
    com_margin: f64,
    foot_error: f64,
    com_error: f64,
}

impl Recorder {
    /// Starts the outputs with the robot standing at time 0, its servos told `targets` (rad).
    fn new(profile: &BipedProfile, targets: &[f64]) -> Result<Self> {
        let outlines = Side::BOTH.map(|s| profile.foot(s).outline.as_slice());
        let mut joints = JointsWriter::new(Vec::new());
        let names = profile.model(Side::Right).variables().iter();
        joints.header_names(names.map(|v| v.name.as_str()))?;
        joints.row(0.0, targets)?;
        let title = format!("{} walking", profile.name);
        Ok(Self {
            polygon: SupportPolygon::new(outlines),
            joints,
            plan: String::from(
                "time,com_x,com_y,zmp_x,zmp_y,left_z,right_z,body_zmp_x,body_zmp_y\n",
            ),
            view: ViewWriter::new(Vec::new(), profile, &title)?,
            zmp_margin: f64::INFINITY,
            body_zmp_margin: f64::INFINITY,
            pending: None,
            com_margin: f64::INFINITY,
            foot_error: 0.0,
            com_error: 0.0,
        })
    }

    /// One tick: the joints `q` (rad) that realise `frame`, what the servos are told for them
    /// (`targets`, rad: joints.csv), the `footsteps` not yet landed.
    fn record(
        &mut self,
        frame: &WalkerFrame,
        q: &[f64],
        targets: &[f64],
        footsteps: &[Footstep],
    ) -> Result<()> {
        let w = &frame.walk;
        let [left, right] = w.feet.map(|f| f.position);
        if let Some((state, row)) = self.pending.take() {
            self.plan.push_str(&row);
            if let Some(p) = frame.previous_zmp {
                self.body_zmp_margin = self.body_zmp_margin.min(self.polygon.margin(&state, p));
                let _ = writeln!(self.plan, ",{:.6},{:.6}", p.x, p.y);
            } else {
                self.plan.push_str(",,\n");
            }
        }
        let row = format!(
            "{:.3},{:.6},{:.6},{:.6},{:.6},{:.6},{:.6}",
            w.time, w.com.x, w.com.y, w.zmp.x, w.zmp.y, left[2], right[2]
        );
        self.pending = Some((*w, row));
        self.zmp_margin = self.zmp_margin.min(self.polygon.margin(w, w.zmp));
        self.com_margin = self.com_margin.min(self.polygon.margin(w, w.com.xy()));
        self.foot_error = self.foot_error.max(frame.foot_error);
        self.com_error = self.com_error.max(frame.com_error);
        self.joints.row(w.time, targets)?;
        let soles = w.feet.map(|f| {
            IsometryMatrix3::from_parts(
                Translation3::from(Vector3::from(f.position)),
                Rotation3::from_axis_angle(&Vector3::z_axis(), f.yaw),
            )
        });
        let phase = match w.support {
            Support::Double => SupportPhase::Double,
            Support::Single { swing, .. } => swing.pick(SupportPhase::Right, SupportPhase::Left),
        };
        let view = ViewFrame {
            time: w.time,
            phase,
            human_support: HumanSupport::Airborne,
            q,
            soles: [&soles[0], &soles[1]],
            com: w.com,
            zmp: Some(w.zmp),
            footsteps,
            hand_supports: [None; 2],
            hands: None,
        };
        self.view
            .frame_of(&view, std::iter::repeat_n(None, HumanJoint::COUNT))
    }

    /// Writes `joints.csv`, `plan.csv`, `view.html` and `walk.json` (`summary`) into `out`;
    /// the viewer marks the frames after `walk_end` (s) as the hold.
    fn write(self, out: &Path, walk_end: f64, summary: &serde_json::Value) -> Result<()> {
        std::fs::create_dir_all(out).with_context(|| format!("cannot create {}", out.display()))?;
        let write = |name: &str, bytes: &[u8]| {
            std::fs::write(out.join(name), bytes)
                .with_context(|| format!("cannot write {}", out.join(name).display()))
        };
        let view = self.view.into_inner(walk_end, summary.clone())?;
        let mut plan = self.plan;
        if let Some((_, row)) = self.pending {
            plan.push_str(&row);
            plan.push_str(",,\n");
        }
        write("joints.csv", &self.joints.into_inner())?;
        write("plan.csv", plan.as_bytes())?;
        write("view.html", &view)?;
        write(
            "walk.json",
            serde_json::to_string_pretty(summary)?.as_bytes(),
        )
    }
}
