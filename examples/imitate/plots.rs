//! Hand-written SVG plots of an imitation run (no plotting dependency): effector trajectories
//! robot vs reference over time (Poubel Fig. 6), the CoM projection with the footprints on the
//! floor (Fig. 8), and the phase timeline of human and robot.

use std::fmt::Write as _;

use taskstack::human::Side;

/// What the plots need of one frame (world frame, metres).
pub struct Sample {
    pub time: f64,
    /// Robot and reference position of each plotted effector.
    pub effectors: Vec<([f64; 3], Option<[f64; 3]>)>,
    pub com: [f64; 2],
    /// World outline of each sole on the ground this frame.
    pub footprints: Vec<(Side, Vec<[f64; 2]>)>,
    pub human: &'static str,
    pub robot: String,
}

const COLORS: [&str; 4] = ["#1f77b4", "#d62728", "#2ca02c", "#9467bd"];

fn polyline(svg: &mut String, points: &[(f64, f64)], color: &str, dashed: bool) {
    if points.is_empty() {
        return;
    }
    let mut d = String::new();
    for (i, (x, y)) in points.iter().enumerate() {
        let _ = write!(d, "{}{x:.2},{y:.2}", if i == 0 { "M" } else { " L" });
    }
    let dash = if dashed {
        r#" stroke-dasharray="4 3""#
    } else {
        ""
    };
    let _ = writeln!(
        svg,
        r#"<path d="{d}" fill="none" stroke="{color}" stroke-width="1.2"{dash}/>"#
    );
}

fn text(svg: &mut String, x: f64, y: f64, s: &str, size: u32) {
    let _ = writeln!(
        svg,
        r#"<text x="{x:.1}" y="{y:.1}" font-family="sans-serif" font-size="{size}">{s}</text>"#
    );
}

/// Effector coordinates over time: one panel per (effector, axis); robot solid, reference dashed.
pub fn effectors(samples: &[Sample], names: &[&str]) -> String {
    let (panel_w, panel_h, margin) = (300.0, 120.0, 50.0);
    let width = margin + 3.0 * (panel_w + margin);
    let height = margin + names.len() as f64 * (panel_h + margin);
    let mut svg = format!(
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" viewBox="0 0 {width} {height}">"#
    );
    svg.push_str("\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n");
    text(
        &mut svg,
        margin,
        20.0,
        "Effector positions in the world (m) vs time (s): robot solid, scaled reference dashed",
        13,
    );
    let (t0, t1) = (
        samples.first().map_or(0.0, |s| s.time),
        samples.last().map_or(1.0, |s| s.time),
    );
    for (e, name) in names.iter().enumerate() {
        for axis in 0..3 {
            let left = margin + axis as f64 * (panel_w + margin);
            let top = margin + e as f64 * (panel_h + margin);
            let values = samples.iter().flat_map(|s| {
                std::iter::once(s.effectors[e].0[axis]).chain(s.effectors[e].1.map(|r| r[axis]))
            });
            let (lo, hi) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
                (lo.min(v), hi.max(v))
            });
            let (lo, hi) = if hi - lo < 1e-3 {
                (lo - 0.01, hi + 0.01)
            } else {
                (lo, hi)
            };
            let x = |t: f64| left + (t - t0) / (t1 - t0).max(1e-9) * panel_w;
            let y = |v: f64| top + panel_h - (v - lo) / (hi - lo) * panel_h;
            let _ = writeln!(
                svg,
                r##"<rect x="{left}" y="{top}" width="{panel_w}" height="{panel_h}" fill="none" stroke="#999"/>"##
            );
            text(
                &mut svg,
                left,
                top - 6.0,
                &format!("{name} {} [{lo:.3}, {hi:.3}] m", ["x", "y", "z"][axis]),
                11,
            );
            let robot: Vec<_> = samples
                .iter()
                .map(|s| (x(s.time), y(s.effectors[e].0[axis])))
                .collect();
            let reference: Vec<_> = samples
                .iter()
                .filter_map(|s| s.effectors[e].1.map(|r| (x(s.time), y(r[axis]))))
                .collect();
            polyline(&mut svg, &reference, COLORS[e % COLORS.len()], true);
            polyline(&mut svg, &robot, COLORS[e % COLORS.len()], false);
        }
    }
    svg.push_str("</svg>\n");
    svg
}

/// The floor seen from above: footprints (each distinct placement once) and the CoM path.
pub fn com_and_feet(samples: &[Sample]) -> String {
    let points = samples.iter().flat_map(|s| {
        std::iter::once(s.com).chain(s.footprints.iter().flat_map(|(_, o)| o.iter().copied()))
    });
    let (mut x0, mut x1, mut y0, mut y1) = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    for [x, y] in points {
        (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
    }
    let pad = 0.02;
    let scale = 2000.0; // px per metre
    let (w, h) = ((x1 - x0 + 2.0 * pad) * scale, (y1 - y0 + 2.0 * pad) * scale);
    // World x forward is drawn upward, y left is drawn leftward.
    let px = |y: f64| (y1 + pad - y) * scale;
    let py = |x: f64| (x1 + pad - x) * scale;
    let mut svg = format!(
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{:.0}" height="{:.0}" viewBox="0 0 {w:.1} {:.1}">"#,
        w,
        h + 40.0,
        h + 40.0
    );
    svg.push_str("\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n");
    let mut drawn: Vec<Vec<[f64; 2]>> = Vec::new();
    for s in samples {
        for (foot, outline) in &s.footprints {
            let seen = drawn.iter().any(|d| {
                d.iter()
                    .zip(outline)
                    .all(|(a, b)| (a[0] - b[0]).abs() + (a[1] - b[1]).abs() < 2e-3)
            });
            if seen {
                continue;
            }
            drawn.push(outline.clone());
            let color = if *foot == Side::Right {
                "#d62728"
            } else {
                "#1f77b4"
            };
            let pts: Vec<String> = outline
                .iter()
                .map(|[x, y]| format!("{:.1},{:.1}", px(*y), py(*x)))
                .collect();
            let _ = writeln!(
                svg,
                r#"<polygon points="{}" fill="{color}" fill-opacity="0.08" stroke="{color}" stroke-width="0.8"/>"#,
                pts.join(" ")
            );
        }
    }
    let com: Vec<_> = samples
        .iter()
        .map(|s| (px(s.com[1]), py(s.com[0])))
        .collect();
    polyline(&mut svg, &com, "black", false);
    text(
        &mut svg,
        5.0,
        h + 25.0,
        "CoM ground projection (black) and soles on the ground (red right, blue left); x up, y left",
        11,
    );
    svg.push_str("</svg>\n");
    svg
}

/// Two bands over time: the human's support and the robot's phase.
pub fn phases(samples: &[Sample]) -> String {
    let (width, band, margin) = (900.0, 30.0, 110.0);
    let (t0, t1) = (
        samples.first().map_or(0.0, |s| s.time),
        samples.last().map_or(1.0, |s| s.time),
    );
    let x = |t: f64| margin + (t - t0) / (t1 - t0).max(1e-9) * width;
    let color = |label: &str| match label {
        "Double" | "DS" => "#cccccc",
        "Right" | "RS" => "#d62728",
        "Left" | "LS" => "#1f77b4",
        "Airborne" => "#ffffff",
        _ => "#ffbf00",
    };
    let mut svg = format!(
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{}" height="130" viewBox="0 0 {} 130">"#,
        width + margin + 20.0,
        width + margin + 20.0
    );
    svg.push_str("\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n");
    for (row, label) in [(0, "human"), (1, "robot")] {
        let top = 20.0 + row as f64 * (band + 10.0);
        text(&mut svg, 5.0, top + 20.0, label, 12);
        let mut start = 0;
        for i in 1..=samples.len() {
            let key = |s: &Sample| {
                if row == 0 {
                    s.human.to_string()
                } else {
                    short(&s.robot)
                }
            };
            if i == samples.len() || key(&samples[i]) != key(&samples[start]) {
                let end = samples.get(i).map_or(t1, |s| s.time);
                let k = key(&samples[start]);
                let _ = writeln!(
                    svg,
                    r#"<rect x="{:.1}" y="{top}" width="{:.1}" height="{band}" fill="{}" stroke="none"/>"#,
                    x(samples[start].time),
                    (x(end) - x(samples[start].time)).max(0.5),
                    color(&k)
                );
                start = i;
            }
        }
    }
    text(
        &mut svg,
        margin,
        120.0,
        &format!("time {t0:.2}–{t1:.2} s: grey DS, red RS, blue LS, amber transition step"),
        11,
    );
    svg.push_str("</svg>\n");
    svg
}

fn short(phase: &str) -> String {
    match phase {
        "DS" | "RS" | "LS" => phase.to_owned(),
        _ => "transition".to_owned(),
    }
}
