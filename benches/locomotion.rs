//! Walking: one tick of the pattern generator (preview window of 1.6 s at 10 ms: 160 gains per
//! axis, the ZMP reference sampled from the step queue) and one tick of the whole-body walker
//! (generator + IK of the NAO or the G1 to 1e-7), both in the middle of a long straight walk.
//! Each iteration restarts the walk when it ends, so every phase is measured.

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use taskstack::BipedProfile;
use taskstack::locomotion::{
    GroundPose, PatternGenerator, WalkParams, WholeBodyWalker, goal_feet, plan_steps,
};
use taskstack::robots::{g1, nao};

fn walker(profile: &BipedProfile) -> WholeBodyWalker<'_> {
    let params = WalkParams::for_profile(profile).unwrap();
    let timing = params.timing;
    let mut walker = WholeBodyWalker::new(profile, params, GroundPose::new(0.0, 0.0, 0.0)).unwrap();
    let start = *walker.generator().standing_feet();
    let goal = goal_feet(&start, &GroundPose::new(2.0, 0.0, 0.0));
    for step in plan_steps(&start, &goal, &profile.step_envelope, timing, 60) {
        walker.push(step).unwrap();
    }
    walker
}

fn generator(profile: &BipedProfile) -> PatternGenerator {
    walker(profile).generator().clone()
}

fn locomotion(c: &mut Criterion) {
    let nao = nao::profile();
    let g1 = g1::profile();
    let mut generator_nao = generator(&nao);
    c.bench_function("walk_generator_tick_nao", |b| {
        b.iter(|| {
            if generator_nao.is_stopped() {
                generator_nao = generator(&nao);
            }
            black_box(generator_nao.tick());
        })
    });
    for (name, profile) in [("nao", &nao), ("g1", &g1)] {
        let mut w = walker(profile);
        c.bench_function(&format!("walker_tick_{name}"), |b| {
            b.iter(|| {
                if w.generator().is_stopped() {
                    w = walker(profile);
                }
                black_box(w.tick().unwrap());
            })
        });
    }
}

criterion_group!(benches, locomotion);
criterion_main!(benches);
