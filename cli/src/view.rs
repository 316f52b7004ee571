//! `view.html`: a self-contained 3D viewer of an imitation run or a walk (the robot drawn from
//! its model's links, the scaled human, the floor, the support polygon, the CoM ground
//! projection, the phases), written as the frames come; and the `view` command that opens it.
//!
//! The file is the page template (`viewer.html`) with the run's data spliced in as compact JSON:
//! positions in integer millimetres, at most [`VIEW_RATE`] frames per second, so a 60 s clip
//! stays around 2 MB. Frames are written as they come, so memory stays flat.

use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Context, Result, bail};
use clap::Args;
use serde_json::json;
use taskstack::human::{HumanJoint, Side};
use taskstack::imitation::EFFECTORS;
use taskstack::imitation::output::CONTACT_HEIGHT;
use taskstack::imitation::output::HandPlacement;
use taskstack::imitation::phase::SupportPhase;
use taskstack::imitation::reference::support::HumanSupport;
use taskstack::locomotion::Footstep;
use taskstack::model::{FrameId, Model, ModelData};
use taskstack::robots::BipedProfile;
use taskstack::{IsometryMatrix3, RobotFrame, Vector2, Vector3};

use crate::Report;

/// The page: a script that draws the data it finds in `const RUN` and `const FRAMES`.
const TEMPLATE: &str = include_str!("viewer.html");
/// Where the data goes in [`TEMPLATE`].
const DATA_MARK: &str = "/*RUN DATA*/";

/// Frames per second of the viewer's data (the run's frames are thinned to at most this rate).
pub(crate) const VIEW_RATE: f64 = 30.0;

/// Segments shorter than this are not drawn (m): joints whose frames share an origin.
const MIN_SEGMENT: f64 = 0.005;

/// Streams `view.html` for one run.
pub(crate) struct ViewWriter<W: Write> {
    out: W,
    /// The model rooted at the right sole: every frame is drawn with it, whatever the root, so
    /// the point list stays the same (the sole's world placement puts it in place).
    model: Model,
    data: ModelData,
    right_sole: FrameId,
    /// Links whose origins are drawn, in the order of each frame's point list.
    links: Vec<usize>,
    /// Named frames drawn as points beyond their link (hands, head…).
    frames: Vec<FrameId>,
    outlines: [Vec<[f64; 2]>; 2],
    next_time: f64,
    written: usize,
    line: String,
}

impl<W: Write> ViewWriter<W> {
    /// Writes the page and the run's constant data (robot segments, sole outlines, human
    /// skeleton) for the robot of `profile`; `title` names the run.
    pub(crate) fn new(mut out: W, profile: &BipedProfile, title: &str) -> Result<Self> {
        let model = profile.model(Side::Right).clone();
        let mut data = model.new_data();
        let right_sole = model.frame_id(&profile.foot(Side::Right).sole)?;
        let stand = &profile.stand;
        model.forward_kinematics(&mut data, stand)?;
        let hands_and_torso = [&profile.hands[0], &profile.hands[1], &profile.torso];
        let drawing = robot_drawing(&model, &data, &hands_and_torso.map(String::as_str))?;
        let human: Vec<[usize; 2]> = HumanJoint::ALL
            .iter()
            .filter_map(|j| j.antecedent().map(|a| [a.index(), j.index()]))
            .collect();
        let outlines = [Side::Left, Side::Right].map(|s| profile.foot(s).outline.clone());
        let run = json!({
            "title": title,
            "robot": profile.name,
            "height_m": drawing.height,
            "segments": drawing.segments,
            "human_segments": human,
            "human_joints": HumanJoint::ALL.iter().map(|j| j.name()).collect::<Vec<_>>(),
            "rate_hz": VIEW_RATE,
            "phases": SupportPhase::ALL.iter().map(ToString::to_string).collect::<Vec<_>>(),
            // The human joints of the hands' targets ([`EFFECTORS`]' hands), in the human points.
            "hand_joints": EFFECTORS[..2].iter().map(|(_, joint)| joint.index()).collect::<Vec<_>>(),
        });
        let (head, _) = split_template()?;
        write!(out, "{head}const RUN = {run};\nconst FRAMES = [\n")?;
        Ok(Self {
            out,
            model,
            data,
            right_sole,
            links: drawing.links,
            frames: drawing.frames,
            outlines,
            next_time: f64::NEG_INFINITY,
            written: 0,
            line: String::new(),
        })
    }

    /// Adds robot frame `r` if it is due at [`VIEW_RATE`]. Each frame is
    /// `[time ms, phase, human support, robot points, human points, left sole, right sole,
    /// CoM xy, grounded bits, planned ZMP xy or null, footsteps, hand supports, robot hands
    /// (left xyz, right xyz) or null]`, lengths in mm in the world
    /// frame; each footstep is `[side (0 left, 1 right), corner x, y, …]`, its sole outline
    /// where it lands; then the hands placed on or held at a surface (see
    /// `push_hand_supports`).
    pub(crate) fn frame(&mut self, r: &RobotFrame) -> Result<()> {
        let reference = (r.reference.iter())
            .map(|p| p.map(|p| r.world_t_root.transform_point(&p.into()).coords));
        let frame = ViewFrame {
            time: r.time,
            phase: r.phase,
            human_support: r.human_support,
            q: &r.q,
            soles: [&r.left_sole, &r.right_sole],
            com: r.com,
            zmp: r.walk.map(|w| w.zmp),
            footsteps: &r.footsteps,
            hand_supports: r.hand_supports,
            hands: Some([0, 1].map(|k| {
                r.world_t_root
                    .transform_point(&r.effectors[k].into())
                    .coords
            })),
        };
        self.frame_of(&frame, reference)
    }

    /// Adds `r` if it is due at [`VIEW_RATE`], with the scaled human's joints `reference`
    /// (world frame, m; [`HumanJoint::ALL`] order, `None` where missing or no human).
    pub(crate) fn frame_of(
        &mut self,
        r: &ViewFrame<'_>,
        reference: impl Iterator<Item = Option<Vector3<f64>>>,
    ) -> Result<()> {
        if r.time < self.next_time {
            return Ok(());
        }
        // 1 % early, so that frames 1/120 s apart are kept every fourth, not fifth.
        self.next_time = r.time + 0.99 / VIEW_RATE;
        self.model.forward_kinematics(&mut self.data, r.q)?;
        let world_t_base = r.soles[1] * self.data.frame_placement(self.right_sole).inverse();
        let phase = r.phase.index();
        let line = &mut self.line;
        line.clear();
        line.push_str(&format!(
            "[{},{},{},[",
            (r.time * 1000.0).round(),
            phase,
            human_support_index(r.human_support)
        ));
        let mut first = true;
        let links = self.links.iter().map(|&l| self.data.link_placement(l));
        let frames = self.frames.iter().map(|&f| self.data.frame_placement(f));
        for placement in links.chain(frames) {
            let p = world_t_base.transform_point(&placement.translation.vector.into());
            push_point(line, &mut first, &p.coords);
        }
        line.push_str("],[");
        let mut first = true;
        for reference in reference {
            if !first {
                line.push(',');
            }
            first = false;
            match reference {
                Some(w) => push_xyz(line, &w),
                None => line.push_str("null,null,null"),
            }
        }
        line.push(']');
        let mut grounded = 0;
        for (i, sole) in r.soles.into_iter().enumerate() {
            line.push_str(",[");
            let mut first = true;
            let mut on_ground = true;
            for &[x, y] in &self.outlines[i] {
                let corner = sole_point(sole, x, y);
                on_ground &= corner.z.abs() <= CONTACT_HEIGHT;
                push_point(line, &mut first, &corner);
            }
            line.push(']');
            grounded |= u8::from(on_ground) << i;
        }
        line.push_str(&format!(",[{},{}],{grounded},", mm(r.com.x), mm(r.com.y)));
        match r.zmp {
            Some(zmp) => line.push_str(&format!("[{},{}]", mm(zmp.x), mm(zmp.y))),
            None => line.push_str("null"),
        }
        line.push_str(",[");
        for (k, step) in r.footsteps.iter().enumerate() {
            line.push_str(if k == 0 { "[" } else { ",[" });
            line.push_str(&step.side.index().to_string());
            for &[x, y] in &self.outlines[step.side.index()] {
                let corner = step.target.to_world([x, y]);
                line.push_str(&format!(",{},{}", mm(corner.x), mm(corner.y)));
            }
            line.push(']');
        }
        line.push_str("],[");
        push_hand_supports(line, &r.hand_supports);
        line.push_str("],");
        match r.hands {
            Some(hands) => {
                line.push('[');
                push_xyz(line, &hands[0]);
                line.push(',');
                push_xyz(line, &hands[1]);
                line.push(']');
            }
            None => line.push_str("null"),
        }
        line.push_str("],\n");
        self.out.write_all(line.as_bytes())?;
        self.written += 1;
        Ok(())
    }

    /// Closes the data (the clip's last time `clip_end`, s, after which the human holds its
    /// pose; the run's `summary`) and writes the rest of the page.
    pub(crate) fn finish(self, clip_end: f64, summary: serde_json::Value) -> Result<()> {
        self.into_inner(clip_end, summary).map(drop)
    }

    /// [`ViewWriter::finish`], giving the output back.
    pub(crate) fn into_inner(mut self, clip_end: f64, summary: serde_json::Value) -> Result<W> {
        let tail = json!({ "clip_end_ms": (clip_end * 1000.0).round(),
                           "summary": summary, "frames": self.written });
        let (_, rest) = split_template()?;
        write!(self.out, "];\nconst TAIL = {tail};\n{rest}")?;
        self.out.flush()?;
        Ok(self.out)
    }
}

impl ViewWriter<Vec<u8>> {
    /// What was written since the last call: the page's head at first, then each frame's line
    /// (empty when the frame was not due).
    pub(crate) fn take_written(&mut self) -> Vec<u8> {
        std::mem::take(&mut self.out)
    }

    /// The live page of a view whose head (the template up to the frames, the run's data
    /// included) is `head`: no frames of its own, `LIVE` set, so that its script takes them
    /// from the WebSocket it opens.
    pub(crate) fn live_page(head: &str) -> Result<String> {
        let (_, rest) = split_template()?;
        let tail = json!({ "clip_end_ms": 1e12, "summary": null, "frames": 0 });
        Ok(format!(
            "{head}];\nconst TAIL = {tail};\nconst LIVE = true;\n{rest}"
        ))
    }
}

/// One frame of a run for the viewer: what [`ViewWriter::frame_of`] draws besides the human.
pub(crate) struct ViewFrame<'a> {
    /// The run's clock (s).
    pub(crate) time: f64,
    /// The robot's phase.
    pub(crate) phase: SupportPhase,
    /// The human's support (what the human timeline shows).
    pub(crate) human_support: HumanSupport,
    /// Joint angles (rad, model variable order).
    pub(crate) q: &'a [f64],
    /// World placements of the soles, `[left, right]`.
    pub(crate) soles: [&'a IsometryMatrix3<f64>; 2],
    /// Whole-body CoM (m, world).
    pub(crate) com: Vector3<f64>,
    /// The walk's planned ZMP (m, world; cart-table model) while the robot walks.
    pub(crate) zmp: Option<Vector2<f64>>,
    /// The walk's footsteps not yet landed (world).
    pub(crate) footsteps: &'a [Footstep],
    /// The hands placed on or held at a surface (world), `[left, right]`.
    pub(crate) hand_supports: [Option<HandPlacement>; 2],
    /// The robot's hands (m, world), `[left, right]`, drawn with their targets (the scaled
    /// human's hands as the robot is asked to reach them); `None` for a run with no human.
    pub(crate) hands: Option<[Vector3<f64>; 2]>,
}

/// What is drawn of the robot: the link origins and named frames whose world positions each
/// frame lists (links first), the segments between them (indices into that list), and the
/// robot's standing height (m).
struct RobotDrawing {
    links: Vec<usize>,
    frames: Vec<FrameId>,
    segments: Vec<[usize; 2]>,
    height: f64,
}

/// A segment per joint from its parent link's origin to its child's, and one from each of
/// `frame_names`' link to the frame, when they are at least [`MIN_SEGMENT`] apart in the
/// posture of `data`.
fn robot_drawing(model: &Model, data: &ModelData, frame_names: &[&str]) -> Result<RobotDrawing> {
    let origin = |link: usize| data.link_placement(link).translation.vector;
    let mut links: Vec<usize> = Vec::new();
    let mut point = |link: usize| match links.iter().position(|&l| l == link) {
        Some(i) => i,
        None => {
            links.push(link);
            links.len() - 1
        }
    };
    let mut segments = Vec::new();
    for (j, joint) in model.joints().iter().enumerate() {
        let (parent, child) = (joint.antecedent, j + 1);
        if (origin(child) - origin(parent)).norm() >= MIN_SEGMENT {
            segments.push([point(parent), point(child)]);
        }
    }
    let (mut frames, mut to_frames) = (Vec::new(), Vec::new());
    for name in frame_names {
        let id = model.frame_id(name)?;
        let link = model.frames()[id.index()].link;
        if (data.frame_placement(id).translation.vector - origin(link)).norm() >= MIN_SEGMENT {
            to_frames.push((point(link), frames.len()));
            frames.push(id);
        }
    }
    // Frame points follow the link points in each frame's list.
    let n = links.len();
    segments.extend(to_frames.into_iter().map(|(a, k)| [a, n + k]));
    let height = (0..model.links().len())
        .map(|l| origin(l).z)
        .fold(0.0, f64::max);
    Ok(RobotDrawing {
        links,
        frames,
        segments,
        height,
    })
}

fn split_template() -> Result<(&'static str, &'static str)> {
    TEMPLATE
        .split_once(DATA_MARK)
        .context("the viewer template has no data mark")
}

/// Each hand placed on or held at a surface as `[side (0 left, 1 right), holding (0/1), point x,
/// y, z, surface height, corner x, y, …]` (mm, world; no corners for an unbounded surface).
fn push_hand_supports(line: &mut String, hands: &[Option<HandPlacement>; 2]) {
    let placed = hands.iter().enumerate();
    for (k, (side, hand)) in placed.filter_map(|(i, h)| h.map(|h| (i, h))).enumerate() {
        let p = hand.point;
        let surface = &hand.surface;
        line.push_str(if k == 0 { "[" } else { ",[" });
        line.push_str(&format!(
            "{side},{},{},{},{},{}",
            u8::from(hand.holding),
            mm(p.x),
            mm(p.y),
            mm(p.z),
            mm(surface.height())
        ));
        for c in surface.corners().into_iter().flatten() {
            line.push_str(&format!(",{},{}", mm(c.x), mm(c.y)));
        }
        line.push(']');
    }
}

fn mm(v: f64) -> i64 {
    (v * 1000.0).round() as i64
}

fn push_xyz(line: &mut String, p: &Vector3<f64>) {
    line.push_str(&format!("{},{},{}", mm(p.x), mm(p.y), mm(p.z)));
}

fn push_point(line: &mut String, first: &mut bool, p: &Vector3<f64>) {
    if !*first {
        line.push(',');
    }
    *first = false;
    push_xyz(line, p);
}

fn sole_point(sole: &IsometryMatrix3<f64>, x: f64, y: f64) -> Vector3<f64> {
    sole.transform_point(&Vector3::new(x, y, 0.0).into()).coords
}

fn human_support_index(support: HumanSupport) -> u8 {
    match support {
        HumanSupport::Double => 0,
        HumanSupport::Right => 1,
        HumanSupport::Left => 2,
        HumanSupport::Airborne => 3,
    }
}

/// Open the 3D viewer of an output folder of `taskstack imitate` or `taskstack batch`.
///
/// Prints the path of OUT_DIR/view.html and opens it in the system's browser (xdg-open, open or
/// start). The page needs no network: everything is in the one file.
#[derive(Debug, Args)]
pub(crate) struct ViewArgs {
    /// An output folder of `imitate` or `walk` (it holds view.html).
    #[arg(value_name = "OUT_DIR")]
    out: PathBuf,
    /// Only print the page's path; do not start a browser.
    #[arg(long)]
    no_open: bool,
}

pub(crate) fn run(args: ViewArgs, report: Report) -> Result<ExitCode> {
    if !args.out.is_dir() {
        bail!("output folder {}: not a folder", args.out.display());
    }
    let page = args.out.join("view.html");
    if !page.is_file() {
        let runs = runs_in(&args.out);
        if !runs.is_empty() {
            bail!(
                "output folder {} holds a batch: its viewers are in the clip folders; view one \
                 with `taskstack view DIR`, DIR one of:\n  {}",
                args.out.display(),
                runs.join("\n  ")
            );
        }
        bail!(
            "output folder {}: no view.html (write one with `taskstack imitate CLIP --out {}`)",
            args.out.display(),
            args.out.display()
        );
    }
    let page = page.canonicalize().context("view.html")?;
    let mut text = String::new();
    if report.json {
        text = format!("{}\n", json!({ "view": page }));
    } else if !report.quiet {
        text = format!("{}\n", page.display());
    }
    crate::output(&text)?;
    if !args.no_open {
        open_in_browser(&page)?;
    }
    Ok(ExitCode::SUCCESS)
}

/// The subfolders of `dir` that hold a `view.html` (a batch's clip folders), sorted.
fn runs_in(dir: &std::path::Path) -> Vec<String> {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Vec::new();
    };
    let mut runs: Vec<String> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.join("view.html").is_file())
        .map(|p| p.display().to_string())
        .collect();
    runs.sort();
    runs
}

/// How long `view` waits for the opener to fail, in 50 ms polls (3 s).
const OPENER_WAIT_POLLS: usize = 60;

/// Opens `page` with the system's opener and waits for it: an opener that finds no browser
/// exits with an error, which is ours then (open the page yourself).
fn open_in_browser(page: &std::path::Path) -> Result<()> {
    let opener = if cfg!(target_os = "macos") {
        "open"
    } else if cfg!(windows) {
        "explorer"
    } else {
        "xdg-open"
    };
    let mut child = std::process::Command::new(opener)
        .arg(page)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .with_context(|| format!("cannot start `{opener}`; open {} yourself", page.display()))?;
    // Some openers return at once, some run the browser in the foreground: wait a little for
    // a failure, and take an opener still running after that as a browser that opened.
    for _ in 0..OPENER_WAIT_POLLS {
        if let Some(status) = child.try_wait()? {
            if !status.success() {
                bail!(
                    "`{opener}` could not open a browser ({status}); open {} yourself",
                    page.display()
                );
            }
            return Ok(());
        }
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    Ok(())
}
