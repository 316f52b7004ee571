"""Adds a playback's simulated robot to a run's ``view.html`` (written by ``taskstack
imitate``), which then draws it in gray beside the plan: the page's data gains
``const SIM = {t0, rate, frames, segments, model, verdict}`` before its ``const TAIL``; a
check run again replaces it. Written whole: through ``view.html.partial`` and a rename."""

from __future__ import annotations

import json
import os
import re
from pathlib import Path

from .player import DRAW_RATE

MARK = "\nconst TAIL = "


def add_simulation(page: Path, verdict) -> bool:
    """Splices ``verdict``'s simulated robot into ``page``; False when the page is not a
    taskstack viewer (left as it is)."""
    text = page.read_text()
    if MARK not in text:
        return False
    text = re.sub(r"\nconst SIM = .*?;\n(?=const TAIL = )", "\n", text, flags=re.S)
    p = verdict.playback
    sim = {
        "t0": round(p.draw_t0, 4),
        "rate": DRAW_RATE,
        "frames": p.draw_frames,
        "segments": p.draw_segments,
        "model": verdict.model,
        "verdict": "PASS" if verdict.passed else "FAIL: " + "; ".join(verdict.failures),
    }
    text = text.replace(MARK, f"\nconst SIM = {json.dumps(sim, separators=(',', ':'))};{MARK}", 1)
    partial = Path(str(page) + ".partial")
    partial.write_text(text)
    os.replace(partial, page)
    return True
