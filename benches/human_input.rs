//! Reading human motion and detecting its support, per frame: BVH (CMU 09_12, 31 joints,
//! 1919 frames) and Kinect v2 CSV (161 frames). Throughput is in frames, so criterion's
//! "elem/s" inverted gives the time per frame. Files are read from memory to time parsing and
//! forward kinematics, not the disk.

use std::hint::black_box;
use std::io::Cursor;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use taskstack::human::HumanFrame;
use taskstack::imitation::reference::support::{SupportConfig, SupportDetector};
use taskstack::io::bvh::{BvhConfig, BvhReader};
use taskstack::io::kinect::{KinectConfig, KinectReader};

const DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/mocap/");

fn bvh_frames(bytes: &[u8], detector: Option<&mut SupportDetector>) -> u64 {
    let mut reader = BvhReader::new(Cursor::new(bytes), "bench", BvhConfig::cmu()).unwrap();
    let mut frame = HumanFrame::new(0.0);
    let mut detector = detector;
    let mut n = 0;
    while reader.read_frame(&mut frame).unwrap() {
        if let Some(d) = detector.as_deref_mut() {
            black_box(d.update(&frame));
        }
        n += 1;
    }
    black_box(&frame);
    n
}

fn kinect_frames(bytes: &[u8], detector: &mut SupportDetector) -> u64 {
    let mut reader = KinectReader::new(Cursor::new(bytes), "bench", KinectConfig::default());
    let mut frame = HumanFrame::new(0.0);
    let mut n = 0;
    while reader.read_frame(&mut frame).unwrap() {
        black_box(detector.update(&frame));
        n += 1;
    }
    n
}

fn human_input(c: &mut Criterion) {
    let bvh = std::fs::read(format!(
        "{DATA}cmu_09_12_walk_forward_backward_sideways.bvh"
    ))
    .unwrap();
    let csv = std::fs::read(format!(
        "{DATA}kinect2_labanotation_ges02_balancinghands.csv"
    ))
    .unwrap();
    let bvh_count = bvh_frames(&bvh, None);
    let frames: Vec<HumanFrame> = BvhReader::new(Cursor::new(&bvh), "bench", BvhConfig::cmu())
        .unwrap()
        .map(Result::unwrap)
        .collect();

    let mut group = c.benchmark_group("human_input");
    group.throughput(Throughput::Elements(bvh_count));
    group.bench_function("bvh_read_fk", |b| {
        b.iter(|| bvh_frames(black_box(&bvh), None))
    });
    group.bench_function("bvh_read_fk_support", |b| {
        b.iter(|| {
            let mut detector = SupportDetector::new(SupportConfig::optical()).unwrap();
            bvh_frames(black_box(&bvh), Some(&mut detector))
        })
    });
    group.bench_function("support_only", |b| {
        b.iter(|| {
            let mut detector = SupportDetector::new(SupportConfig::optical()).unwrap();
            for f in &frames {
                black_box(detector.update(black_box(f)));
            }
        })
    });
    let mut detector = SupportDetector::new(SupportConfig::kinect()).unwrap();
    group.throughput(Throughput::Elements(kinect_frames(&csv, &mut detector)));
    group.bench_function("kinect_read_support", |b| {
        b.iter(|| {
            let mut detector = SupportDetector::new(SupportConfig::kinect()).unwrap();
            kinect_frames(black_box(&csv), &mut detector)
        })
    });
    group.finish();
}

criterion_group!(benches, human_input);
criterion_main!(benches);
