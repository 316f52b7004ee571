//! Reading + support detection + scaling (+ human joint angles) per frame, on CMU 09_12
//! (31 joints, 1919 frames) read from memory. Throughput is in frames: criterion's "elem/s"
//! inverted is the time per frame.

use std::hint::black_box;
use std::io::Cursor;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use taskstack::human::HumanFrame;
use taskstack::imitation::reference::scaler::{RobotSkeleton, ScaleConfig, Scaler};
use taskstack::imitation::reference::support::{SupportConfig, SupportDetector};
use taskstack::io::bvh::{BvhConfig, BvhReader};
use taskstack::robots::{HumanJointAngles, nao};

const CLIP: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/tests/data/mocap/cmu_09_12_walk_forward_backward_sideways.bvh"
);

fn pipeline(bytes: &[u8], angles: Option<&mut nao::JointAngles>) -> u64 {
    let mut reader = BvhReader::new(Cursor::new(bytes), "bench", BvhConfig::cmu()).unwrap();
    let mut detector = SupportDetector::new(SupportConfig::optical()).unwrap();
    let mut scaler = Scaler::new(
        RobotSkeleton::of(&nao::profile()).unwrap(),
        ScaleConfig::new(nao::STEP_ENVELOPE),
    )
    .unwrap();
    let mut q = [0.0; nao::VARIABLES.len()];
    let mut angles = angles;
    let mut frame = HumanFrame::new(0.0);
    let mut n = 0;
    while reader.read_frame(&mut frame).unwrap() {
        let support = detector.update(&frame);
        let scaled = scaler.scale(&frame, support).unwrap();
        if let Some(a) = angles.as_deref_mut() {
            a.compute(scaled.directions(), &mut q).unwrap();
        }
        black_box(scaled);
        n += 1;
    }
    black_box(q);
    n
}

fn imitation_input(c: &mut Criterion) {
    let bvh = std::fs::read(CLIP).unwrap();
    let frames: Vec<HumanFrame> = BvhReader::new(Cursor::new(&bvh), "bench", BvhConfig::cmu())
        .unwrap()
        .map(Result::unwrap)
        .collect();
    let mut detector = SupportDetector::new(SupportConfig::optical()).unwrap();
    let supports: Vec<_> = frames.iter().map(|f| detector.update(f)).collect();
    let model = nao::rfoot();
    let mut angles = nao::JointAngles::new(&model).unwrap();

    let mut group = c.benchmark_group("imitation_input");
    group.throughput(Throughput::Elements(frames.len() as u64));
    group.bench_function("bvh_read_support_scale", |b| {
        b.iter(|| pipeline(black_box(&bvh), None))
    });
    group.bench_function("bvh_read_support_scale_angles", |b| {
        b.iter(|| pipeline(black_box(&bvh), Some(&mut angles)))
    });
    group.bench_function("scale_only", |b| {
        let mut scaler = Scaler::new(
            RobotSkeleton::of(&nao::profile()).unwrap(),
            ScaleConfig::new(nao::STEP_ENVELOPE),
        )
        .unwrap();
        b.iter(|| {
            for (f, s) in frames.iter().zip(&supports) {
                black_box(scaler.scale(black_box(f), *s).unwrap());
            }
        })
    });
    group.finish();
}

criterion_group!(benches, imitation_input);
criterion_main!(benches);
