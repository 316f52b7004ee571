//! `Imitator::step` on real clips, for the NAO and the Unitree G1 and both methods (Poubel's
//! task tables, Koenemann et al.'s): frames of double support (CMU 02_10, standing gestures),
//! of a stand on one leg (CMU 05_02) and of a walk with right and left single supports (CMU
//! 07_04), streamed from memory in a loop.
//!
//! Criterion's figure is the mean step over the laps; the tail is printed before each case:
//! the median, 99th percentile and largest step time of one timed pass over the clip after a
//! warm-up pass (`… tail: median … p99 … max … µs`), the frames a controller running at a fixed
//! rate has to fit.

use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;
use std::time::Instant;
use taskstack::human::HumanFrame;
use taskstack::imitation::config::ImitationMethod;
use taskstack::imitation::koenemann::KoenemannConfig;
use taskstack::imitation::phase::SupportPhase;
use taskstack::imitation::poubel::PoubelConfig;
use taskstack::imitation::{Imitator, ImitatorConfig};
use taskstack::io::clip::Clip;
use taskstack::robots::{BipedProfile, g1, nao};

fn frames(name: &str) -> Vec<HumanFrame> {
    let path = format!("{}/tests/data/mocap/{name}", env!("CARGO_MANIFEST_DIR"));
    Clip::open(path).unwrap().collect::<Result<_, _>>().unwrap()
}

/// A robot by name, and how to build its profile.
type Robot = (&'static str, fn() -> BipedProfile);

fn bench(c: &mut Criterion) {
    let robots: [Robot; 2] = [("nao", nao::profile), ("g1", g1::profile)];
    let methods = [
        ("poubel", ImitationMethod::default()),
        (
            "koenemann",
            ImitationMethod::Koenemann(KoenemannConfig::default()),
        ),
    ];
    for (((label, clip), (robot, profile)), (method_name, method)) in [
        (
            "double_support_02_10",
            "cmu_02_10_wash_self_standing_arm_gestures.bvh",
        ),
        (
            "single_support_05_02",
            "cmu_05_02_stand_arm_gestures_turn_single_leg.bvh",
        ),
        ("walk_07_04", "cmu_07_04_slow_walk.bvh"),
    ]
    .into_iter()
    .flat_map(|clip| robots.map(|robot| (clip, robot)))
    .flat_map(|case| methods.clone().map(|method| (case, method)))
    {
        let frames = frames(clip);
        let config = ImitatorConfig {
            method,
            ..ImitatorConfig::default()
        };
        let mut imitator = Imitator::new(profile(), config).unwrap();
        // Warm up on the whole clip once, and count the phases the bench will see.
        let mut single = 0;
        for f in &frames {
            let p = imitator.step(f).unwrap().phase;
            single += usize::from(matches!(p, SupportPhase::Right | SupportPhase::Left));
        }
        eprintln!(
            "{robot} {method_name} {label}: {} frames, {single} in single support on the first pass",
            frames.len()
        );
        let name = format!("imitator_step/{robot}/{method_name}/{label}");
        print_tail(&name, &mut imitator, &frames);
        bench_laps(c, &name, &mut imitator, &frames);
    }
}

/// How far one lap of `frames` shifts the next lap's times (s): the clip plus one frame.
fn lap_duration(frames: &[HumanFrame]) -> f64 {
    frames.last().unwrap().time - frames[0].time + 1.0 / 120.0
}

/// Times every step of one more pass over `frames` (after the imitator's warm-up on them) and
/// prints the median, 99th percentile and largest (µs).
fn print_tail(name: &str, imitator: &mut Imitator, frames: &[HumanFrame]) {
    let duration = lap_duration(frames);
    let mut times: Vec<f64> = frames
        .iter()
        .map(|f| {
            let mut frame = *f;
            frame.time += duration;
            let start = Instant::now();
            black_box(imitator.step(&frame).unwrap().q[0]);
            start.elapsed().as_secs_f64() * 1e6
        })
        .collect();
    times.sort_by(f64::total_cmp);
    let at = |p: f64| times[((times.len() - 1) as f64 * p).round() as usize];
    eprintln!(
        "{name} tail: median {:.1} p99 {:.1} max {:.1} µs",
        at(0.5),
        at(0.99),
        at(1.0)
    );
}

/// Benches `imitator.step` on `frames` replayed in laps with increasing times, so the imitator
/// sees a continuous stream (after the warm-up pass and [`print_tail`]'s).
fn bench_laps(c: &mut Criterion, name: &str, imitator: &mut Imitator, frames: &[HumanFrame]) {
    let duration = lap_duration(frames);
    let (mut i, mut lap) = (0, 2.0);
    c.bench_function(name, |b| {
        b.iter(|| {
            let mut frame = frames[i];
            frame.time += lap * duration;
            i += 1;
            if i == frames.len() {
                i = 0;
                lap += 1.0;
            }
            black_box(imitator.step(&frame).unwrap().q[0])
        })
    });
}

/// A dynamic walk (`FootstepConfig::dynamic`, the pattern generator in the imitation) on CMU
/// 07_04, NAO: the clip replayed in laps, so the robot keeps walking after the human's steps.
fn dynamic_walk(c: &mut Criterion) {
    let frames = frames("cmu_07_04_slow_walk.bvh");
    let mut poubel = PoubelConfig::default();
    poubel.footsteps.follow = true;
    poubel.footsteps.dynamic = true;
    let config = ImitatorConfig {
        method: ImitationMethod::Poubel(poubel),
        ..ImitatorConfig::default()
    };
    let mut imitator = Imitator::new(nao::profile(), config).unwrap();
    let walking = frames
        .iter()
        .filter(|f| imitator.step(f).unwrap().walk.is_some())
        .count();
    eprintln!(
        "nao poubel dynamic walk 07_04: {} frames, {walking} walking on the first pass",
        frames.len()
    );
    let name = "imitator_step/nao/poubel/dynamic_walk_07_04";
    print_tail(name, &mut imitator, &frames);
    bench_laps(c, name, &mut imitator, &frames);
}

/// Poubel's method on the NAO with the ZMP balance (`PoubelConfig::zmp_balance`) and hands
/// at 1 m/s, on the stand on one leg (CMU 05_02): the cost of the "dynamics" level.
fn zmp_balance(c: &mut Criterion) {
    let frames = frames("cmu_05_02_stand_arm_gestures_turn_single_leg.bvh");
    let config = ImitatorConfig {
        method: ImitationMethod::Poubel(PoubelConfig {
            zmp_balance: Some(true),
            ..PoubelConfig::default()
        }),
        max_tracking_speed: Some(1.0),
        max_tracking_acceleration: Some(10.0),
        ..ImitatorConfig::default()
    };
    let mut imitator = Imitator::new(nao::profile(), config).unwrap();
    for f in &frames {
        imitator.step(f).unwrap();
    }
    let name = "imitator_step/nao/poubel/zmp_balance_05_02";
    print_tail(name, &mut imitator, &frames);
    bench_laps(c, name, &mut imitator, &frames);
}

criterion_group!(benches, bench, dynamic_walk, zmp_balance);
criterion_main!(benches);
