"""``physics.svg``: a playback over time, four panels sharing the time axis: the base's tilt
(°), the measured ZMP's margin inside the soles in contact and the CoM's inside the soles'
contact hull (mm; below 0 it is outside), and each sole's normal force (N). One line style per model (nominal solid, weak dashed); the verdicts in
the title. Plain SVG, no plotting library."""

from __future__ import annotations

import math
import os
from pathlib import Path
from typing import List, Sequence

WIDTH, PANEL, MARGIN = 900, 150, 50
#: Points per line at most (the series is thinned evenly beyond).
MAX_POINTS = 1500
#: (title, series column, scale to the plotted unit, colours per sole or one)
PANELS = [
    ("base tilt (°)", [2], 1.0),
    ("measured ZMP margin in the soles in contact (mm)", [6], 1000.0),
    ("CoM margin in the contact hull (mm)", [3], 1000.0),
    ("sole force (N): left blue, right orange", [4, 5], 1.0),
]
COLOURS = ["#1f77b4", "#ff7f0e"]


def _polyline(points: Sequence[tuple], colour: str, dashed: bool) -> str:
    dash = ' stroke-dasharray="5,3"' if dashed else ""
    coords = " ".join(f"{x:.1f},{y:.1f}" for x, y in points)
    return f'<polyline fill="none" stroke="{colour}" stroke-width="1.2"{dash} points="{coords}"/>'


def render(verdicts: List) -> str:
    """The SVG text for the playbacks of one run (each a :class:`~taskstack.sim.checks.Verdict`)."""
    series = [v.playback.series for v in verdicts if v.playback.series]
    height = MARGIN + len(PANELS) * (PANEL + MARGIN)
    title = "; ".join(f"{v.model}: {'PASS' if v.passed else 'FAIL'}" for v in verdicts)
    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{WIDTH}" height="{height}" font-family="sans-serif" font-size="12">',
           f'<text x="{MARGIN}" y="20" font-size="14">{verdicts[0].out_dir if verdicts else ""} — {title}</text>']
    if not series:
        return "\n".join(out + ["</svg>"])
    t0 = min(s[0][0] for s in series)
    t1 = max(s[-1][0] for s in series)
    span = max(t1 - t0, 1e-9)
    for p, (name, columns, scale) in enumerate(PANELS):
        top = MARGIN + p * (PANEL + MARGIN)
        values = [r[c] * scale for s in series for r in s for c in columns if math.isfinite(r[c])]
        lo, hi = (min(values + [0.0]), max(values + [0.0])) if values else (0.0, 1.0)
        hi = hi if hi > lo else lo + 1.0
        y = lambda v: top + PANEL - (v - lo) / (hi - lo) * PANEL  # noqa: E731
        x = lambda t: MARGIN + (t - t0) / span * (WIDTH - 2 * MARGIN)  # noqa: E731
        out.append(f'<rect x="{MARGIN}" y="{top}" width="{WIDTH - 2 * MARGIN}" height="{PANEL}" fill="none" stroke="#ccc"/>')
        out.append(f'<text x="{MARGIN}" y="{top - 6}">{name}</text>')
        out.append(f'<text x="{MARGIN - 4}" y="{top + 10}" text-anchor="end">{hi:.0f}</text>')
        out.append(f'<text x="{MARGIN - 4}" y="{top + PANEL}" text-anchor="end">{lo:.0f}</text>')
        out.append(f'<line x1="{MARGIN}" x2="{WIDTH - MARGIN}" y1="{y(0):.1f}" y2="{y(0):.1f}" stroke="#999" stroke-width="0.5"/>')
        for k, s in enumerate(series):
            for j, c in enumerate(columns):
                every = max(1, len(s) // MAX_POINTS)
                pts = [(x(r[0]), y(r[c] * scale)) for r in s[::every] if math.isfinite(r[c])]
                colour = COLOURS[j] if len(columns) > 1 else "#333"
                out.append(_polyline(pts, colour, dashed=k > 0))
    out.append(f'<text x="{WIDTH - MARGIN}" y="{height - 15}" text-anchor="end">time (s), {t0:.1f}–{t1:.1f}</text>')
    out.append("</svg>")
    return "\n".join(out)


def write_plot(path: Path, verdicts: List) -> None:
    """Writes :func:`render` to ``path`` whole: through ``path.partial`` and a rename."""
    partial = Path(str(path) + ".partial")
    partial.write_text(render(verdicts))
    os.replace(partial, path)
