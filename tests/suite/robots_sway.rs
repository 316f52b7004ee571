//! The sway shaper (`robots::sway`): commands that leave a lightly damped mode at the design
//! period still. Checked on an oscillator integrated here (`ẍ = ω² (u − x) − 2ζω ẋ`, the sway
//! mode driven by the command `u`), not against the shaper's own weights.

use nalgebra::Vector3;
use taskstack::human::{HumanFrame, HumanJoint};
use taskstack::imitation::config::ImitationMethod;
use taskstack::imitation::koenemann::KoenemannConfig;
use taskstack::imitation::reference::support::SupportConfig;
use taskstack::imitation::{Imitator, ImitatorConfig};
use taskstack::io::clip::Clip;
use taskstack::robots::sway::{SWAY_DAMPING, SwayError, SwayShaper};
use taskstack::robots::{BipedProfile, g1};

const DT: f64 = 1.0 / 120.0;

/// The largest swing `|x − 1|` of the mode (period `mode_period`) after a unit step of the
/// command at t = 0.2 s, shaped for `design_period` (or not shaped), once the shaped command
/// has settled.
fn residual_sway(design_period: Option<f64>, mode_period: f64) -> f64 {
    let mut shaper = design_period.map(|p| SwayShaper::new(p, 1, DT).unwrap());
    let omega = 2.0 * std::f64::consts::PI / mode_period;
    let (mut x, mut v, mut largest) = (0.0_f64, 0.0_f64, 0.0_f64);
    let settled = 0.2 + design_period.unwrap_or(0.0);
    for k in 0..(8.0 / DT) as usize {
        let t = k as f64 * DT;
        let mut u = [if t >= 0.2 { 1.0 } else { 0.0 }];
        if let Some(shaper) = &mut shaper {
            shaper.shape(t, &mut u).unwrap();
        }
        // Semi-implicit Euler in 100 substeps: the mode is integrated, the command held.
        let h = DT / 100.0;
        for _ in 0..100 {
            v += h * (omega * omega * (u[0] - x) - 2.0 * SWAY_DAMPING * omega * v);
            x += h * v;
        }
        if t > settled + DT {
            largest = largest.max((x - 1.0).abs());
        }
    }
    largest
}

#[test]
fn a_shaped_step_leaves_the_sway_mode_still_near_its_period() {
    let unshaped = residual_sway(None, 1.0);
    assert!(
        unshaped > 0.8,
        "an unshaped step rocks the mode: {unshaped}"
    );
    let at_period = residual_sway(Some(1.0), 1.0);
    assert!(at_period < 0.01 * unshaped, "{at_period} of {unshaped}");
    // The derivative's zero: a mode 10 % off the design period rocks at under 5 % of an
    // unshaped step's (undamped: cos²(πr/2) for the frequency ratio r: 2.4 %), 25 % off at
    // under 20 % (14.6 % at r = 1.25, 9.5 % at 0.8).
    for (mode, share) in [(0.9, 0.05), (1.1, 0.05), (0.8, 0.2), (1.25, 0.2)] {
        let off = residual_sway(Some(1.0), mode);
        let unshaped = residual_sway(None, mode);
        assert!(off < share * unshaped, "mode {mode} s: {off} of {unshaped}");
    }
}

#[test]
fn the_shaped_command_follows_a_ramp_half_a_period_late() {
    let period = 1.1;
    let mut shaper = SwayShaper::new(period, 2, DT).unwrap();
    let delay = shaper.mean_delay();
    assert!(delay > 0.45 * period && delay <= 0.5 * period, "{delay}");
    for k in 0..400 {
        let t = k as f64 * DT;
        let mut u = [t, -2.0 * t];
        shaper.shape(t, &mut u).unwrap();
        if t >= period {
            assert!((u[0] - (t - delay)).abs() < 1e-12, "t {t}: {}", u[0]);
            assert!((u[1] + 2.0 * (t - delay)).abs() < 1e-12, "t {t}: {}", u[1]);
        }
    }
}

#[test]
fn shaped_commands_stay_between_the_commands_at_any_frame_times() {
    // Frames at uneven times (a repeated time too): the shaped value is a mix of commands.
    let mut shaper = SwayShaper::new(0.5, 1, 0.1).unwrap();
    let (mut t, mut seen) = (0.0_f64, (f64::INFINITY, f64::NEG_INFINITY));
    for k in 0..300_u32 {
        t += [0.0, 0.003, 0.02, 0.007][(k % 4) as usize];
        let value = (f64::from(k) * 0.37).sin() * f64::from(k % 7);
        seen = (seen.0.min(value), seen.1.max(value));
        let mut u = [value];
        shaper.shape(t, &mut u).unwrap();
        assert!(u[0] >= seen.0 - 1e-12 && u[0] <= seen.1 + 1e-12, "k {k}");
    }
}

#[test]
fn bad_periods_and_commands_are_refused() {
    for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        assert!(matches!(
            SwayShaper::new(bad, 3, DT),
            Err(SwayError::Period(_))
        ));
    }
    let mut shaper = SwayShaper::new(1.0, 2, DT).unwrap();
    shaper.shape(1.0, &mut [0.1, 0.2]).unwrap();
    let err = shaper.shape(0.5, &mut [0.1, 0.2]).unwrap_err();
    assert!(matches!(err, SwayError::Time { .. }), "{err}");
    assert!(matches!(
        shaper.shape(f64::NAN, &mut [0.1, 0.2]),
        Err(SwayError::Time { .. })
    ));
    assert!(matches!(
        shaper.shape(2.0, &mut [0.1]),
        Err(SwayError::Length {
            expected: 2,
            got: 1
        })
    ));
    let mut nan = [0.1, f64::NAN];
    assert!(matches!(
        shaper.shape(2.0, &mut nan),
        Err(SwayError::NonFinite(_))
    ));
    // A refused command leaves the shaper as it was: the next one is shaped from 1.0 s on.
    let mut u = [0.1, 0.2];
    shaper.shape(1.0, &mut u).unwrap();
    assert!(
        (u[0] - 0.1).abs() < 1e-15 && (u[1] - 0.2).abs() < 1e-15,
        "{u:?}"
    );
}

#[test]
fn the_g1_commands_its_servo_targets_through_the_shaper() {
    let profile = g1::profile();
    let period = profile.sway_period.expect("the G1 states its sway");
    let unshaped = BipedProfile {
        sway_period: None,
        ..profile.clone()
    };
    // Both wait the shaper's length before a lift (the shaped robot's default), so that only
    // the shaping differs.
    let (mut clip, config) = slow_dance(Some(period));
    let mut shaped = Imitator::new(profile, config.clone()).unwrap();
    let mut plain = Imitator::new(unshaped, config.clone()).unwrap();
    let n = shaped.variable_names().count();
    let mut shaper = SwayShaper::new(period, n, config.nominal_dt).unwrap();
    let mut frame = HumanFrame::new(0.0);
    let mut largest_lag = 0.0_f64;
    while clip.read_frame(&mut frame).unwrap() {
        let a = shaped.step(&frame).unwrap().clone();
        let b = plain.step(&frame).unwrap();
        assert_eq!(a.q, b.q, "the plan is not shaped");
        let mut expected = b.servo_targets.clone();
        shaper.shape(b.time, &mut expected).unwrap();
        assert_eq!(a.servo_targets, expected, "t = {}", a.time);
        let lag = a.servo_targets.iter().zip(&b.servo_targets);
        largest_lag = lag.fold(largest_lag, |m, (x, y)| m.max((x - y).abs()));
    }
    assert!(
        largest_lag > 0.01,
        "the shaper moved nothing: {largest_lag}"
    );
}

/// CMU 05_12 (a slow dance with single supports) and the default settings for it, with the
/// weight shift's `settle_time`.
fn slow_dance(settle_time: Option<f64>) -> (Clip, ImitatorConfig) {
    let path = format!(
        "{}/tests/data/mocap/cmu_05_12_slow_dance_tendu_arms_high.bvh",
        env!("CARGO_MANIFEST_DIR")
    );
    let clip = Clip::open(path).unwrap();
    let mut config = ImitatorConfig {
        support: SupportConfig::for_capture(clip.capture()),
        ..ImitatorConfig::default()
    };
    config.poubel_mut().unwrap().phase.settle_time = settle_time;
    (clip, config)
}

/// The robot time (s) of the first of `frames` whose phase has a foot in the air.
fn first_airborne(imitator: &mut Imitator, frames: impl Iterator<Item = HumanFrame>) -> f64 {
    for frame in frames {
        let out = imitator.step(&frame).unwrap();
        if out.phase.airborne_foot().is_some() {
            return out.time;
        }
    }
    panic!("the robot never lifted a foot");
}

/// The robot time (s) of the slow dance's first frame with a foot in the air.
fn first_lift(profile: &BipedProfile, settle_time: Option<f64>) -> f64 {
    let (mut clip, config) = slow_dance(settle_time);
    let mut imitator = Imitator::new(profile.clone(), config).unwrap();
    let mut frame = HumanFrame::new(0.0);
    let frames = std::iter::from_fn(|| clip.read_frame(&mut frame).unwrap().then_some(frame));
    first_airborne(&mut imitator, frames)
}

#[test]
fn the_g1_lifts_a_foot_a_sway_period_after_its_weight_is_over_the_other() {
    // Until the first lift both runs are the same frame for frame; the default (the profile's
    // sway period) holds the finished weight shift for the shaper's length before the lift,
    // to within a frame (the clip's frame times are rounded).
    let profile = g1::profile();
    let period = profile.sway_period.unwrap();
    let waited = first_lift(&profile, None) - first_lift(&profile, Some(0.0));
    let dt = ImitatorConfig::default().nominal_dt;
    assert!(
        (waited - period).abs() <= dt,
        "waited {waited} s for a sway period of {period} s"
    );
}

/// Koenemann's method on the G1 with `method`, and a human who stands still on both feet for
/// 1 s (the first frame of CMU 05_02) and then holds the right foot 15 cm up for 5 s.
fn koenemann_lifting_right_foot(method: KoenemannConfig) -> (Imitator, Vec<HumanFrame>) {
    let path = format!(
        "{}/tests/data/mocap/cmu_05_02_stand_arm_gestures_turn_single_leg.bvh",
        env!("CARGO_MANIFEST_DIR")
    );
    let mut clip = Clip::open(path).unwrap();
    let config = ImitatorConfig {
        support: SupportConfig::for_capture(clip.capture()),
        method: ImitationMethod::Koenemann(method),
        ..ImitatorConfig::default()
    };
    let mut standing = HumanFrame::new(0.0);
    assert!(clip.read_frame(&mut standing).unwrap());
    let frames = (0..720).map(|k| {
        let mut frame = standing;
        frame.time = k as f64 * DT;
        if frame.time >= 1.0 {
            for joint in [HumanJoint::RAnkle, HumanJoint::RToe] {
                let lifted = frame.get(joint).map(|p| p + Vector3::z() * 0.15);
                frame.set(joint, lifted);
            }
        }
        frame
    });
    let imitator = Imitator::new(g1::profile(), config).unwrap();
    (imitator, frames.collect())
}

/// The robot time (s) of the first frame with a foot in the air in
/// [`koenemann_lifting_right_foot`], with the weight shift's `settle_time`.
fn first_koenemann_lift(settle_time: Option<f64>) -> f64 {
    let (mut imitator, frames) = koenemann_lifting_right_foot(KoenemannConfig {
        settle_time,
        ..KoenemannConfig::default()
    });
    first_airborne(&mut imitator, frames.into_iter())
}

#[test]
fn the_g1_on_koenemanns_method_also_waits_a_sway_period_before_a_lift() {
    let period = g1::profile().sway_period.unwrap();
    let waited = first_koenemann_lift(None) - first_koenemann_lift(Some(0.0));
    assert!(
        (waited - period).abs() <= DT,
        "waited {waited} s for a sway period of {period} s"
    );
}

/// The largest leg-joint acceleration (as a share of the ramp's `v_max / T`, `T` the G1's sway
/// period) and CoM acceleration (m/s², horizontal, during the weight shift from 1 to 3 s) of
/// [`koenemann_lifting_right_foot`] with the legs' `leg_ramp_time`, by second differences of
/// the output (the CoM in the root frame, over frames with one root).
fn koenemann_leg_and_com_accelerations(leg_ramp_time: Option<f64>) -> (f64, f64) {
    let (mut imitator, frames) = koenemann_lifting_right_foot(KoenemannConfig {
        leg_ramp_time,
        ..KoenemannConfig::default()
    });
    let profile = g1::profile();
    let legs = profile.sole_chain_variables(&profile.stand).unwrap();
    let period = profile.sway_period.unwrap();
    let ramp: Vec<f64> = (imitator.bounds().velocity().iter())
        .map(|v| v / period)
        .collect();
    let outputs: Vec<_> = frames
        .iter()
        .map(|frame| imitator.step(frame).unwrap().clone())
        .collect();
    let (mut legs_share, mut com) = (0.0_f64, 0.0_f64);
    for w in outputs.windows(3) {
        for i in (0..legs.len()).filter(|&i| legs[i]) {
            let a = (w[2].q[i] - 2.0 * w[1].q[i] + w[0].q[i]) / (DT * DT);
            legs_share = legs_share.max(a.abs() / ramp[i]);
        }
        let shifting = w[0].time >= 1.0 && w[2].time <= 3.0;
        if shifting && w[0].root == w[2].root {
            let a = (w[2].com - 2.0 * w[1].com + w[0].com) / (DT * DT);
            com = com.max(a.xy().norm());
        }
    }
    (legs_share, com)
}

#[test]
fn the_g1_on_koenemanns_method_ramps_its_legs_over_a_sway_period() {
    // Ramped (the default: the profile's sway period), each leg joint changes its speed by at
    // most v_max / T per second, and the held sole's correction in double support adds what
    // the legs' common line left (up to about twice that); unramped (0), the legs start and
    // stop at their velocity limit within a frame, a hundred times the ramp's rate. The CoM
    // they carry accelerates less as it shifts onto the left foot (0.31 against 0.55 m/s²).
    let (ramped_legs, ramped_com) = koenemann_leg_and_com_accelerations(None);
    let (abrupt_legs, abrupt_com) = koenemann_leg_and_com_accelerations(Some(0.0));
    assert!(ramped_legs < 3.0, "ramped legs at {ramped_legs} × the ramp");
    assert!(
        abrupt_legs > 30.0,
        "unramped legs at {abrupt_legs} × the ramp"
    );
    assert!(
        ramped_com < 0.7 * abrupt_com,
        "CoM {ramped_com} m/s² ramped, {abrupt_com} unramped"
    );
}
