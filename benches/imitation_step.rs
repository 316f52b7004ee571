//! `Imitator::step` on real clips, for the NAO and the Unitree G1 and both methods (Poubel's
//! task tables, Koenemann et al.'s): frames of double support (CMU 02_10, standing gestures)
//! and of a walk with right and left single supports (CMU 07_04), streamed from memory in a
//! loop.

use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;
use taskstack::human::HumanFrame;
use taskstack::imitation::config::ImitationMethod;
use taskstack::imitation::imitator::{Imitator, ImitatorConfig};
use taskstack::imitation::koenemann::KoenemannConfig;
use taskstack::imitation::phase::SupportPhase;
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
        ("poubel", ImitationMethod::Poubel),
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
        ("walk_07_04", "cmu_07_04_slow_walk.bvh"),
    ]
    .into_iter()
    .flat_map(|clip| robots.map(|robot| (clip, robot)))
    .flat_map(|case| methods.map(|method| (case, method)))
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
        bench_laps(c, &name, &mut imitator, &frames);
    }
}

/// Benches `imitator.step` on `frames` replayed in laps with increasing times, so the imitator
/// sees a continuous stream.
fn bench_laps(c: &mut Criterion, name: &str, imitator: &mut Imitator, frames: &[HumanFrame]) {
    let duration = frames.last().unwrap().time - frames[0].time + 1.0 / 120.0;
    let (mut i, mut lap) = (0, 1.0);
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
    let mut config = ImitatorConfig::default();
    config.footsteps.follow = true;
    config.footsteps.dynamic = true;
    let mut imitator = Imitator::new(nao::profile(), config).unwrap();
    let walking = frames
        .iter()
        .filter(|f| imitator.step(f).unwrap().walk.is_some())
        .count();
    eprintln!(
        "nao poubel dynamic walk 07_04: {} frames, {walking} walking on the first pass",
        frames.len()
    );
    bench_laps(
        c,
        "imitator_step/nao/poubel/dynamic_walk_07_04",
        &mut imitator,
        &frames,
    );
}

criterion_group!(benches, bench, dynamic_walk);
criterion_main!(benches);
