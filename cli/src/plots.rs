//! The run plots, recorded while the clip is imitated in bounded memory (samples are thinned by
//! two whenever [`MAX_SAMPLES`] is reached) and written as SVG at the end:
//!
//! * `effectors.svg`: each hand's and ankle's distance to the scaled human (cm) over time, the
//!   robot's phases shaded; beside each hand's, dashed, the part no arm posture within the
//!   joint limits removes (the reach report's least error, over the clip's frames);
//! * `com.svg`: the CoM ground path seen from above inside the footprints (each placement once);
//! * `phases.svg`: the human's support and the robot's phase over time;
//! * `joints.svg`: the right arm's joint angles against their limits.

use taskstack::human::Side;
use taskstack::imitation::output::{CONTACT_HEIGHT, EFFECTORS};
use taskstack::imitation::phase::SupportPhase;
use taskstack::imitation::reference::support::HumanSupport;
use taskstack::model::Model;
use taskstack::{Imitator, RobotFrame, Vector3};

use crate::svg::{Axes, Svg, range};

/// Most samples kept for the time plots.
const MAX_SAMPLES: usize = 4096;
/// A foot standing this far (m) from its last footprint has been placed anew.
const NEW_PLACEMENT: f64 = 0.005;

const COLORS: [&str; 6] = [
    "#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b",
];
const SUPPORT_COLORS: [&str; 3] = ["#1982c4", "#6a4c93", "#8ac926"];
/// The transition steps' shading (the viewer's timeline uses the same): the CoM steps (CoM to
/// foot, CoM to middle) and the foot steps (lift, lower).
const COM_STEP_COLOR: &str = "#ffca3a";
const FOOT_STEP_COLOR: &str = "#ff924c";
/// The effector traces: a colour no phase shading uses.
const TRACE_COLOR: &str = "#222";

/// A row of the phase plot: the support colour index of a sample (`None`: transition).
type SupportOf = fn(&Sample) -> Option<usize>;

struct Sample {
    time: f64,
    errors: [Option<f64>; 4],
    /// The part of each hand's error no arm posture removes (m, `[left, right]`).
    least: [Option<f64>; 2],
    phase: SupportPhase,
    human: HumanSupport,
    com: [f64; 2],
}

/// Records what the plots need, frame by frame.
pub(crate) struct PlotRecorder {
    samples: Vec<Sample>,
    /// Joint angles of the plotted limb, `limb.len()` per sample.
    angles: Vec<f64>,
    stride: usize,
    seen: usize,
    /// The plotted limb: (variable index, name, lower, upper) (rad).
    limb: Vec<(usize, String, f64, f64)>,
    outlines: [Vec<[f64; 2]>; 2],
    /// Footprints (side, world outline), each placement once.
    footprints: Vec<(Side, Vec<[f64; 2]>)>,
    last_footprint: [Option<Vector3<f64>>; 2],
}

impl PlotRecorder {
    pub(crate) fn new(imitator: &Imitator) -> Self {
        let profile = imitator.profile();
        let model = profile.model(Side::Right);
        let bounds = imitator.bounds();
        let limb = limb_variables(model, &profile.hands[1], &profile.torso)
            .into_iter()
            .map(|v| {
                let name = model.variables()[v].name.clone();
                (v, name, bounds.lower()[v], bounds.upper()[v])
            })
            .collect();
        Self {
            samples: Vec::new(),
            angles: Vec::new(),
            stride: 1,
            seen: 0,
            limb,
            outlines: [Side::Left, Side::Right].map(|s| profile.foot(s).outline.clone()),
            footprints: Vec::new(),
            last_footprint: [None; 2],
        }
    }

    /// Records `r`, with `least` the part of each hand's error no arm posture removes (m,
    /// `[left, right]`; `None` where unknown).
    pub(crate) fn record(&mut self, r: &RobotFrame, least: [Option<f64>; 2]) {
        self.record_footprints(r);
        self.seen += 1;
        if !(self.seen - 1).is_multiple_of(self.stride) {
            return;
        }
        let mut errors = [None; 4];
        for (e, (_, joint)) in EFFECTORS.iter().enumerate() {
            errors[e] = r.reference[joint.index()].map(|p| (r.effectors[e] - p).norm());
        }
        self.samples.push(Sample {
            time: r.time,
            errors,
            least,
            phase: r.phase,
            human: r.human_support,
            com: [r.com.x, r.com.y],
        });
        self.angles.extend(self.limb.iter().map(|(v, ..)| r.q[*v]));
        if self.samples.len() >= MAX_SAMPLES {
            self.thin();
        }
    }

    /// Keeps every other sample and doubles the stride.
    fn thin(&mut self) {
        let k = self.limb.len();
        let mut keep = 0;
        for i in (0..self.samples.len()).step_by(2) {
            self.samples.swap(keep, i);
            for j in 0..k {
                self.angles[keep * k + j] = self.angles[i * k + j];
            }
            keep += 1;
        }
        self.samples.truncate(keep);
        self.angles.truncate(keep * k);
        self.stride *= 2;
    }

    fn record_footprints(&mut self, r: &RobotFrame) {
        for (i, sole) in [r.left_sole, r.right_sole].iter().enumerate() {
            let corners: Vec<Vector3<f64>> = (self.outlines[i].iter())
                .map(|&[x, y]| sole.transform_point(&Vector3::new(x, y, 0.0).into()).coords)
                .collect();
            if !corners.iter().all(|c| c.z.abs() <= CONTACT_HEIGHT) {
                continue;
            }
            let at = sole.translation.vector;
            let moved = self.last_footprint[i].is_none_or(|p| (p - at).norm() > NEW_PLACEMENT);
            if moved {
                self.last_footprint[i] = Some(at);
                let side = if i == 0 { Side::Left } else { Side::Right };
                self.footprints
                    .push((side, corners.iter().map(|c| [c.x, c.y]).collect()));
            }
        }
    }

    /// The four plots: `(file name, SVG)`.
    pub(crate) fn render(&self, title: &str) -> [(&'static str, String); 4] {
        [
            ("effectors.svg", self.effectors(title)),
            ("com.svg", self.com(title)),
            ("phases.svg", self.phases(title)),
            ("joints.svg", self.joints(title)),
        ]
    }

    fn time_range(&self) -> (f64, f64) {
        let t0 = self.samples.first().map_or(0.0, |s| s.time);
        let t1 = self.samples.last().map_or(1.0, |s| s.time);
        (t0, if t1 > t0 { t1 } else { t0 + 1.0 })
    }

    /// Shades every phase of the robot, transitions included, behind a time chart.
    fn shade_phases(&self, svg: &mut Svg, axes: &Axes) {
        for (start, end, color) in runs(&self.samples, |s| phase_color(s.phase)) {
            let (x0, x1) = (axes.px(start), axes.px(end));
            svg.rect(x0, axes.top, (x1 - x0).max(0.5), axes.height, color, 0.15);
        }
    }

    fn effectors(&self, title: &str) -> String {
        let (panel_h, gap, left, width) = (130.0, 60.0, 70.0, 760.0);
        let mut svg = Svg::new(left + width + 30.0, 70.0 + 4.0 * (panel_h + gap));
        svg.text(
            left,
            22.0,
            14,
            "start",
            &format!("{title}: distance of each effector to the scaled human"),
        );
        svg.legend(
            left,
            44.0,
            &[
                ("RS", SUPPORT_COLORS[0], false),
                ("LS", SUPPORT_COLORS[1], false),
                ("DS", SUPPORT_COLORS[2], false),
                ("CoM step", COM_STEP_COLOR, false),
                ("lift / lower", FOOT_STEP_COLOR, false),
                ("distance", TRACE_COLOR, false),
                ("no arm posture removes", TRACE_COLOR, true),
            ],
        );
        let x = self.time_range();
        for (e, (name, _)) in EFFECTORS.iter().enumerate() {
            let values = self
                .samples
                .iter()
                .filter_map(|s| s.errors[e])
                .map(|v| v * 100.0);
            let y = (0.0, range(values, 1.0).1);
            let axes = Axes {
                left,
                top: 70.0 + e as f64 * (panel_h + gap),
                width,
                height: panel_h,
                x,
                y,
            };
            self.shade_phases(&mut svg, &axes);
            axes.draw(&mut svg, "time (s)", &format!("{name} (cm)"));
            let points: Vec<_> = (self.samples.iter())
                .map(|s| s.errors[e].map(|v| axes.point(s.time, v * 100.0)))
                .collect();
            svg.path(&points, TRACE_COLOR, 1.5, false);
            if let Some(hand) = (e < 2).then_some(e) {
                let least: Vec<_> = (self.samples.iter())
                    .map(|s| s.least[hand].map(|v| axes.point(s.time, v * 100.0)))
                    .collect();
                svg.path(&least, TRACE_COLOR, 1.0, true);
            }
        }
        svg.finish()
    }

    fn com(&self, title: &str) -> String {
        let points = self.footprints.iter().flat_map(|(_, o)| o.iter().copied());
        let points: Vec<[f64; 2]> = points.chain(self.samples.iter().map(|s| s.com)).collect();
        let (x, y) = (
            range(points.iter().map(|p| p[0]), 0.1),
            range(points.iter().map(|p| p[1]), 0.1),
        );
        // Equal scales on both axes: the wider span sets the metres per pixel.
        let size = 560.0;
        let scale = size / (x.1 - x.0).max(y.1 - y.0);
        let (w, h) = ((x.1 - x.0) * scale, (y.1 - y.0) * scale);
        let mut svg = Svg::new((w + 120.0).max(720.0), h + 130.0);
        svg.text(
            80.0,
            22.0,
            14,
            "start",
            &format!("{title}: CoM ground path and footprints, seen from above"),
        );
        svg.legend(
            80.0,
            44.0,
            &[
                ("CoM", "#000", false),
                ("left foot", COLORS[0], false),
                ("right foot", COLORS[1], false),
            ],
        );
        // Plot x (forward) to the right and y (left) up: the view from above.
        let axes = Axes {
            left: 80.0,
            top: 60.0,
            width: w,
            height: h,
            x,
            y,
        };
        axes.draw(&mut svg, "x, forward (m)", "y, left (m)");
        for (side, outline) in &self.footprints {
            let color = if *side == Side::Left {
                COLORS[0]
            } else {
                COLORS[1]
            };
            let corners: Vec<_> = outline.iter().map(|p| axes.point(p[0], p[1])).collect();
            svg.polygon(&corners, color, color);
        }
        let path: Vec<_> = self
            .samples
            .iter()
            .map(|s| Some(axes.point(s.com[0], s.com[1])))
            .collect();
        svg.path(&path, "#000", 1.2, false);
        svg.finish()
    }

    fn phases(&self, title: &str) -> String {
        let (left, width) = (110.0, 760.0);
        let mut svg = Svg::new(left + width + 30.0, 200.0);
        svg.text(
            left,
            22.0,
            14,
            "start",
            &format!("{title}: support over time"),
        );
        svg.legend(
            left,
            44.0,
            &[
                ("right (RS)", SUPPORT_COLORS[0], false),
                ("left (LS)", SUPPORT_COLORS[1], false),
                ("double (DS)", SUPPORT_COLORS[2], false),
                ("transition / airborne", "#bbb", false),
            ],
        );
        let axes = Axes {
            left,
            top: 60.0,
            width,
            height: 80.0,
            x: self.time_range(),
            y: (0.0, 2.0),
        };
        let rows: [(&str, SupportOf); 2] = [
            ("human", |s| match s.human {
                HumanSupport::Right => Some(0),
                HumanSupport::Left => Some(1),
                HumanSupport::Double => Some(2),
                HumanSupport::Airborne => None,
            }),
            ("robot", |s| continuous(s.phase)),
        ];
        for (row, (label, of)) in rows.iter().enumerate() {
            let top = axes.top + row as f64 * 40.0 + 4.0;
            for (start, end, value) in runs(&self.samples, of) {
                let color = value.map_or("#bbb", |k| SUPPORT_COLORS[k]);
                let (x0, x1) = (axes.px(start), axes.px(end));
                svg.rect(x0, top, (x1 - x0).max(0.5), 32.0, color, 0.8);
            }
            svg.text(left - 8.0, top + 20.0, 11, "end", label);
        }
        let axes = Axes {
            y: (0.0, 1.0),
            ..axes
        };
        draw_time_axis(&mut svg, &axes);
        svg.finish()
    }

    fn joints(&self, title: &str) -> String {
        let (panel_h, gap, left, width) = (90.0, 50.0, 90.0, 740.0);
        let k = self.limb.len();
        let mut svg = Svg::new(
            left + width + 30.0,
            80.0 + k.max(1) as f64 * (panel_h + gap),
        );
        svg.text(
            left,
            22.0,
            14,
            "start",
            &format!("{title}: right-arm joint angles and their limits"),
        );
        svg.legend(
            left,
            44.0,
            &[("angle", COLORS[0], false), ("limits", COLORS[1], true)],
        );
        let x = self.time_range();
        for (j, (_, name, lower, upper)) in self.limb.iter().enumerate() {
            let values = (0..self.samples.len()).map(|i| self.angles[i * k + j]);
            let y = range(values.chain([*lower, *upper]), 0.1);
            let axes = Axes {
                left,
                top: 70.0 + j as f64 * (panel_h + gap),
                width,
                height: panel_h,
                x,
                y,
            };
            axes.draw(&mut svg, "time (s)", &format!("{name} (rad)"));
            for limit in [lower, upper] {
                let line = [Some(axes.point(x.0, *limit)), Some(axes.point(x.1, *limit))];
                svg.path(&line, COLORS[1], 1.2, true);
            }
            let points: Vec<_> = (self.samples.iter().enumerate())
                .map(|(i, s)| Some(axes.point(s.time, self.angles[i * k + j])))
                .collect();
            svg.path(&points, COLORS[0], 1.5, false);
        }
        svg.finish()
    }
}

/// The variables between the torso and the hand: the hand's ancestors that are not the torso's.
fn limb_variables(model: &Model, hand: &str, torso: &str) -> Vec<usize> {
    let ancestors = |frame: &str| -> Vec<usize> {
        let Ok(id) = model.frame_id(frame) else {
            return Vec::new();
        };
        let mut link = model.frames()[id.index()].link;
        let mut chain = Vec::new();
        while link > 0 {
            let joint = &model.joints()[link - 1];
            chain.extend(joint.variable);
            link = joint.antecedent;
        }
        chain
    };
    let torso = ancestors(torso);
    let mut arm: Vec<usize> = ancestors(hand)
        .into_iter()
        .filter(|v| !torso.contains(v))
        .collect();
    arm.reverse();
    arm.dedup();
    arm
}

/// The shading colour of a phase (see [`SUPPORT_COLORS`], [`COM_STEP_COLOR`]).
fn phase_color(phase: SupportPhase) -> &'static str {
    use taskstack::imitation::phase::{Landing, TakeOff};
    match phase {
        SupportPhase::Right => SUPPORT_COLORS[0],
        SupportPhase::Left => SUPPORT_COLORS[1],
        SupportPhase::Double => SUPPORT_COLORS[2],
        SupportPhase::DoubleToRight(TakeOff::ComToFoot)
        | SupportPhase::DoubleToLeft(TakeOff::ComToFoot)
        | SupportPhase::RightToDouble(Landing::ComToMiddle)
        | SupportPhase::LeftToDouble(Landing::ComToMiddle) => COM_STEP_COLOR,
        _ => FOOT_STEP_COLOR,
    }
}

/// Index into the support colours of a continuous phase (RS, LS, DS); `None` in transitions.
fn continuous(phase: SupportPhase) -> Option<usize> {
    match phase {
        SupportPhase::Right => Some(0),
        SupportPhase::Left => Some(1),
        SupportPhase::Double => Some(2),
        _ => None,
    }
}

/// Runs of equal `value` over the samples: (start time, end time, value).
fn runs<T: PartialEq + Copy>(
    samples: &[Sample],
    value: impl Fn(&Sample) -> T,
) -> Vec<(f64, f64, T)> {
    let mut out: Vec<(f64, f64, T)> = Vec::new();
    for s in samples {
        let v = value(s);
        match out.last_mut() {
            Some(last) if last.2 == v => last.1 = s.time,
            Some(last) => {
                last.1 = s.time;
                out.push((s.time, s.time, v));
            }
            None => out.push((s.time, s.time, v)),
        }
    }
    out
}

fn draw_time_axis(svg: &mut Svg, axes: &Axes) {
    let bottom = axes.top + axes.height;
    svg.line(
        (axes.left, bottom),
        (axes.left + axes.width, bottom),
        "#444",
        1.0,
    );
    for t in crate::svg::ticks(axes.x.0, axes.x.1) {
        let x = axes.px(t);
        svg.line((x, bottom), (x, bottom + 4.0), "#444", 1.0);
        svg.text(x, bottom + 16.0, 10, "middle", &crate::svg::label(t));
    }
    svg.text(
        axes.left + axes.width / 2.0,
        bottom + 32.0,
        11,
        "middle",
        "time (s)",
    );
}
