//! Koenemann et al.'s legs on a real clip (`KoenemannConfig::leg_stop_time`): each leg joint
//! slows down before its IK target, so none turns back at speed within a frame. Counted here
//! from the output postures by first differences, not with the imitator's metrics.

use taskstack::human::HumanFrame;
use taskstack::imitation::config::ImitationMethod;
use taskstack::imitation::imitator::{Imitator, ImitatorConfig};
use taskstack::imitation::koenemann::KoenemannConfig;
use taskstack::imitation::support::SupportConfig;
use taskstack::io::clip::Clip;
use taskstack::robots::nao;

/// Frames of CMU `clip` in which a NAO leg joint turns back at speed under Koenemann's method
/// with `leg_stop_time`: it moved at least half its allowed velocity one way over the previous
/// frame and at least half of it the other way over this one.
fn leg_reversals(clip: &str, leg_stop_time: Option<f64>) -> usize {
    let path = format!("{}/tests/data/mocap/{clip}", env!("CARGO_MANIFEST_DIR"));
    let mut clip = Clip::open(path).unwrap();
    let config = ImitatorConfig {
        support: SupportConfig::for_capture(clip.capture()),
        method: ImitationMethod::Koenemann(KoenemannConfig {
            leg_stop_time,
            ..KoenemannConfig::default()
        }),
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
    let reversed = |w: &[(f64, Vec<f64>)]| {
        (0..legs.len()).filter(|&i| legs[i]).any(|i| {
            let before = (w[1].1[i] - w[0].1[i]) / (w[1].0 - w[0].0);
            let after = (w[2].1[i] - w[1].1[i]) / (w[2].0 - w[1].0);
            let fast = 0.5 * allowed[i];
            (before >= fast && after <= -fast) || (before <= -fast && after >= fast)
        })
    };
    postures.windows(3).filter(|w| reversed(w)).count()
}

#[test]
fn koenemanns_nao_legs_slow_down_before_their_targets_and_do_not_turn_back_at_speed() {
    // CMU 09_12 (walking forward, backward and sideways): with the legs stopping at once
    // (leg_stop_time 0, the NAO's behaviour before the stop time), a knee reached its target at
    // its velocity limit and reversed within a frame when the target crossed it (2 frames on this clip).
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
