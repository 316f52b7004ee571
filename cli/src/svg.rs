//! A minimal SVG writer for the run plots: charts with axes, ticks, units and legends. No
//! plotting dependency: the plots are a few lines and rectangles.

use std::fmt::Write as _;

/// An SVG document being written (pixels, y down).
pub(crate) struct Svg {
    body: String,
    width: f64,
    height: f64,
}

impl Svg {
    pub(crate) fn new(width: f64, height: f64) -> Self {
        let mut svg = Self {
            body: String::new(),
            width,
            height,
        };
        svg.rect(0.0, 0.0, width, height, "white", 1.0);
        svg
    }

    pub(crate) fn finish(self) -> String {
        format!(
            "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" viewBox=\"0 0 {w} {h}\" font-family=\"sans-serif\">\n{}</svg>\n",
            self.body,
            w = self.width,
            h = self.height
        )
    }

    pub(crate) fn text(&mut self, x: f64, y: f64, size: u32, anchor: &str, text: &str) {
        let text = text.replace('&', "&amp;").replace('<', "&lt;");
        let _ = writeln!(
            self.body,
            r#"<text x="{x:.1}" y="{y:.1}" font-size="{size}" text-anchor="{anchor}">{text}</text>"#
        );
    }

    pub(crate) fn rect(&mut self, x: f64, y: f64, w: f64, h: f64, fill: &str, opacity: f64) {
        let _ = writeln!(
            self.body,
            r#"<rect x="{x:.1}" y="{y:.1}" width="{w:.1}" height="{h:.1}" fill="{fill}" fill-opacity="{opacity}"/>"#
        );
    }

    pub(crate) fn line(&mut self, a: (f64, f64), b: (f64, f64), color: &str, width: f64) {
        let _ = writeln!(
            self.body,
            r#"<line x1="{:.1}" y1="{:.1}" x2="{:.1}" y2="{:.1}" stroke="{color}" stroke-width="{width}"/>"#,
            a.0, a.1, b.0, b.1
        );
    }

    /// A polyline; `None` points break it.
    pub(crate) fn path(
        &mut self,
        points: &[Option<(f64, f64)>],
        color: &str,
        width: f64,
        dashed: bool,
    ) {
        let mut d = String::new();
        let mut pen_down = false;
        for p in points {
            match p {
                Some((x, y)) => {
                    let _ = write!(d, "{}{x:.1},{y:.1} ", if pen_down { "L" } else { "M" });
                    pen_down = true;
                }
                None => pen_down = false,
            }
        }
        if d.is_empty() {
            return;
        }
        let dash = if dashed {
            r#" stroke-dasharray="5 3""#
        } else {
            ""
        };
        let _ = writeln!(
            self.body,
            r#"<path d="{d}" fill="none" stroke="{color}" stroke-width="{width}"{dash}/>"#
        );
    }

    pub(crate) fn polygon(&mut self, points: &[(f64, f64)], fill: &str, stroke: &str) {
        let mut p = String::new();
        for (x, y) in points {
            let _ = write!(p, "{x:.1},{y:.1} ");
        }
        let _ = writeln!(
            self.body,
            r#"<polygon points="{p}" fill="{fill}" fill-opacity="0.25" stroke="{stroke}" stroke-width="1"/>"#
        );
    }

    /// A legend: one swatch and label per entry `(label, color, dashed)`, in a row from `(x, y)`.
    pub(crate) fn legend(&mut self, x: f64, y: f64, entries: &[(&str, &str, bool)]) {
        let mut at = x;
        for (label, color, dashed) in entries {
            self.path(
                &[Some((at, y - 4.0)), Some((at + 18.0, y - 4.0))],
                color,
                2.5,
                *dashed,
            );
            self.text(at + 22.0, y, 11, "start", label);
            at += 40.0 + 7.0 * label.chars().count() as f64;
        }
    }
}

/// A chart area mapping data coordinates to pixels.
pub(crate) struct Axes {
    pub(crate) left: f64,
    pub(crate) top: f64,
    pub(crate) width: f64,
    pub(crate) height: f64,
    pub(crate) x: (f64, f64),
    pub(crate) y: (f64, f64),
}

impl Axes {
    pub(crate) fn px(&self, x: f64) -> f64 {
        self.left + (x - self.x.0) / (self.x.1 - self.x.0) * self.width
    }

    pub(crate) fn py(&self, y: f64) -> f64 {
        self.top + self.height - (y - self.y.0) / (self.y.1 - self.y.0) * self.height
    }

    pub(crate) fn point(&self, x: f64, y: f64) -> (f64, f64) {
        (self.px(x), self.py(y))
    }

    /// The frame, grid, tick labels and axis labels (with units).
    pub(crate) fn draw(&self, svg: &mut Svg, x_label: &str, y_label: &str) {
        for t in ticks(self.x.0, self.x.1) {
            let x = self.px(t);
            svg.line((x, self.top), (x, self.top + self.height), "#e4e4e4", 1.0);
            svg.line(
                (x, self.top + self.height),
                (x, self.top + self.height + 4.0),
                "#444",
                1.0,
            );
            svg.text(x, self.top + self.height + 16.0, 10, "middle", &label(t));
        }
        for t in ticks(self.y.0, self.y.1) {
            let y = self.py(t);
            svg.line((self.left, y), (self.left + self.width, y), "#e4e4e4", 1.0);
            svg.line((self.left - 4.0, y), (self.left, y), "#444", 1.0);
            svg.text(self.left - 7.0, y + 3.5, 10, "end", &label(t));
        }
        let (l, t, r, b) = (
            self.left,
            self.top,
            self.left + self.width,
            self.top + self.height,
        );
        svg.path(
            &[
                Some((l, t)),
                Some((r, t)),
                Some((r, b)),
                Some((l, b)),
                Some((l, t)),
            ],
            "#444",
            1.0,
            false,
        );
        svg.text((l + r) / 2.0, b + 32.0, 11, "middle", x_label);
        let _ = writeln!(
            svg.body,
            r#"<text x="{x:.1}" y="{y:.1}" font-size="11" text-anchor="middle" transform="rotate(-90 {x:.1} {y:.1})">{y_label}</text>"#,
            x = l - 40.0,
            y = (t + b) / 2.0
        );
    }
}

/// Round tick values covering `lo..=hi`: the step of 1, 2 or 5 × 10^k that gives closest to six
/// intervals.
pub(crate) fn ticks(lo: f64, hi: f64) -> Vec<f64> {
    let span = hi - lo;
    if !(span.is_finite() && span > 0.0) {
        return vec![lo];
    }
    let power = 10f64.powf((span / 6.0).log10().floor());
    let step = [0.5, 1.0, 2.0, 5.0, 10.0]
        .iter()
        .map(|m| m * power)
        .min_by(|a, b| {
            ((span / a) - 6.0)
                .abs()
                .total_cmp(&((span / b) - 6.0).abs())
        })
        .unwrap_or(power);
    let first = (lo / step - 1e-9).ceil() as i64;
    let last = (hi / step + 1e-9).floor() as i64;
    (first..=last).map(|k| k as f64 * step).collect()
}

pub(crate) fn label(value: f64) -> String {
    let text = format!("{:.3}", value);
    let text = text.trim_end_matches('0').trim_end_matches('.');
    if text == "-0" {
        "0".into()
    } else {
        text.into()
    }
}

/// `(lo, hi)` of the values, widened by 5 % (and to at least `min_span`) so lines clear the frame.
pub(crate) fn range(values: impl Iterator<Item = f64>, min_span: f64) -> (f64, f64) {
    let (lo, hi) = values
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
    if lo > hi {
        return (0.0, min_span);
    }
    let pad = ((hi - lo) * 0.05).max((min_span - (hi - lo)).max(0.0) / 2.0);
    (lo - pad, hi + pad)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_are_round_and_inside() {
        // 0..1.3: steps 0.1, 0.2, 0.5 give 13, 6.5 and 2.6 intervals; 0.2 is closest to six.
        let t = ticks(0.0, 1.3);
        assert_eq!(t.len(), 7);
        assert!((t[6] - 1.2).abs() < 1e-12);
        // −0.02..0.095 (span 0.115): 0.01, 0.02, 0.05 give 11.5, 5.75, 2.3 intervals → 0.02.
        let t = ticks(-0.02, 0.095);
        assert_eq!(t.len(), 6);
        assert!((t[0] + 0.02).abs() < 1e-12 && (t[5] - 0.08).abs() < 1e-12);
        assert_eq!(label(0.30000000000000004), "0.3");
        assert_eq!(label(-0.0), "0");
    }
}
