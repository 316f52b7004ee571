//! End-to-end imitation of every bundled real clip (CMU BVH and Kinect v2): the invariants hold on
//! every frame — no NaN, joints within their limits and velocity limits, the CoM projection inside
//! the support polygon, no slip of the support foot across model switches, the paired bodies
//! (forearms, torso, head, shins, feet) at least the NAO's self-collision margin apart — and the robot's
//! support sequence follows the human's: DS→RS→DS for the single-leg stance of `cmu_05_02`, DS
//! throughout for `cmu_02_10`, alternating single supports for the walks.
//!
//! After its last frame each clip is held for a few seconds (the human standing still), so that
//! a robot moving at 10 % of its rated speed can finish the step it is taking.
//! `cargo test --release --test imitation_end_to_end -- --nocapture` prints the per-clip metrics.

use crate::common;

use taskstack::human::{HumanFrame, HumanJoint, Side};
use taskstack::imitation::ImitationMethod;
use taskstack::imitation::koenemann::KoenemannConfig;
use taskstack::imitation::metrics::{ImitationMetrics, MetricsRecorder};
use taskstack::imitation::phase::SupportPhase;
use taskstack::imitation::poubel::PoubelConfig;
use taskstack::imitation::reference::support::SupportConfig;
use taskstack::imitation::shaping::MotionLimits;
use taskstack::imitation::walking::footsteps::FootstepConfig;
use taskstack::imitation::walking::look_ahead::{FootLookAhead, FootSchedule};
use taskstack::imitation::{Imitator, ImitatorConfig};
use taskstack::io::clip::Clip;
use taskstack::locomotion::WalkParams;
use taskstack::robots::nao;

const SETTLE_SECONDS: f64 = 5.0;

fn clip_path(name: &str) -> String {
    format!("{}/tests/data/mocap/{name}", env!("CARGO_MANIFEST_DIR"))
}

/// Runs a clip (plus the settling hold) and checks the per-frame invariants; returns the metrics
/// and the robot phase of every frame.
fn run(name: &str) -> (ImitationMetrics, Vec<SupportPhase>) {
    run_with(name, ImitatorConfig::default(), HELD_FOOT_TOLERANCE)
}

/// How far (m, rad) a standing foot may move in the plan. The support foot (the model root) is
/// still by construction; the other standing foot is held by the IK's top level, and a
/// contact-only Newton step ends every frame (`PhaseSolver::settle_contact`), so what is left
/// is that step's second-order term, about `L·δq²` for its small `δq` (measured: under 1e-11 m
/// on the bundled clips).
const HELD_FOOT_TOLERANCE: f64 = 1e-6;

/// How far (m, rad) a standing foot may move in a plan of Koenemann's method: its legs are
/// solved by their own IK, which stops at a tolerance (`imitation::koenemann`), without the
/// contact step (measured: 1.0e-6 rad on CMU 02_10).
const KOENEMANN_FOOT_TOLERANCE: f64 = 2e-5;

/// How far inside the self-collision margin a body may end a frame (m): the IK's first-order
/// step toward the margin overshoots it by its second-order term, corrected at the next frame
/// (measured with the hands at 0.8 m/s: 0.57 mm of the 10 mm margin, the right forearm over
/// the head on Kinect ges01, since the arms hang from the robot's shoulders and the waving hand
/// aims over the head; at the ZMP level's 1 m/s: 1.2 mm, the left forearm by the torso on CMU
/// 05_12). The bodies are then still 8 mm apart.
const CLEARANCE_TOLERANCE: f64 = 2e-3;

fn run_with(
    name: &str,
    config: ImitatorConfig,
    slip_tolerance: f64,
) -> (ImitationMetrics, Vec<SupportPhase>) {
    run_held(name, config, slip_tolerance, SETTLE_SECONDS)
}

/// [`run_with`], holding the human's last pose `settle` seconds after the clip.
fn run_held(
    name: &str,
    config: ImitatorConfig,
    slip_tolerance: f64,
    settle: f64,
) -> (ImitationMetrics, Vec<SupportPhase>) {
    let mut clip = Clip::open(clip_path(name)).unwrap();
    let config = ImitatorConfig {
        support: SupportConfig::for_capture(clip.capture()),
        ..config
    };
    let mut imitator = Imitator::new(nao::profile(), config).unwrap();
    let mut recorder = MetricsRecorder::new(&imitator);
    let mut phases = Vec::new();
    let mut frame = HumanFrame::new(0.0);
    let mut last = None;
    let mut step = |imitator: &mut Imitator, frame: &HumanFrame, recorder: &mut MetricsRecorder| {
        let r = imitator.step(frame).unwrap().clone();
        assert!(
            r.q.iter().all(|q| q.is_finite()),
            "{name} t = {}: NaN in q",
            r.time
        );
        assert!(r.com.iter().all(|c| c.is_finite()));
        recorder.record(&r);
        phases.push(r.phase);
    };
    while clip.read_frame(&mut frame).unwrap() {
        step(&mut imitator, &frame, &mut recorder);
        last = Some(frame);
    }
    let mut hold = last.expect("the clip has frames");
    let end = hold.time;
    while hold.time < end + settle {
        hold.time += 1.0 / 120.0;
        step(&mut imitator, &hold, &mut recorder);
    }
    let m = recorder.finish();
    eprintln!(
        "{name}: {} frames, robot {}, transitions {} (median {:.2} s), CoM margin ≥ {:.4} m, hand error DS {:.4}/{:.4} m, SS {:.4}/{:.4} m, step median {:.1} µs",
        m.frames,
        m.robot_support_sequence.join("→"),
        m.transition_durations.count,
        m.transition_durations.median,
        m.min_com_margin,
        m.effectors[0].double_support.mean,
        m.effectors[1].double_support.mean,
        m.effectors[0].single_support.mean,
        m.effectors[1].single_support.mean,
        m.solve_time_us.median,
    );
    assert_eq!(m.joint_limit_violations, 0, "{name}: joint limits");
    assert_eq!(m.velocity_limit_violations, 0, "{name}: velocity limits");
    assert_eq!(
        m.frames_com_outside, 0,
        "{name}: CoM outside the support polygon"
    );
    assert!(
        m.min_com_margin > 0.0,
        "{name}: CoM margin {}",
        m.min_com_margin
    );
    let clearance = m
        .self_clearance
        .as_ref()
        .expect("the NAO has self-collision pairs");
    assert!(
        clearance.min_distance >= clearance.margin - CLEARANCE_TOLERANCE,
        "{name}: {:?} {:.4} m apart, margin {} m",
        clearance.closest,
        clearance.min_distance,
        clearance.margin
    );
    for (what, value) in [
        ("support foot slip (m)", m.max_support_slip),
        ("support foot turn (rad)", m.max_support_turn),
        ("held foot slip (m)", m.max_held_foot_slip),
        ("held foot turn (rad)", m.max_held_foot_turn),
    ] {
        assert!(value <= slip_tolerance, "{name}: {what} {value}");
    }
    (m, phases)
}

fn contains(sequence: &[&str], pattern: &[&str]) -> bool {
    sequence.windows(pattern.len()).any(|w| w == pattern)
}

#[test]
fn single_leg_stance_clip_goes_double_right_double() {
    let (m, _) = run("cmu_05_02_stand_arm_gestures_turn_single_leg.bvh");
    assert!(
        contains(&m.robot_support_sequence, &["DS", "RS", "DS"]),
        "{:?}",
        m.robot_support_sequence
    );
}

#[test]
fn double_support_clip_never_leaves_double_support() {
    let (m, phases) = run("cmu_02_10_wash_self_standing_arm_gestures.bvh");
    assert_eq!(m.robot_support_sequence, vec!["DS"]);
    assert!(phases.iter().all(|p| *p == SupportPhase::Double));
    // Hands in double support, against the scaled reference (m): reported, bounded loosely
    // because at 10 % speed the robot lags fast human gestures.
    assert!(m.effectors[0].double_support.mean < 0.15 && m.effectors[1].double_support.mean < 0.15);
}

/// Walking (`FootstepConfig::follow`), the robot steps with both feet on the walks and goes the
/// human's way: it travels at least a third of the scaled human's distance in the clip and a
/// 60 s hold (a step takes 5–7 s: before a foot lifts, the torso leans over the stance foot,
/// and it comes back upright after the landing).
#[test]
fn walks_are_walked() {
    for name in [
        "cmu_07_04_slow_walk.bvh",
        "cmu_09_12_walk_forward_backward_sideways.bvh",
        "cmu_131_01_start_walk_stop_maxskel.bvh",
    ] {
        let (m, _) = run_held(name, step_by_step(), HELD_FOOT_TOLERANCE, 60.0);
        let singles: Vec<&str> = m
            .robot_support_sequence
            .iter()
            .copied()
            .filter(|s| *s != "DS")
            .collect();
        assert!(
            singles.contains(&"RS") && singles.contains(&"LS"),
            "{name}: {:?}",
            m.robot_support_sequence
        );
        assert!(m.robot_steps >= 2, "{name}: {} robot steps", m.robot_steps);
        assert!(
            m.travel.robot_m > m.travel.scaled_human_m / 3.0,
            "{name}: {:?}",
            m.travel
        );
    }
}

/// Walking step by step, a human standing in place takes the robot nowhere: on CMU 02_10 and
/// the two Kinect clips the human never steps, but a standing foot's heading (ankle → toe)
/// jitters by up to 12° and its ankle by up to 3.2 cm, against the planner's 5° and 2 cm step
/// thresholds (before `FootstepConfig::pivot` and `slide` the NAO stepped 3, 1 and 2 times).
#[test]
fn walking_takes_no_step_for_a_standing_human() {
    for name in [
        "cmu_02_10_wash_self_standing_arm_gestures.bvh",
        "kinect2_labanotation_ges01_wavehand.csv",
        "kinect2_labanotation_ges02_balancinghands.csv",
    ] {
        let (m, _) = run_held(name, step_by_step(), HELD_FOOT_TOLERANCE, SETTLE_SECONDS);
        assert_eq!(m.robot_steps, 0, "{name}");
        assert_eq!(m.robot_support_sequence, vec!["DS"], "{name}");
    }
}

/// How far (m, rad) a standing foot may move in the plan of a dynamic walk: the walking table's
/// contact level ends every frame with its own Newton step, as the support phases' does
/// (measured: under 1e-9 m; 4e-5 m on CMU 09_12 before it had one).
const WALKING_FOOT_TOLERANCE: f64 = 1e-6;

/// The dynamic walk ([`FootstepConfig::dynamic`]) on the bundled walks: the robot takes steps of
/// the following timing (1.0 s double + 0.67 s single support on the NAO), the plan's ZMP stays at least 5 mm
/// inside the support polygon on every walking frame (the pattern generator's margin), the
/// invariants of `run_held` hold (limits, velocities, the CoM over the soles on the floor,
/// standing feet still) and the robot ends within 25 % of the scaled human's travel after a
/// 60 s hold (the NAO walks 5 cm steps of 1.67 s). This checks the plan; `.ci/physics` judges
/// it in physics.
#[test]
fn dynamic_walks_are_walked() {
    for name in [
        "cmu_07_04_slow_walk.bvh",
        "cmu_09_12_walk_forward_backward_sideways.bvh",
        "cmu_131_01_start_walk_stop_maxskel.bvh",
    ] {
        let (m, _) = run_held(name, dynamic(), WALKING_FOOT_TOLERANCE, 60.0);
        let w = m.walking.unwrap_or_else(|| panic!("{name}: never walked"));
        assert!(w.steps >= 6, "{name}: {w:?}");
        assert!(w.zmp_margin_min_m >= 0.005, "{name}: {w:?}");
        // A following step: 6 + 4 time constants of the cart-table (1.67 s on the NAO).
        let z = WalkParams::for_profile(&nao::profile())
            .unwrap()
            .settings
            .com_height;
        let expected = 10.0 * (z / 9.81).sqrt();
        let step = w.step_duration_s.expect("several steps per walk");
        assert!(
            (step - expected).abs() < 0.02,
            "{name}: {w:?}, {expected} s"
        );
        let t = &m.travel;
        assert!(
            (t.robot_m - t.scaled_human_m).abs() <= 0.25 * t.scaled_human_m,
            "{name}: {t:?}"
        );
        // It follows the human's steps, and goes on stepping after the human's last.
        let f = m
            .following
            .unwrap_or_else(|| panic!("{name}: the human stepped"));
        assert!(f.matched_steps >= 1, "{name}: {f:?}");
        assert!(f.catch_up_s.is_some_and(|s| s > 0.0), "{name}: {f:?}");
        // And ends near where the scaled human stands (measured at the automatic hold: 0.18,
        // 0.02 and 0.20 m off after 0.88, 0.27 and 0.65 m of the scaled human's travel).
        assert!(t.error_m < t.scaled_human_m / 3.0, "{name}: {t:?}");
    }
}

/// A human standing in place (CMU 02_10: arm gestures, feet pivoting a little) makes the
/// dynamic walk take no step at all: only where a human foot lands counts.
#[test]
fn dynamic_walk_takes_no_step_for_a_standing_human() {
    let (m, _) = run_held(
        "cmu_02_10_wash_self_standing_arm_gestures.bvh",
        dynamic(),
        HELD_FOOT_TOLERANCE,
        SETTLE_SECONDS,
    );
    assert_eq!(m.walking, None);
    assert_eq!(m.robot_support_sequence, vec!["DS"]);
}

/// The dynamic walk turns the way the human turns. CMU 05_02 starts with the left foot in
/// relevé (its toe 5.7 cm behind and 11.5 cm below the ankle), which once read as a foot
/// pointing backward and set the walk's starting heading: the robot turned 84° left while the
/// human's pelvis turned 43° (0.75 rad) right, a heading error of 2.20 rad at the end. The
/// error must now be below the human's own turn, the error of a robot that did not turn.
#[test]
fn dynamic_walk_turns_with_the_human() {
    let name = "cmu_05_02_stand_arm_gestures_turn_single_leg.bvh";
    let (m, _) = run_held(name, dynamic(), WALKING_FOOT_TOLERANCE, 60.0);
    let error = m.travel.heading_error_rad;
    assert!(error.abs() < 0.75, "{name}: {:?}", m.travel);
}

/// With `walking_arms` the hands follow the human while the robot walks (CMU 07_04, 60 s
/// hold): the invariants of `run_held` hold (limits, velocities, the arms clear of the torso,
/// the CoM over the soles, standing feet still), and the hands' mean error over the clip's
/// single-support frames (the human's steps, which the robot walks) is at least a fifth
/// smaller than with the arms held in the posture the walk started in (measured: 12.5 → 6.8 cm).
#[test]
fn walking_arms_follow_the_human_hands() {
    let name = "cmu_07_04_slow_walk.bvh";
    let single_support = |m: &ImitationMetrics| {
        let hands = &m.effectors_clip[..2];
        let frames: usize = hands.iter().map(|e| e.single_support.count).sum();
        let sum: f64 = (hands.iter())
            .map(|e| e.single_support.mean * e.single_support.count as f64)
            .sum();
        assert!(frames > 0, "{name}: no single-support frame");
        sum / frames as f64
    };
    let (held, _) = run_held(name, dynamic(), WALKING_FOOT_TOLERANCE, 60.0);
    let mut config = dynamic();
    config.poubel_mut().unwrap().footsteps.walking_arms = true;
    let (following, _) = run_held(name, config, WALKING_FOOT_TOLERANCE, 60.0);
    let (held, following) = (single_support(&held), single_support(&following));
    eprintln!("{name}: hands in single support {held:.4} → {following:.4} m");
    assert!(
        following < 0.8 * held,
        "{name}: {held:.4} → {following:.4} m"
    );
}

/// Walking step by step (`--walk`).
fn step_by_step() -> ImitatorConfig {
    ImitatorConfig::from(PoubelConfig {
        footsteps: FootstepConfig {
            follow: true,
            ..FootstepConfig::default()
        },
        ..PoubelConfig::default()
    })
}

fn dynamic() -> ImitatorConfig {
    ImitatorConfig::from(PoubelConfig {
        footsteps: FootstepConfig {
            follow: true,
            dynamic: true,
            ..FootstepConfig::default()
        },
        ..PoubelConfig::default()
    })
}

/// The offline mode ([`FootLookAhead`]) on the clips with one-leg stances it can follow: the
/// robot's foot never leaves the ground before the human's (no negative lag), its best-timed
/// lift comes a second or more sooner after the human's lift-off than online and its
/// best-timed landing sooner too, and the invariants hold.
#[test]
fn offline_mode_lifts_with_the_human() {
    for name in [
        "cmu_05_02_stand_arm_gestures_turn_single_leg.bvh",
        "cmu_07_04_slow_walk.bvh",
    ] {
        let clip = Clip::open(clip_path(name)).unwrap();
        let support = SupportConfig::for_capture(clip.capture());
        let frames: Vec<HumanFrame> = clip.collect::<Result<_, _>>().unwrap();
        let schedule = FootSchedule::of_clip(&frames, support).unwrap();
        let offline = ImitatorConfig::from(PoubelConfig {
            look_ahead: Some(FootLookAhead::new(schedule)),
            ..PoubelConfig::default()
        });
        let (ahead, _) = run_with(name, offline, HELD_FOOT_TOLERANCE);
        let (online, _) = run(name);
        let (a, o) = (ahead.lift_lag, online.lift_lag);
        let (la, lo) = (ahead.landing_lag, online.landing_lag);
        eprintln!("{name}: lift lag offline {a:?}, online {o:?}; landing lag {la:?}, {lo:?}");
        assert!(a.count >= 1 && o.count >= 1, "{name}: {a:?} {o:?}");
        assert!(
            a.min >= 0.0,
            "{name}: a foot lifted before the human's: {a:?}"
        );
        assert!(a.min < o.min - 1.0, "{name}: {a:?} vs {o:?}");
        assert!(la.min < lo.min, "{name}: {la:?} vs {lo:?}");
    }
}

#[test]
fn offline_mode_settings_are_checked() {
    let ahead = FootLookAhead::new(FootSchedule::default());
    let build = |look_ahead: FootLookAhead| {
        let config = ImitatorConfig::from(PoubelConfig {
            look_ahead: Some(look_ahead),
            ..PoubelConfig::default()
        });
        Imitator::new(nao::profile(), config)
            .err()
            .map(|e| e.to_string())
    };
    assert_eq!(build(ahead.clone()), None);
    for (lift_lead, landing_lead, name) in [
        (-0.1, 0.8, "look_ahead.lift_lead"),
        (1.5, f64::NAN, "look_ahead.landing_lead"),
        (f64::INFINITY, 0.8, "look_ahead.lift_lead"),
    ] {
        let bad = FootLookAhead {
            lift_lead,
            landing_lead,
            ..ahead.clone()
        };
        let error = build(bad);
        assert!(
            error.as_ref().is_some_and(|e| e.contains(name)),
            "{error:?}"
        );
    }
}

#[test]
fn other_clips_keep_the_invariants() {
    for name in [
        "cmu_05_12_slow_dance_tendu_arms_high.bvh",
        "kinect2_labanotation_ges01_wavehand.csv",
        "kinect2_labanotation_ges02_balancinghands.csv",
    ] {
        run(name);
    }
}

/// At the full rated joint speeds (two IK steps per frame, tasks up to 1 m/s, the CoM and the
/// swing foot shaped twice as fast as by default) the robot takes several steps of a 21 s walk;
/// landings end flat, so no tilt of the world builds up over them, and the invariants still
/// hold on every frame.
#[test]
fn a_walk_at_full_speed_keeps_the_invariants() {
    let config = ImitatorConfig {
        method: ImitationMethod::Poubel(PoubelConfig {
            max_task_speed: Some(1.0),
            iterations_per_frame: 2,
            ..PoubelConfig::default()
        }),
        velocity_fraction: Some(1.0),
        upper_body_velocity_fraction: Some(1.0),
        motion: Some(MotionLimits {
            com_speed: 0.1,
            com_acceleration: 0.6,
            foot_speed: 0.1,
            ..MotionLimits::default()
        }),
        ..ImitatorConfig::default()
    };
    // Steps larger than by default: the held foot's second-order error grows with their square.
    let (m, _) = run_with(
        "cmu_09_12_walk_forward_backward_sideways.bvh",
        config,
        10.0 * HELD_FOOT_TOLERANCE,
    );
    assert!(
        m.robot_support_changes >= 6,
        "{:?}",
        m.robot_support_sequence
    );
}

/// A user table with more tasks than Table I (the head tracked too in every phase, and nine more
/// frames' heights held: up to 17 tasks) is solved and reported whole.
#[test]
fn overridden_tables_are_solved_and_reported_whole() {
    use taskstack::human::HumanJoint;
    use taskstack::imitation::phase::PhaseConfig;
    use taskstack::imitation::phase::tables::{Axes, PointTarget, Task, TaskTables};
    let mut tables = TaskTables::contact_first(&PhaseConfig::default(), &nao::profile());
    for phase in SupportPhase::ALL {
        let mut table = tables.table(phase).clone();
        let last = table.levels.len() - 1;
        table.levels[last].tasks.push(Task::Point {
            frame: "gaze".into(),
            offset: [0.0; 3],
            axes: Axes::XYZ,
            target: PointTarget::Scaled(HumanJoint::Head),
        });
        // And the heights of nine more frames held, for a table larger than any of Table I's.
        for frame in [
            "head",
            "l_elbow",
            "r_elbow",
            "l_knee",
            "r_knee",
            "l_wrist",
            "r_wrist",
            "l_shoulder",
            "r_shoulder",
        ] {
            table.levels[last].tasks.push(Task::Point {
                frame: frame.into(),
                offset: [0.0; 3],
                axes: Axes::Z,
                target: PointTarget::Held { lift: 0.0 },
            });
        }
        tables.set(table).unwrap();
    }
    let config = ImitatorConfig::from(PoubelConfig {
        tables: Some(tables.clone()),
        ..PoubelConfig::default()
    });
    // Double support (17 tasks) and a walk's single supports and transitions (14 and 15 tasks).
    for name in [
        "cmu_02_10_wash_self_standing_arm_gestures.bvh",
        "cmu_07_04_slow_walk.bvh",
    ] {
        let mut clip = Clip::open(clip_path(name)).unwrap();
        let config = ImitatorConfig {
            support: SupportConfig::for_capture(clip.capture()),
            ..config.clone()
        };
        let mut imitator = Imitator::new(nao::profile(), config).unwrap();
        let mut frame = HumanFrame::new(0.0);
        while clip.read_frame(&mut frame).unwrap() && frame.time < 3.0 {
            let r = imitator.step(&frame).unwrap();
            let expected: usize = tables
                .table(r.phase)
                .levels
                .iter()
                .map(|l| l.tasks.len())
                .sum();
            assert_eq!(r.task_count, expected, "{}", r.phase);
            assert!(r.task_errors[..r.task_count].iter().all(|e| e.is_finite()));
        }
    }
}

/// Koenemann et al.'s method keeps the same invariants on every bundled clip (every `.bvh` and
/// `.csv` in `tests/data/mocap`: limits, velocity
/// limits, the CoM inside the polygon of the feet on the ground, no slip of a standing foot),
/// and follows the single-leg stance of `cmu_05_02` (the offset reaches the right foot before
/// the left lifts, and the left comes back down).
#[test]
fn koenemann_keeps_the_invariants_on_every_clip() {
    let config = ImitatorConfig::from(KoenemannConfig::default());
    let mut names: Vec<String> = std::fs::read_dir(clip_path(""))
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .filter(|n| n.ends_with(".bvh") || n.ends_with(".csv"))
        .collect();
    names.sort();
    assert!(names.len() >= 8, "the bundled clips: {names:?}");
    for name in &names {
        let (m, _) = run_with(name, config.clone(), KOENEMANN_FOOT_TOLERANCE);
        if name.starts_with("cmu_05_02") {
            assert!(
                contains(&m.robot_support_sequence, &["DS", "RS", "DS"]),
                "{:?}",
                m.robot_support_sequence
            );
        }
    }
}

/// Koenemann et al.'s arms on CMU 02_10, where the human folds the right arm tighter than the
/// NAO's elbow bends: the hand target is kept beyond the folded arm's reach, so the arm's IK
/// does not press the elbow into its limit frame after frame while the wrist turns back and
/// forth at its velocity bound (145 frames of 2 400 had a joint reversing at speed, 135 of
/// them the right wrist's yaw; `ImitationMetrics::joint_reversal_frames`).
#[test]
fn koenemann_arms_do_not_chatter_on_a_tightly_folded_arm() {
    let config = ImitatorConfig::from(KoenemannConfig::default());
    let name = "cmu_02_10_wash_self_standing_arm_gestures.bvh";
    let (m, _) = run_with(name, config, KOENEMANN_FOOT_TOLERANCE);
    assert!(
        m.joint_reversal_frames * 200 <= m.frames,
        "{} of {} frames with a joint turning back at speed",
        m.joint_reversal_frames,
        m.frames
    );
}

/// Damping toward the last step ([`PoubelConfig::damping_momentum`]). With fast hands and
/// the ZMP level, CMU 05_02's arms reverse at speed on 90 of 1 123 frames at the textbook
/// damping (0.02 toward rest); a damping of 0.1 toward rest stops that but leaves the hands
/// 9.8 cm from the human on average, 0.1 toward 0.8 of the last step 8.1 cm (measured by
/// the CLI, `--zmp-balance --tracking-speed 1 --tracking-acceleration 10 --damping 0.1`).
/// Over the clip the momentum brings the hands' mean error from 5.4 to 4.4 cm (NAO support
/// margin 20 mm); the test asks for at least 5 mm.
/// The run's invariants ([`run_with`]: limits, held feet, self-collision margin) hold.
#[test]
fn damping_toward_the_last_step_stops_the_chatter_and_keeps_the_hands() {
    let name = "cmu_05_02_stand_arm_gestures_turn_single_leg.bvh";
    let run = |momentum: f64| {
        let config = ImitatorConfig {
            method: ImitationMethod::Poubel(PoubelConfig {
                zmp_balance: Some(true),
                damping_momentum: momentum,
                damping: Some(0.1),
                ..PoubelConfig::default()
            }),
            max_tracking_speed: Some(1.0),
            max_tracking_acceleration: Some(10.0),
            ..ImitatorConfig::default()
        };
        let (m, _) = run_with(name, config, HELD_FOOT_TOLERANCE);
        let hands: Vec<f64> = (m.effectors_clip.iter())
            .filter(|e| e.name.ends_with("hand"))
            .map(|e| e.mean().unwrap())
            .collect();
        (hands.iter().sum::<f64>() / hands.len() as f64, m)
    };
    // Out of range: refused by name, not ignored (Koenemann's method has neither setting).
    for (momentum, damping, name) in [
        (1.5, None, "poubel.damping_momentum"),
        (f64::NAN, None, "poubel.damping_momentum"),
        (0.0, Some(0.0), "poubel.damping"),
        (0.0, Some(f64::INFINITY), "poubel.damping"),
    ] {
        let config = ImitatorConfig::from(PoubelConfig {
            damping_momentum: momentum,
            damping,
            ..PoubelConfig::default()
        });
        let refused = Imitator::new(nao::profile(), config).err();
        assert!(
            refused.is_some_and(|e| e.to_string().contains(name)),
            "{name}"
        );
    }
    let (at_rest, _) = run(0.0);
    let (moving, m) = run(0.8);
    assert!(
        moving + 0.005 < at_rest,
        "hands {moving} m with the momentum, {at_rest} m without"
    );
    assert!(
        m.joint_reversal_frames * 100 <= m.frames,
        "{} of {} frames with a joint turning back at speed",
        m.joint_reversal_frames,
        m.frames
    );
}

/// The clip `name` opened, and the NAO's imitator for it at default settings.
fn nao_on(name: &str) -> (Clip, Imitator) {
    let clip = Clip::open(clip_path(name)).unwrap();
    let config = ImitatorConfig {
        support: SupportConfig::for_capture(clip.capture()),
        ..ImitatorConfig::default()
    };
    (clip, Imitator::new(nao::profile(), config).unwrap())
}

/// The hands' IK keeps each elbow 0.3 rad (`MIN_ELBOW_BEND`) from the straight arm: a
/// straight elbow is singular, and CMU 02_10's right hand, reaching over its head and back
/// down, stayed straight-armed 20 cm off its reference for 6 s before. The NAO's documented
/// elbow roll ranges are left [−88.5°, −2°], right [2°, 88.5°]; the arm is straight near 0
/// (within 0.03 rad: the hand's offsets), so the elbows stay at least 0.27 rad bent, and on
/// this clip they reach that bound.
#[test]
fn the_hands_keep_the_elbows_bent() {
    let (mut clip, mut imitator) = nao_on("cmu_02_10_wash_self_standing_arm_gestures.bvh");
    let names: Vec<String> = imitator.variable_names().map(str::to_owned).collect();
    let index = |name: &str| names.iter().position(|n| n == name).unwrap();
    let (left, right) = (index("LElbowRoll"), index("RElbowRoll"));
    let mut frame = HumanFrame::new(0.0);
    let mut least = f64::INFINITY;
    while clip.read_frame(&mut frame).unwrap() {
        let q = &imitator.step(&frame).unwrap().q;
        least = least.min(-q[left]).min(q[right]);
    }
    assert!(least >= 0.27, "an elbow at {least} rad");
    assert!(least < 0.33, "the elbows never near straight: {least} rad");
}

/// Poubel's method hangs the scaled arms from the robot's shoulders: each frame's shoulder
/// references are the NAO's shoulder frames in the posture it stood in before the frame
/// (forward kinematics here, in the model of the frame's root: CMU 07_04 steps onto a leg, so
/// the root switches soles), and on this walk no hand reference lies beyond the arm's reach
/// (61 of its frames did with the arms hung from the scaled shoulders, the human's shoulders
/// swaying as it walks).
#[test]
fn the_arms_hang_from_the_robots_shoulders() {
    let (mut clip, mut imitator) = nao_on("cmu_07_04_slow_walk.bvh");
    let profile = imitator.profile().clone();
    let mut data = profile.models.each_ref().map(|m| m.new_data());
    let mut recorder = MetricsRecorder::new(&imitator);
    let mut frame = HumanFrame::new(0.0);
    let mut before: Option<Vec<f64>> = None;
    let mut checked = 0;
    while clip.read_frame(&mut frame).unwrap() {
        let out = imitator.step(&frame).unwrap();
        recorder.record(out);
        if let Some(q) = &before {
            let (model, data) = (profile.model(out.root), &mut data[out.root.index()]);
            model.forward_kinematics(data, q).unwrap();
            for (joint, name) in [
                (HumanJoint::LShoulder, "l_shoulder"),
                (HumanJoint::RShoulder, "r_shoulder"),
            ] {
                let robot = data.frame_placement(model.frame_id(name).unwrap());
                let reference = out.reference[joint.index()].expect("a shoulder reference");
                assert!(
                    (robot.translation.vector - reference).norm() < 1e-12,
                    "t = {}: {name} {reference} vs the robot's {}",
                    out.time,
                    robot.translation.vector
                );
            }
            checked += 1;
        }
        before = Some(out.q.clone());
    }
    assert!(checked > 400, "{checked} frames");
    let reach = recorder.finish().hand_reach.expect("the NAO maps its arms");
    for hand in reach {
        assert_eq!(hand.unreachable_frames, 0, "{hand:?}");
    }
}

/// The CoM tasks move only the joints that turn the torso, a sole or a hand: the NAO's head,
/// which moves the CoM by millimetres per radian, stays where the posture gradient keeps it,
/// facing forward (a clip gives no head angles). When the balance level also moved the head,
/// a level the legs could not meet (their joints at their limits) drove it at its speed limit:
/// over CMU 07_04 the head turned 0.57 rad and pitched 0.37 rad (measured before the change;
/// on 02_10 it swept its whole yaw range, ±2.09 rad).
#[test]
fn the_balance_level_leaves_the_head_alone() {
    let (mut clip, mut imitator) = nao_on("cmu_07_04_slow_walk.bvh");
    let model = imitator.profile().model(Side::Right);
    let head = ["HeadYaw", "HeadPitch"].map(|name| model.variable_index(name).unwrap());
    let mut frame = HumanFrame::new(0.0);
    let mut largest: f64 = 0.0;
    while clip.read_frame(&mut frame).unwrap() {
        let q = &imitator.step(&frame).unwrap().q;
        largest = head.iter().fold(largest, |m, &k| m.max(q[k].abs()));
    }
    assert!(largest < 0.1, "the head turned {largest} rad");
}

/// What a frame reports of the robot (its hands and ankles in the root's frame, the world CoM)
/// is the forward kinematics of the posture it reports, computed here afresh in the model of
/// the frame's root. Poubel's method reuses the kinematics its last solve left instead of
/// computing them again at the next frame's start; CMU 131_01 steps onto each leg, so the
/// root switches soles and the reused kinematics place the new root in the world.
#[test]
fn each_frame_reports_the_kinematics_of_its_posture() {
    let (mut clip, mut imitator) = nao_on("cmu_131_01_start_walk_stop_maxskel.bvh");
    let profile = imitator.profile().clone();
    let mut data = profile.models.each_ref().map(|m| m.new_data());
    let mut frame = HumanFrame::new(0.0);
    let (mut frames, mut roots) = (0, [false; 2]);
    while clip.read_frame(&mut frame).unwrap() {
        let out = imitator.step(&frame).unwrap();
        let (model, data) = (profile.model(out.root), &mut data[out.root.index()]);
        model.forward_kinematics(data, &out.q).unwrap();
        let names = [
            &profile.hands[0],
            &profile.hands[1],
            &profile.foot(Side::Left).ankle,
            &profile.foot(Side::Right).ankle,
        ];
        for (name, reported) in names.iter().zip(&out.effectors) {
            let fresh = data
                .frame_placement(model.frame_id(name).unwrap())
                .translation
                .vector;
            assert!(
                (fresh - reported).norm() < 1e-12,
                "frame {frames}: {name} {fresh} vs {reported}"
            );
        }
        let com = out
            .world_t_root
            .transform_point(&model.com(data).unwrap().into())
            .coords;
        assert!((com - out.com).norm() < 1e-12, "frame {frames}: CoM");
        roots[out.root.index()] = true;
        frames += 1;
    }
    assert!(
        roots == [true, true],
        "the clip roots the model at both soles"
    );
}

/// With a budget of passes (`Settings::max_passes`) every frame's solve of Poubel's method
/// takes at most that many, and the invariants of `run_held` hold. CMU 131_01 steps onto one
/// leg and back: without a budget its lift and landing frames took up to 21 passes, so both
/// budgets are reached there (a solve cut short reports itself not converged).
#[test]
fn each_frame_solves_within_its_pass_budget() {
    let name = "cmu_131_01_start_walk_stop_maxskel.bvh";
    for budget in [8, 3] {
        let mut config = ImitatorConfig::default();
        config.poubel_mut().unwrap().solver.max_passes = Some(budget);
        run_held(name, config.clone(), HELD_FOOT_TOLERANCE, 1.0);
        let (mut clip, _) = nao_on(name);
        config.support = SupportConfig::for_capture(clip.capture());
        let mut imitator = Imitator::new(nao::profile(), config).unwrap();
        let (mut frame, mut most, mut cut) = (HumanFrame::new(0.0), 0, 0);
        while clip.read_frame(&mut frame).unwrap() {
            let out = imitator.step(&frame).unwrap();
            let passes = out.solve_passes;
            assert!(passes <= budget, "t = {}: {passes} passes", out.time);
            most = most.max(passes);
            cut += usize::from(passes == budget && !out.solve_converged);
        }
        assert_eq!(most, budget);
        assert!(cut > 0, "no solve was cut short at {budget} passes");
    }
}

/// The largest vertical moment (N·m) the arms' motion asks of the floor over `name` with
/// `config`: recomputed from the frames' postures, `Ḣ_z = (H(q₋, v) − H(q₋, v₋))/Δt` with `H`
/// the links' momentum by differences (`common::momentum_by_differences`) for the arms'
/// joints' velocities alone (picked by name), in the model of the frame's root.
fn arms_yaw_moment(name: &str, config: ImitatorConfig) -> (f64, ImitationMetrics) {
    let mut clip = Clip::open(clip_path(name)).unwrap();
    let config = ImitatorConfig {
        support: SupportConfig::for_capture(clip.capture()),
        ..config
    };
    let mut imitator = Imitator::new(nao::profile(), config).unwrap();
    let profile = imitator.profile().clone();
    let arms: Vec<bool> = (imitator.variable_names())
        .map(|n| ["Shoulder", "Elbow", "Wrist"].iter().any(|a| n.contains(a)))
        .collect();
    assert_eq!(arms.iter().filter(|a| **a).count(), 10);
    let mut recorder = MetricsRecorder::new(&imitator);
    let mut frames: Vec<(Side, Vec<f64>, f64)> = Vec::new();
    let mut frame = HumanFrame::new(0.0);
    while clip.read_frame(&mut frame).unwrap() {
        let out = imitator.step(&frame).unwrap();
        recorder.record(out);
        frames.push((out.root, out.q.clone(), out.time));
    }
    let mut worst: f64 = 0.0;
    for w in frames.windows(3) {
        let [(r0, q0, t0), (r1, q1, t1), (r2, q2, t2)] = [&w[0], &w[1], &w[2]];
        if r0 != r1 || r1 != r2 {
            continue;
        }
        let velocity = |a: &[f64], b: &[f64], dt: f64| -> Vec<f64> {
            (a.iter().zip(b).zip(&arms))
                .map(|((a, b), arm)| if *arm { (b - a) / dt } else { 0.0 })
                .collect()
        };
        let (before, now) = (velocity(q0, q1, t1 - t0), velocity(q1, q2, t2 - t1));
        let model = profile.model(*r1);
        let rate = (common::momentum_by_differences(model, q1, &now)
            - common::momentum_by_differences(model, q1, &before))
            / (t2 - t1);
        if rate.z.abs() > 0.35 {
            eprintln!("t {t2:.3} yaw {:.3}", rate.z);
        }
        worst = worst.max(rate.z.abs());
    }
    (worst, recorder.finish())
}

/// The ZMP balance alone gives the NAO's hands its profile's balanced speeds, 1 m/s and
/// 10 m/s² in every phase (`MotionTuning::balanced_hands`): the same joint angles as with those
/// speeds asked for by hand, and not the angles of the ordinary speeds.
#[test]
fn zmp_balance_moves_the_hands_at_the_profiles_balanced_speeds() {
    let name = "kinect2_labanotation_ges02_balancinghands.csv";
    let angles = |config: ImitatorConfig| -> Vec<Vec<f64>> {
        let mut clip = Clip::open(clip_path(name)).unwrap();
        let config = ImitatorConfig {
            support: SupportConfig::for_capture(clip.capture()),
            ..config
        };
        let mut imitator = Imitator::new(nao::profile(), config).unwrap();
        let mut frame = HumanFrame::new(0.0);
        let mut out = Vec::new();
        while clip.read_frame(&mut frame).unwrap() {
            out.push(imitator.step(&frame).unwrap().q.clone());
        }
        out
    };
    let balanced = ImitatorConfig::from(PoubelConfig {
        zmp_balance: Some(true),
        ..PoubelConfig::default()
    });
    let asked = ImitatorConfig {
        max_tracking_speed: Some(1.0),
        max_tracking_acceleration: Some(5.0),
        ..balanced.clone()
    };
    let ordinary = ImitatorConfig {
        max_tracking_speed: Some(nao::TUNING.tracking_speed),
        max_tracking_acceleration: Some(nao::TUNING.tracking_acceleration),
        ..balanced.clone()
    };
    let by_default = angles(balanced);
    assert_eq!(by_default, angles(asked));
    assert_ne!(by_default, angles(ordinary));
}

/// The ZMP balance with hands at 1 m/s (10 m/s²): the arms' vertical moment on the floor,
/// recomputed from the postures, stays within the profile's bound; without it the same hands
/// ask the floor for several times more (the judge's loaded feet turned 3.5–4.6° on this clip),
/// and the hands follow about as closely either way.
#[test]
fn zmp_balance_bounds_the_arms_moment_on_the_floor() {
    let name = "kinect2_labanotation_ges02_balancinghands.csv";
    let fast = |zmp_balance| ImitatorConfig {
        method: ImitationMethod::Poubel(PoubelConfig {
            zmp_balance,
            ..PoubelConfig::default()
        }),
        max_tracking_speed: Some(1.0),
        max_tracking_acceleration: Some(10.0),
        ..ImitatorConfig::default()
    };
    let bound = nao::profile().max_floor_yaw_moment();
    let (free, free_metrics) = arms_yaw_moment(name, fast(Some(false)));
    let (balanced, balanced_metrics) = arms_yaw_moment(name, fast(Some(true)));
    let hands = |m: &ImitationMetrics| {
        let e = &m.effectors_clip[..2];
        (e[0].double_support.mean + e[1].double_support.mean) / 2.0
    };
    eprintln!(
        "{name}: arms' vertical moment {free:.3} → {balanced:.3} N·m (bound {bound:.3}); hands {:.4} → {:.4} m",
        hands(&free_metrics),
        hands(&balanced_metrics)
    );
    assert!(free > 2.0 * bound, "{free} N·m without the ZMP level");
    assert!(balanced < 1.1 * bound, "{balanced} N·m, bound {bound}");
    assert!(hands(&balanced_metrics) < hands(&free_metrics) + 0.005);
}
