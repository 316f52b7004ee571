//! Koenemann et al.'s joints on real clips slow down before their targets
//! (`KoenemannConfig::leg_stop_time`, `arm_stop_time`): no leg joint turns back at speed within
//! a frame, and the arms do not stop from their velocity limit within one. Counted here from the
//! output postures by first differences, not with the imitator's metrics.

use taskstack::human::HumanFrame;
use taskstack::imitation::config::ImitationMethod;
use taskstack::imitation::koenemann::KoenemannConfig;
use taskstack::imitation::reference::support::SupportConfig;
use taskstack::imitation::{Imitator, ImitatorConfig};
use taskstack::io::clip::Clip;
use taskstack::robots::nao;

/// An output frame's time (s) and joint positions (rad).
type Posture = (f64, Vec<f64>);

/// The NAO's postures and allowed velocities (rad/s) under
/// Koenemann's method on the bundled `clip` with `method`, and which variables are leg joints.
fn postures(clip: &str, method: KoenemannConfig) -> (Vec<Posture>, Vec<f64>, Vec<bool>) {
    let path = format!("{}/tests/data/mocap/{clip}", env!("CARGO_MANIFEST_DIR"));
    let mut clip = Clip::open(path).unwrap();
    let config = ImitatorConfig {
        support: SupportConfig::for_capture(clip.capture()),
        method: ImitationMethod::Koenemann(method),
        ..ImitatorConfig::default()
    };
    let profile = nao::profile();
    let legs = profile.sole_chain_variables(&profile.stand).unwrap();
    let mut imitator = Imitator::new(profile, config).unwrap();
    let allowed = imitator.bounds().velocity().to_vec();
    let mut frame = HumanFrame::new(0.0);
    let mut postures = Vec::new();
    while clip.read_frame(&mut frame).unwrap() {
        let out = imitator.step(&frame).unwrap();
        postures.push((out.time, out.q.clone()));
    }
    (postures, allowed, legs)
}

/// Joint `i`'s velocities (rad/s) over the two frame steps of `w`.
fn velocities(w: &[Posture], i: usize) -> [f64; 2] {
    [0, 1].map(|k| (w[k + 1].1[i] - w[k].1[i]) / (w[k + 1].0 - w[k].0))
}

/// Frames of `clip` in which a leg joint turns back at speed with `leg_stop_time`: it moved at
/// least half its allowed velocity one way over the previous frame and at least half of it
/// the other way over this one.
fn leg_reversals(clip: &str, leg_stop_time: Option<f64>) -> usize {
    let method = KoenemannConfig {
        leg_stop_time,
        ..KoenemannConfig::default()
    };
    let (postures, allowed, legs) = postures(clip, method);
    let reversed = |w: &[Posture]| {
        (0..legs.len()).filter(|&i| legs[i]).any(|i| {
            let [before, after] = velocities(w, i);
            let fast = 0.5 * allowed[i];
            (before >= fast && after <= -fast) || (before <= -fast && after >= fast)
        })
    };
    postures.windows(3).filter(|w| reversed(w)).count()
}

/// Frames of `clip` in which a joint other than the legs' stops from its velocity limit
/// with `arm_stop_time`: at least 90 % of its allowed velocity over the previous frame, at most
/// 10 % of it (or turned back) over this one.
fn arm_stops(clip: &str, arm_stop_time: Option<f64>) -> usize {
    let method = KoenemannConfig {
        arm_stop_time,
        ..KoenemannConfig::default()
    };
    let (postures, allowed, legs) = postures(clip, method);
    let stopped = |w: &[Posture]| {
        (0..legs.len()).filter(|&i| !legs[i]).any(|i| {
            let [before, after] = velocities(w, i);
            before.abs() >= 0.9 * allowed[i] && after * before.signum() <= 0.1 * allowed[i]
        })
    };
    postures.windows(3).filter(|w| stopped(w)).count()
}

#[test]
fn koenemanns_nao_legs_slow_down_before_their_targets_and_do_not_turn_back_at_speed() {
    // CMU 09_12 (walking forward, backward and sideways): with the legs stopping at once
    // (leg_stop_time 0, the NAO's behaviour before the stop time), a knee reached its target at
    // its velocity limit and reversed within a frame when the target crossed it (2 frames).
    let clip = "cmu_09_12_walk_forward_backward_sideways.bvh";
    let abrupt = leg_reversals(clip, Some(0.0));
    let slowed = leg_reversals(clip, None);
    assert!(
        abrupt > 0,
        "the abrupt legs never reversed: the test sees nothing"
    );
    assert_eq!(
        slowed, 0,
        "{slowed} reversals with the default stop time ({abrupt} abrupt)"
    );
}

#[test]
fn koenemanns_nao_arms_slow_down_before_their_targets() {
    // CMU 05_12 (a slow dance with the arms high): stopping at once (arm_stop_time 0, the
    // behaviour before the stop time), the arms ran into their targets at their velocity limit
    // and stopped within a frame (23 frames at the NAO's balanced hand speeds, 1 m/s and
    // 5 m/s²; 34 at the slower caps before them); with the default stop time (0.10 s from the
    // limit to rest, a frame is 1/120 s) 3 remain (1 before), three successive frames at
    // 10.98 s in which the left shoulder and elbow roll turn back at speed: the stop time
    // bounds the approach to a target, and a target that jumps back toward the joint, or a
    // position limit, still stops it at once.
    let clip = "cmu_05_12_slow_dance_tendu_arms_high.bvh";
    let abrupt = arm_stops(clip, Some(0.0));
    let slowed = arm_stops(clip, None);
    assert!(
        abrupt > 0,
        "the abrupt arms never stopped at speed: the test sees nothing"
    );
    assert!(
        5 * slowed <= abrupt,
        "{slowed} stops at speed with the default, {abrupt} abrupt"
    );
}
