//! The imitation's metrics against counts made by hand: a joint that turns back at speed within
//! a frame is counted once, a slower wobble not at all.

use taskstack::human::HumanFrame;
use taskstack::imitation::metrics::{ImitationMetrics, MetricsRecorder};
use taskstack::imitation::output::RobotFrame;
use taskstack::imitation::reference::support::SupportConfig;
use taskstack::imitation::{Imitator, ImitatorConfig};
use taskstack::io::clip::Clip;
use taskstack::robots::nao;

/// The NAO's frames on the first two seconds of CMU 02_10 (standing, arm gestures), and its
/// imitator (for its joint bounds).
fn frames() -> (Imitator, Vec<RobotFrame>) {
    let path = format!(
        "{}/tests/data/mocap/cmu_02_10_wash_self_standing_arm_gestures.bvh",
        env!("CARGO_MANIFEST_DIR")
    );
    let mut clip = Clip::open(path).unwrap();
    let config = ImitatorConfig {
        support: SupportConfig::for_capture(clip.capture()),
        ..ImitatorConfig::default()
    };
    let mut imitator = Imitator::new(nao::profile(), config).unwrap();
    let mut frame = HumanFrame::new(0.0);
    let mut out = Vec::new();
    while out.len() < 240 && clip.read_frame(&mut frame).unwrap() {
        out.push(imitator.step(&frame).unwrap().clone());
    }
    (imitator, out)
}

fn metrics(imitator: &Imitator, frames: &[RobotFrame]) -> ImitationMetrics {
    let mut recorder = MetricsRecorder::new(imitator);
    for f in frames {
        recorder.record(f);
    }
    recorder.finish()
}

/// Moves joint `joint` of frame `k` by `fraction` of its allowed step out and back: the frame
/// before steps out, the one after steps back.
fn bump(imitator: &Imitator, frames: &mut [RobotFrame], joint: usize, k: usize, fraction: f64) {
    let dt = frames[k].time - frames[k - 1].time;
    frames[k].q[joint] += fraction * imitator.bounds().velocity()[joint] * dt;
}

/// The quietest joint and stretch of the run: where every step of that joint over four frames
/// is under a tenth of its allowed step, so a bump of 0.8 neither hides in nor adds to the
/// run's own motion and stays within the velocity bound.
fn quiet(imitator: &Imitator, frames: &[RobotFrame]) -> (usize, usize) {
    let n = frames[0].q.len();
    let calm = |j: usize, k: usize| {
        (k - 2..=k + 1).all(|i| {
            let dt = frames[i + 1].time - frames[i].time;
            let step = (frames[i + 1].q[j] - frames[i].q[j]).abs();
            step < 0.1 * imitator.bounds().velocity()[j] * dt
        })
    };
    (0..n)
        .flat_map(|j| (10..frames.len() - 10).map(move |k| (j, k)))
        .find(|&(j, k)| calm(j, k))
        .expect("a quiet joint somewhere in two seconds")
}

#[test]
fn a_joint_turning_back_at_speed_is_counted_once() {
    let (imitator, frames) = frames();
    let base = metrics(&imitator, &frames);
    let (joint, k) = quiet(&imitator, &frames);
    let mut fast = frames.clone();
    bump(&imitator, &mut fast, joint, k, 0.8);
    let m = metrics(&imitator, &fast);
    assert_eq!(m.joint_reversal_frames, base.joint_reversal_frames + 1);
    assert_eq!(m.velocity_limit_violations, base.velocity_limit_violations);
    // At 0.4 of the allowed step each way it is a wobble, not a reversal at speed.
    let mut slow = frames.clone();
    bump(&imitator, &mut slow, joint, k, 0.4);
    assert_eq!(
        metrics(&imitator, &slow).joint_reversal_frames,
        base.joint_reversal_frames
    );
}
