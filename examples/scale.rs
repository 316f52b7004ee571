//! Scales a motion clip to the NAO segment by segment (Poubel eq. 1, per support phase) and shows
//! the result.
//!
//! ```sh
//! cargo run --release --example scale -- [CLIP.bvh|CLIP.csv] [--out DIR] [--frames 100,900]
//! ```
//!
//! Without a clip, the bundled `tests/data/mocap/cmu_05_02_stand_arm_gestures_turn_single_leg.bvh`
//! (CMU conventions); `.csv` files are read as Kinect v2 (support thresholds for Kinect).
//! Writes (default `DIR` = `target/scale`):
//!
//! * `DIR/support.csv`: `time,support` (seconds; `Double`, `Right`, `Left`, `Airborne`);
//! * `DIR/scaled.csv`: `time,stance,` then `x,y,z` (metres, support sole frame) of every robot
//!   point;
//! * `DIR/skeletons.svg`: at each chosen frame, the human skeleton beside the scaled one, front
//!   view (y–z, seen from the front) and side view (x–z, seen from the robot's right).
//!
//! Errors (unreadable clip, bad arguments) go to stderr with exit status 1 or 2.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use nalgebra::{Rotation3, Vector3};
use taskstack::human::Side;
use taskstack::human::{HumanFrame, HumanJoint};
use taskstack::imitation::reference::scaler::{
    RobotSkeleton, ScaleConfig, ScaledSkeleton, Scaler, Stance,
};
use taskstack::imitation::reference::support::{HumanSupport, SupportConfig, SupportDetector};
use taskstack::io::clip::Clip;
use taskstack::robots::nao;

const DEFAULT_CLIP: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/tests/data/mocap/cmu_05_02_stand_arm_gestures_turn_single_leg.bvh"
);

struct Args {
    clip: PathBuf,
    out: PathBuf,
    frames: Vec<usize>,
}

fn parse_args() -> Result<Args, String> {
    let mut args = Args {
        clip: PathBuf::from(DEFAULT_CLIP),
        out: PathBuf::from("target/scale"),
        frames: vec![100, 900],
    };
    let mut it = std::env::args().skip(1);
    while let Some(a) = it.next() {
        match a.as_str() {
            "--out" => args.out = it.next().ok_or("--out needs a directory")?.into(),
            "--frames" => {
                let list = it.next().ok_or("--frames needs a list like 100,900")?;
                args.frames = list
                    .split(',')
                    .map(|s| {
                        s.trim()
                            .parse()
                            .map_err(|_| format!("bad frame number `{s}`"))
                    })
                    .collect::<Result<_, _>>()?;
            }
            _ if a.starts_with("--") => return Err(format!("unknown option `{a}`")),
            _ => args.clip = a.into(),
        }
    }
    Ok(args)
}

/// Every frame of the clip, and the support detector settings that suit its source.
fn read_clip(path: &Path) -> Result<(Vec<HumanFrame>, SupportConfig), String> {
    let clip = Clip::open(path).map_err(|e| e.to_string())?;
    let support = SupportConfig::for_capture(clip.capture());
    let frames = clip
        .collect::<Result<Vec<_>, _>>()
        .map_err(|e| e.to_string())?;
    Ok((frames, support))
}

/// Bones as (from, to) point pairs.
type Bones = Vec<(Vector3<f64>, Vector3<f64>)>;

fn human_bones(frame: &HumanFrame, base: Side) -> Bones {
    // Shown as the scaler sees it: turned so the base foot's ankle→toe points along +x.
    let (ankle, toe) = match base {
        Side::Left => (HumanJoint::LAnkle, HumanJoint::LToe),
        Side::Right => (HumanJoint::RAnkle, HumanJoint::RToe),
    };
    let heading = match (frame.get(ankle), frame.get(toe)) {
        (Some(a), Some(t)) => (t.y - a.y).atan2(t.x - a.x),
        _ => 0.0,
    };
    let r = Rotation3::from_axis_angle(&Vector3::z_axis(), -heading);
    HumanJoint::ALL
        .into_iter()
        .filter(|&j| j != HumanJoint::Pelvis)
        .filter_map(|j| Some((r * frame.get(j.antecedent()?)?, r * frame.get(j)?)))
        .collect()
}

fn robot_bones(scaled: &ScaledSkeleton, skeleton: &RobotSkeleton) -> Bones {
    skeleton
        .joints()
        .iter()
        .filter_map(|&j| Some((scaled.get(skeleton.antecedent(j)?)?, scaled.get(j)?)))
        .collect()
}

const PANEL: f64 = 220.0;

/// Draws `bones` in a PANEL×PANEL box at (`x0`, `y0`), projected on (horizontal `h`, z),
/// scaled to fit; returns the SVG and the skeleton's height in metres.
fn panel(
    svg: &mut String,
    bones: &Bones,
    x0: f64,
    y0: f64,
    h: fn(&Vector3<f64>) -> f64,
    label: &str,
    colour: &str,
) {
    let (mut lo, mut hi) = (
        Vector3::repeat(f64::INFINITY),
        Vector3::repeat(f64::NEG_INFINITY),
    );
    for (a, b) in bones {
        for p in [a, b] {
            let q = Vector3::new(h(p), p.z, 0.0);
            lo = lo.inf(&q);
            hi = hi.sup(&q);
        }
    }
    let size = (hi - lo).max().max(1e-9);
    let s = (PANEL - 40.0) / size;
    let cx = (lo.x + hi.x) / 2.0;
    let map = |p: &Vector3<f64>| {
        (
            x0 + PANEL / 2.0 + (h(p) - cx) * s,
            y0 + PANEL - 20.0 - (p.z - lo.y) * s,
        )
    };
    let _ = writeln!(
        svg,
        r#"<rect x="{x0}" y="{y0}" width="{PANEL}" height="{PANEL}" fill="none" stroke="silver"/>"#
    );
    let _ = writeln!(
        svg,
        r#"<line x1="{x0}" y1="{gy:.1}" x2="{x1}" y2="{gy:.1}" stroke="gray" stroke-dasharray="4 3"/>"#,
        gy = y0 + PANEL - 20.0 - (0.0 - lo.y) * s,
        x1 = x0 + PANEL
    );
    for (a, b) in bones {
        let ((x1, y1), (x2, y2)) = (map(a), map(b));
        let _ = writeln!(
            svg,
            r#"<line x1="{x1:.1}" y1="{y1:.1}" x2="{x2:.1}" y2="{y2:.1}" stroke="{colour}" stroke-width="3" stroke-linecap="round"/>"#
        );
    }
    let _ = writeln!(
        svg,
        r#"<text x="{}" y="{}" font-size="12" font-family="sans-serif">{label} ({:.2} m tall)</text>"#,
        x0 + 4.0,
        y0 + 14.0,
        hi.y - lo.y
    );
}

fn run(args: &Args) -> Result<(), String> {
    let (frames, support_config) = read_clip(&args.clip)?;
    let mut detector = SupportDetector::new(support_config).map_err(|e| e.to_string())?;
    let skeleton = RobotSkeleton::of(&nao::profile()).unwrap();
    let mut scaler = Scaler::new(skeleton.clone(), ScaleConfig::new(nao::STEP_ENVELOPE))
        .map_err(|e| e.to_string())?;
    std::fs::create_dir_all(&args.out).map_err(|e| format!("{}: {e}", args.out.display()))?;

    let points: Vec<HumanJoint> = skeleton.joints().to_vec();
    let mut support_csv = String::from("time,support\n");
    let mut scaled_csv = String::from("time,stance");
    for j in &points {
        let _ = write!(scaled_csv, ",{0}_x,{0}_y,{0}_z", j.name());
    }
    scaled_csv.push('\n');
    let mut shown = Vec::new();
    let mut counts = [0usize; 4];
    let mut stances = [0usize; 3];
    for (k, frame) in frames.iter().enumerate() {
        let support = detector.update(frame);
        counts[support as usize] += 1;
        let scaled = scaler
            .scale(frame, support)
            .map_err(|e| format!("frame {k}: {e}"))?;
        stances[scaled.stance as usize] += 1;
        let _ = writeln!(support_csv, "{:.6},{support:?}", frame.time);
        let _ = write!(scaled_csv, "{:.6},{:?}", frame.time, scaled.stance);
        for &j in &points {
            let p = scaled.get(j).unwrap_or_else(Vector3::zeros);
            let _ = write!(scaled_csv, ",{:.6},{:.6},{:.6}", p.x, p.y, p.z);
        }
        scaled_csv.push('\n');
        if args.frames.contains(&k) {
            shown.push((k, *frame, support, *scaled));
        }
    }
    let write = |name: &str, text: &str| {
        let path = args.out.join(name);
        std::fs::write(&path, text).map_err(|e| format!("{}: {e}", path.display()))
    };
    write("support.csv", &support_csv)?;
    write("scaled.csv", &scaled_csv)?;

    let width = 4.0 * PANEL + 50.0;
    let height = shown.len() as f64 * (PANEL + 30.0) + 10.0;
    let mut svg = format!(
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" viewBox="0 0 {width} {height}"><rect width="100%" height="100%" fill="white"/>"#
    );
    svg.push('\n');
    // Seen from the front: the human's left (+y) on the viewer's right.
    let front: fn(&Vector3<f64>) -> f64 = |p| p.y;
    let side: fn(&Vector3<f64>) -> f64 = |p| p.x;
    for (row, (k, frame, support, scaled)) in shown.iter().enumerate() {
        let y0 = 10.0 + row as f64 * (PANEL + 30.0) + 20.0;
        let _ = writeln!(
            svg,
            r#"<text x="10" y="{}" font-size="14" font-family="sans-serif">frame {k}, t = {:.2} s, human support {support:?}, robot stance {:?} (ground dashed)</text>"#,
            y0 - 6.0,
            frame.time,
            scaled.stance
        );
        let human = human_bones(frame, scaled.base());
        let robot = robot_bones(scaled, &skeleton);
        panel(&mut svg, &human, 10.0, y0, front, "human, front", "#1f77b4");
        panel(
            &mut svg,
            &robot,
            20.0 + PANEL,
            y0,
            front,
            "NAO scaled, front",
            "#d62728",
        );
        panel(
            &mut svg,
            &human,
            30.0 + 2.0 * PANEL,
            y0,
            side,
            "human, side",
            "#1f77b4",
        );
        panel(
            &mut svg,
            &robot,
            40.0 + 3.0 * PANEL,
            y0,
            side,
            "NAO scaled, side",
            "#d62728",
        );
    }
    svg.push_str("</svg>\n");
    write("skeletons.svg", &svg)?;

    let n = frames.len().max(1) as f64;
    println!("{}: {} frames", args.clip.display(), frames.len());
    println!(
        "human support: DS {:.0}%, RS {:.0}%, LS {:.0}%, airborne {:.0}%",
        100.0 * counts[HumanSupport::Double as usize] as f64 / n,
        100.0 * counts[HumanSupport::Right as usize] as f64 / n,
        100.0 * counts[HumanSupport::Left as usize] as f64 / n,
        100.0 * counts[HumanSupport::Airborne as usize] as f64 / n,
    );
    println!(
        "robot stance: DS {}, RS {}, LS {} frames",
        stances[Stance::Double as usize],
        stances[Stance::Right as usize],
        stances[Stance::Left as usize]
    );
    println!(
        "wrote {}/support.csv, scaled.csv, skeletons.svg ({} frames drawn)",
        args.out.display(),
        shown.len()
    );
    Ok(())
}

fn main() -> ExitCode {
    let args = match parse_args() {
        Ok(a) => a,
        Err(e) => {
            eprintln!("scale: {e}");
            return ExitCode::from(2);
        }
    };
    match run(&args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("scale: {e}");
            ExitCode::FAILURE
        }
    }
}
