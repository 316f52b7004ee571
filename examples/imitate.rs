//! The library's imitation loop in a few lines: the NAO imitates a bundled clip, one
//! `Imitator::step` per human frame, and the joint angles stream into a CSV file.
//!
//! `cargo run --release --example imitate -- [CLIP.bvh|CLIP.csv] [OUT.csv]`
//!
//! The `taskstack imitate` command (`cli/`) does the same with every option, metrics, plots and a
//! 3D viewer; this example shows the API it is built on.

use std::fs::File;
use std::io::BufWriter;

use taskstack::export::JointsWriter;
use taskstack::human::HumanFrame;
use taskstack::imitation::metrics::MetricsRecorder;
use taskstack::imitation::reference::support::SupportConfig;
use taskstack::io::clip::Clip;
use taskstack::robots::nao;
use taskstack::{Imitator, ImitatorConfig};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let clip_path = args.next().unwrap_or_else(|| {
        concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/tests/data/mocap/cmu_05_02_stand_arm_gestures_turn_single_leg.bvh"
        )
        .to_owned()
    });
    let out_path = args
        .next()
        .unwrap_or_else(|| "imitate_joints.csv".to_owned());

    let mut clip = Clip::open(&clip_path)?;
    // Support-detection thresholds for the kind of capture (optical mocap or a depth camera).
    let config = ImitatorConfig {
        support: SupportConfig::for_capture(clip.capture()),
        ..ImitatorConfig::default()
    };
    let mut imitator = Imitator::new(nao::profile(), config)?;
    let mut metrics = MetricsRecorder::new(&imitator);
    let file = File::create(&out_path).map_err(|e| format!("{out_path}: {e}"))?;
    let mut joints = JointsWriter::new(BufWriter::new(file));
    joints.header(&imitator)?;

    let mut human = HumanFrame::new(0.0);
    while clip.read_frame(&mut human)? {
        let robot = imitator.step(&human)?; // joint angles (rad) within limits, phase, CoM, …
        joints.frame(robot)?;
        metrics.record(robot);
    }
    joints.finish()?;

    let m = metrics.finish();
    println!(
        "{clip_path}: {} frames, {:.1} s; robot phases {}; min CoM margin {:.3} m; wrote {out_path}",
        m.frames,
        m.duration,
        m.robot_support_sequence.join(" → "),
        m.min_com_margin
    );
    Ok(())
}
