//! Support detection on the real clips (expected phases from `tests/data/mocap/README.md`) and on
//! hand-made foot trajectories.

use nalgebra::Vector3;
use proptest::prelude::*;
use taskstack::human::Side;
use taskstack::human::{HumanFrame, HumanJoint as J};
use taskstack::imitation::reference::support::{
    HumanSupport, SupportConfig, SupportDetector, SupportError,
};
use taskstack::io::bvh::{BvhConfig, BvhReader};
use taskstack::io::kinect::{KinectConfig, KinectReader};

const DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/mocap/");

/// A run of frames with one support phase: (phase, first frame time, last frame time).
#[derive(Debug, Clone, Copy)]
struct Phase {
    support: HumanSupport,
    start: f64,
    end: f64,
}

impl Phase {
    fn duration(&self) -> f64 {
        self.end - self.start
    }
}

fn phases(frames: &[HumanFrame], config: SupportConfig) -> Vec<Phase> {
    let mut detector = SupportDetector::new(config).unwrap();
    let mut out: Vec<Phase> = Vec::new();
    for f in frames {
        let support = detector.update(f);
        match out.last_mut() {
            Some(p) if p.support == support => p.end = f.time,
            _ => out.push(Phase {
                support,
                start: f.time,
                end: f.time,
            }),
        }
    }
    out
}

/// Frames of a BVH clip; CMU-MB clips start with a synthetic T-pose frame, skipped (README).
fn bvh(name: &str, skip_t_pose: bool) -> Vec<HumanFrame> {
    BvhReader::open(format!("{DATA}{name}"), BvhConfig::cmu())
        .unwrap()
        .skip(usize::from(skip_t_pose))
        .map(Result::unwrap)
        .collect()
}

fn kinect(name: &str) -> Vec<HumanFrame> {
    KinectReader::open(format!("{DATA}{name}"), KinectConfig::default())
        .unwrap()
        .map(Result::unwrap)
        .collect()
}

fn count(phases: &[Phase], support: HumanSupport) -> usize {
    phases.iter().filter(|p| p.support == support).count()
}

/// README: "7.0–8.8 s: single support on the RIGHT leg, left foot lifted ~0.15–0.2 m … ~9 s:
/// both feet down". The detector must find one right-support phase covering 7.1–8.7 s, starting
/// within 0.3 s of 7.0 and ending within 0.5 s of 8.8 (the foot comes down 8.8–9.2 s), ≥ 1.6 s.
#[test]
fn cmu_05_02_has_the_right_leg_stance() {
    let found = phases(
        &bvh("cmu_05_02_stand_arm_gestures_turn_single_leg.bvh", true),
        SupportConfig::optical(),
    );
    let stance = found
        .iter()
        .find(|p| p.support == HumanSupport::Right && p.start < 7.1 && p.end > 8.7)
        .unwrap_or_else(|| panic!("no right stance over 7.1–8.7 s in {found:?}"));
    assert!((stance.start - 7.0).abs() < 0.3, "{stance:?}");
    assert!((stance.end - 8.8).abs() < 0.5, "{stance:?}");
    assert!(stance.duration() > 1.6, "{stance:?}");
    // 0–3 s standing still (left foot on its toes): double support.
    assert!(
        found[0].support == HumanSupport::Double && found[0].end > 3.0,
        "{found:?}"
    );
}

/// README: "Double support the whole time, feet planted".
#[test]
fn cmu_02_10_is_double_support_throughout() {
    let found = phases(
        &bvh("cmu_02_10_wash_self_standing_arm_gestures.bvh", true),
        SupportConfig::optical(),
    );
    assert_eq!(found.len(), 1, "{found:?}");
    assert_eq!(found[0].support, HumanSupport::Double);
}

/// Walking alternates single supports with short double supports. Checks: several Right and
/// Left phases; single-support phases of a walk last 0.2–1 s; nearly no airborne time (walking
/// has no flight phase; a frame or two at a fast stylised step is tolerated).
fn assert_walk(found: &[Phase], min_each: usize) {
    assert!(count(found, HumanSupport::Right) >= min_each, "{found:?}");
    assert!(count(found, HumanSupport::Left) >= min_each, "{found:?}");
    let airborne: f64 = found
        .iter()
        .filter(|p| p.support == HumanSupport::Airborne)
        .map(|p| p.duration() + 1.0 / 120.0)
        .sum();
    assert!(airborne < 0.05, "airborne {airborne} s: {found:?}");
}

/// Sequence of single supports, ignoring double-support and airborne phases.
fn singles(found: &[Phase]) -> Vec<Phase> {
    found
        .iter()
        .copied()
        .filter(|p| matches!(p.support, HumanSupport::Right | HumanSupport::Left))
        .collect()
}

/// README: straight slow walk, ~6 steps over 3.74 s.
#[test]
fn cmu_07_04_walk_alternates_strictly() {
    let found = phases(
        &bvh("cmu_07_04_slow_walk.bvh", true),
        SupportConfig::optical(),
    );
    assert_walk(&found, 3);
    let steps = singles(&found);
    assert!(
        steps.windows(2).all(|w| w[0].support != w[1].support),
        "{found:?}"
    );
    // Inner single supports (not cut by the clip's ends) last 0.4–0.9 s at ~0.9 m/s.
    for p in &steps[1..steps.len() - 1] {
        assert!((0.4..0.9).contains(&p.duration()), "{p:?}");
    }
}

/// README: 16 s of continuous walking, forward, U-turn, backward, sideways.
#[test]
fn cmu_09_12_walk_alternates() {
    let found = phases(
        &bvh("cmu_09_12_walk_forward_backward_sideways.bvh", true),
        SupportConfig::optical(),
    );
    assert_walk(&found, 10);
    let steps = singles(&found);
    let alternating = steps
        .windows(2)
        .filter(|w| w[0].support != w[1].support)
        .count();
    assert!(
        alternating as f64 >= 0.9 * (steps.len() - 1) as f64,
        "{alternating} of {} alternate",
        steps.len() - 1
    );
}

/// README: 0–1 s standing, stylised start, ~4–6.5 s walking, ~7–8.3 s standing (CMU-MAX, no
/// T-pose frame).
#[test]
fn cmu_131_01_starts_walks_and_stops() {
    let found = phases(
        &bvh("cmu_131_01_start_walk_stop_maxskel.bvh", false),
        SupportConfig::optical(),
    );
    assert_walk(&found, 2);
    assert!(
        found[0].support == HumanSupport::Double && found[0].end > 0.5,
        "{found:?}"
    );
    let last = found.last().unwrap();
    assert!(
        last.support == HumanSupport::Double && last.start < 7.0,
        "{found:?}"
    );
    let walking: Vec<Phase> = singles(&found)
        .into_iter()
        .filter(|p| p.start > 4.0 && p.end < 6.8)
        .collect();
    assert!(walking.len() >= 4, "{found:?}");
    assert!(
        walking.windows(2).all(|w| w[0].support != w[1].support),
        "{found:?}"
    );
}

/// README: both Kinect subjects stand in double support throughout.
#[test]
fn kinect_clips_stand_in_double_support() {
    for name in [
        "kinect2_labanotation_ges01_wavehand.csv",
        "kinect2_labanotation_ges02_balancinghands.csv",
    ] {
        let found = phases(&kinect(name), SupportConfig::kinect());
        assert_eq!(found.len(), 1, "{name}: {found:?}");
        assert_eq!(found[0].support, HumanSupport::Double);
    }
}

/// A frame with both feet given by ankle positions (toes 10 cm ahead, 3 cm lower, like a flat
/// foot) at time `t`.
fn feet_frame(t: f64, left: Vector3<f64>, right: Vector3<f64>) -> HumanFrame {
    let mut f = HumanFrame::new(t);
    let toe = Vector3::new(0.1, 0.0, -0.03);
    f.set(J::LAnkle, Some(left));
    f.set(J::LToe, Some(left + toe));
    f.set(J::RAnkle, Some(right));
    f.set(J::RToe, Some(right + toe));
    f
}

/// The left foot hovers between the on (5 cm) and off (8 cm) heights: it keeps whatever state it
/// had. One-frame spikes above the off height (shorter than the 30 ms dwell) do not flip it.
#[test]
fn hysteresis_and_dwell_hold_the_state() {
    let dt = 1.0 / 120.0;
    let right = Vector3::new(0.0, -0.1, 0.05);
    let mut detector = SupportDetector::new(SupportConfig::optical()).unwrap();
    // Ground = sole point (toe) at 0.02 m. Both feet down for 0.5 s.
    for k in 0..60 {
        let f = feet_frame(k as f64 * dt, Vector3::new(0.0, 0.1, 0.05), right);
        assert_eq!(detector.update(&f), HumanSupport::Double);
    }
    // Left sole point 0.065 m above the ground (between 0.05 and 0.08), with a single frame at
    // +0.10 m every 10 frames: stays in support.
    for k in 60..240 {
        let lift = if k % 10 == 0 { 0.10 } else { 0.065 };
        let f = feet_frame(k as f64 * dt, Vector3::new(0.0, 0.1, 0.05 + lift), right);
        assert_eq!(detector.update(&f), HumanSupport::Double, "frame {k}");
    }
    // Lifted to 0.15 m: right support after the dwell (within 5 frames).
    let mut switched_at = None;
    for k in 240..300 {
        let f = feet_frame(k as f64 * dt, Vector3::new(0.0, 0.1, 0.20), right);
        if detector.update(&f) == HumanSupport::Right && switched_at.is_none() {
            switched_at = Some(k);
        }
    }
    let k = switched_at.expect("left foot lifted");
    assert!((243..=245).contains(&k), "switched at frame {k}");
    // Back down to 0.065 m above ground (between the thresholds): stays lifted.
    for k in 300..400 {
        let f = feet_frame(k as f64 * dt, Vector3::new(0.0, 0.1, 0.05 + 0.065), right);
        assert_eq!(detector.update(&f), HumanSupport::Right, "frame {k}");
    }
    assert!(detector.foot(Side::Right).in_support);
    assert!((detector.foot(Side::Left).height.unwrap() - 0.065).abs() < 1e-9);
}

/// Walking up a ramp rising 10 cm per 4 m (z = 0.025·x), steps 0.5 m long: every landing is
/// detected although the last footholds are 8–10 cm above the start, above a fixed 5 cm
/// threshold over the starting floor.
#[test]
fn local_ground_follows_a_rising_floor() {
    let dt = 1.0 / 120.0;
    let ramp = |x: f64| 0.025 * x;
    // Ankle 5 cm above the floor when flat (toe 2 cm above).
    let planted = |x: f64, y: f64| Vector3::new(x, y, ramp(x) + 0.05);
    let mut detector = SupportDetector::new(SupportConfig::optical()).unwrap();
    let mut t = 0.0;
    let (mut left_x, mut right_x) = (0.0, 0.0);
    let mut phases_seen = Vec::new();
    let mut push = |s: HumanSupport| {
        if phases_seen.last() != Some(&s) {
            phases_seen.push(s);
        }
    };
    for step in 0..8 {
        // Double support for 0.1 s.
        for _ in 0..12 {
            push(detector.update(&feet_frame(t, planted(left_x, 0.1), planted(right_x, -0.1))));
            t += dt;
        }
        // Swing the rear foot 1.0 m forward in 0.5 s, 15 cm up at mid-swing.
        let left_swings = step % 2 == 0;
        let from = if left_swings { left_x } else { right_x };
        for k in 1..=60 {
            let s = k as f64 / 60.0;
            let x = from + 1.0 * s;
            let swing =
                planted(x, 0.0) + Vector3::new(0.0, 0.0, 0.15 * (std::f64::consts::PI * s).sin());
            let (l, r) = if left_swings {
                (Vector3::new(swing.x, 0.1, swing.z), planted(right_x, -0.1))
            } else {
                (planted(left_x, 0.1), Vector3::new(swing.x, -0.1, swing.z))
            };
            push(detector.update(&feet_frame(t, l, r)));
            t += dt;
        }
        if left_swings {
            left_x += 1.0;
        } else {
            right_x += 1.0;
        }
    }
    // The last footholds are at x = 4 m: 10 cm above the start.
    assert!(ramp(left_x.max(right_x)) >= 0.1);
    let expected: Vec<HumanSupport> = (0..8)
        .flat_map(|step| {
            [
                HumanSupport::Double,
                if step % 2 == 0 {
                    HumanSupport::Right
                } else {
                    HumanSupport::Left
                },
            ]
        })
        .collect();
    assert_eq!(phases_seen, expected);
    // The learnt ground at the last foothold is the toe's resting height there.
    let ground = detector.ground_height(4.1, 0.1).unwrap();
    assert!((ground - (ramp(4.1) + 0.02)).abs() < 0.01, "{ground}");
}

#[test]
fn missing_feet_and_bad_times_keep_the_state() {
    let mut detector = SupportDetector::new(SupportConfig::kinect()).unwrap();
    let f = feet_frame(
        0.0,
        Vector3::new(0.0, 0.1, 0.05),
        Vector3::new(0.0, -0.1, 0.05),
    );
    assert_eq!(detector.update(&f), HumanSupport::Double);
    assert_eq!(detector.update(&HumanFrame::new(1.0)), HumanSupport::Double);
    assert_eq!(detector.foot(Side::Left).height, None);
    let mut nan_time = f;
    nan_time.time = f64::NAN;
    assert_eq!(detector.update(&nan_time), HumanSupport::Double);
}

#[test]
fn invalid_configs_are_refused() {
    let swapped = SupportConfig {
        height_on: 0.1,
        height_off: 0.05,
        ..SupportConfig::optical()
    };
    assert_eq!(
        SupportDetector::new(swapped).unwrap_err(),
        SupportError::Config("height_on", "must be finite and ≤ height_off")
    );
    let nan = SupportConfig {
        speed_window: f64::NAN,
        ..SupportConfig::kinect()
    };
    assert!(SupportDetector::new(nan).is_err());
}

fn maybe_point() -> impl Strategy<Value = Option<Vector3<f64>>> {
    let coordinate = prop_oneof![
        -1e6f64..1e6,
        -1.0f64..1.0,
        Just(0.0),
        Just(1e300),
        Just(f64::NAN)
    ];
    prop::option::of(
        (coordinate.clone(), coordinate.clone(), coordinate)
            .prop_map(|(x, y, z)| Vector3::new(x, y, z)),
    )
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// Random feet (missing, coincident, huge, NaN — which `set` turns into missing) and times
    /// never panic, and every reported height, speed and ground estimate is finite.
    #[test]
    fn random_frames_never_panic(frames in prop::collection::vec(
        (prop_oneof![0.0f64..10.0, Just(f64::NAN), Just(0.0)], maybe_point(), maybe_point(), maybe_point(), maybe_point()),
        1..40,
    )) {
        for config in [SupportConfig::optical(), SupportConfig::kinect()] {
            let mut detector = SupportDetector::new(config).unwrap();
            for (t, la, lt, ra, rt) in &frames {
                let mut f = HumanFrame::new(*t);
                f.set(J::LAnkle, *la);
                f.set(J::LToe, *lt);
                f.set(J::RAnkle, *ra);
                f.set(J::RToe, *rt);
                detector.update(&f);
                for side in [Side::Left, Side::Right] {
                    let s = detector.foot(side);
                    prop_assert!(s.height.is_none_or(f64::is_finite));
                    prop_assert!(s.speed.is_none_or(f64::is_finite));
                }
                if let Some(g) = detector.ground_height(0.0, 0.0) {
                    prop_assert!(g.is_finite());
                }
            }
        }
    }
}
