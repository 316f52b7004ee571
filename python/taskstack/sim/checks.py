"""The checks of a playback, their thresholds, and the verdict of a run.

A run is played with at most ``TAIL_KEPT_S`` of a final stretch of constant targets (a run's
hold: a robot at rest under constant targets stays at rest, and a long hold would only dilute
the shares below), then the check's own hold. It passes when, over the trajectory and the
holds:

==========================  ====================================================================
``fall``                    the base stays above 60 % of its standing height and within 45° of
                            upright
``foot_tilt_deg``           a sole touching the floor tilts at most 5° (more is a foot rocking
                            on an edge)
``slip_m``                  a loaded sole (≥ 20 % of the weight) slides at most 5 mm under its
                            centre of pressure
``turn_deg``                a loaded sole turns at most 2° about the vertical
``zmp_inside_share``        the measured ZMP (the centre of pressure of the floor's forces on
                            the soles) is at least 2 mm inside the outline of the soles in
                            contact at least 99 % of the time: a dynamic motion may carry the
                            CoM outside the support, but the floor can only push inside it, and
                            a foot rolling onto an edge brings the ZMP to that edge
``com_inside_share_hold``   the CoM ground projection is inside the hull of the soles' floor
                            contacts at least 99 % of the final hold: the robot ends standing
                            still
``non_foot_contact``        nothing but the soles touches the floor
``limit_violations``        no target outside the URDF's joint limits (by more than the 1e-6 rad
                            of joints.csv's rounding)
==========================  ====================================================================

The same checks and thresholds as the physics judge of the project's CI; the CoM's share of
the whole run inside the contact hull is measured and reported (``com_inside_share``), not
judged: it is a criterion for standing still, which a dynamic walk fails by design.
"""

from __future__ import annotations

import csv
import math
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Dict, List, Optional

import numpy as np

from .. import _taskstack
from .model import PhysicsModel, build
from .player import ZMP_EDGE_M, Playback, play

#: Every check's threshold (units in the names).
THRESHOLDS = {
    "foot_tilt_deg": 5.0,
    "slip_m": 0.005,
    "turn_deg": 2.0,
    "zmp_inside_share": 0.99,
    "zmp_edge_m": ZMP_EDGE_M,
    "com_inside_share_hold": 0.99,
}
#: Seconds of a final stretch of constant targets that are played (see :func:`shorten_tail`).
TAIL_KEPT_S = 5.0


@dataclass
class Verdict:
    """One run on one model: pass or fail, each failed check said in words, the measures."""

    out_dir: str
    robot: str
    model: str
    passed: bool
    failures: List[str]
    playback: Playback

    def summary(self) -> str:
        p = self.playback
        head = f"{'PASS' if self.passed else 'FAIL'} {self.out_dir} {self.robot} {self.model:7}"
        measures = (f"tilt {p.max_foot_tilt_deg:4.1f}° slip {p.max_slip_m * 1000:5.1f} mm "
                    f"turn {p.max_turn_deg:4.1f}° ZMP inside {p.zmp_inside_share * 100:5.1f} % "
                    f"CoM inside {p.com_inside_share * 100:5.1f} %")
        return f"{head} {measures}" + (f"; {'; '.join(self.failures)}" if self.failures else "")

    def to_json(self) -> Dict:
        out = asdict(self)
        for bulky in ("series", "draw_frames", "draw_segments", "draw_t0"):
            out["playback"].pop(bulky)
        out["thresholds"] = THRESHOLDS
        return out


def judge(p: Playback) -> List[str]:
    """The failed checks of a playback, in words (empty: it passes)."""
    failures = []
    if p.fell_at is not None:
        failures.append(f"fell at {p.fell_at:.2f} s ({p.fall_reason})")
    if p.max_foot_tilt_deg > THRESHOLDS["foot_tilt_deg"]:
        failures.append(f"a sole on the floor tilted {p.max_foot_tilt_deg:.1f}° (> 5°)")
    if p.max_slip_m > THRESHOLDS["slip_m"]:
        failures.append(f"a loaded sole slid {p.max_slip_m * 1000:.1f} mm (> 5 mm)")
    if p.max_turn_deg > THRESHOLDS["turn_deg"]:
        failures.append(f"a loaded sole turned {p.max_turn_deg:.1f}° (> 2°)")
    if p.zmp_inside_share < THRESHOLDS["zmp_inside_share"]:
        failures.append(f"ZMP inside the soles {p.zmp_inside_share * 100:.1f} % of the time (< 99 %)")
    if p.fell_at is None and p.com_inside_share_hold < THRESHOLDS["com_inside_share_hold"]:
        failures.append(f"CoM inside the contact hull {p.com_inside_share_hold * 100:.1f} % of the final hold (< 99 %)")
    if p.non_foot_contact is not None:
        failures.append(f"{p.non_foot_contact} touched the floor at {p.non_foot_contact_at:.2f} s")
    if p.limit_violations:
        failures.append(f"{p.limit_violations} targets outside the joint limits")
    return failures


class InputError(ValueError):
    """A run folder or trajectory that cannot be checked."""


def read_trajectory(path: Path):
    """``joints.csv``: its column names, times (N) and joint angles (N x J)."""
    try:
        with open(path, newline="") as f:
            rows = list(csv.reader(f))
    except OSError as e:
        raise InputError(f"{path}: {e.strerror or e}") from e
    if len(rows) < 2 or not rows[0] or rows[0][0] != "time":
        raise InputError(f"{path}: not a joints.csv (a header time,<joints> and one row per frame)")
    try:
        data = np.array([[float(v) for v in row] for row in rows[1:] if row], dtype=float)
    except ValueError as e:
        raise InputError(f"{path}: {e}") from e
    if data.ndim != 2 or data.shape[1] != len(rows[0]) or not np.all(np.isfinite(data)):
        raise InputError(f"{path}: rows must have {len(rows[0])} finite numbers")
    if np.any(np.diff(data[:, 0]) <= 0):
        raise InputError(f"{path}: times must increase")
    return rows[0][1:], data[:, 0], data[:, 1:]


def robot_of(columns: List[str], robot: Optional[str] = None) -> str:
    """``robot`` if its joints are ``columns``; without one, the built-in robot whose they
    are."""
    for candidate in [robot] if robot else ["nao", "g1"]:
        try:
            variables = _taskstack.robot_description(candidate)["variables"]
        except (OSError, ValueError) as e:
            raise InputError(f"robot {candidate}: {e}") from e
        if set(variables) == set(columns):
            return candidate
    if robot:
        raise InputError(f"joints {columns[:3]}…: not the joints of {robot}")
    raise InputError(f"joints {columns[:3]}…: neither the NAO's nor the G1's (a profile's run: --robot PROFILE.toml)")


def shorten_tail(times: np.ndarray, q: np.ndarray, keep: float = TAIL_KEPT_S):
    """``times`` and ``q`` with at most ``keep`` seconds of their final stretch of constant
    targets, and the seconds left out."""
    moving = np.nonzero(np.any(np.abs(q - q[-1]) > 1e-12, axis=1))[0]
    start = float(times[moving[-1] + 1]) if len(moving) else float(times[0])
    if float(times[-1]) - start <= keep:
        return times, q, 0.0
    kept = times <= start + keep + 1e-9
    return times[kept], q[kept], float(times[-1] - times[kept][-1])


_MODELS: Dict[tuple, PhysicsModel] = {}


def check_run(out_dir, weak: bool = False, settle: float = 1.0, hold: float = 1.0,
              robot: Optional[str] = None) -> Verdict:
    """Plays ``OUT_DIR/joints.csv`` (or a ``joints.csv`` path) on the nominal or weak model of
    ``robot`` (``"nao"``, ``"g1"``, a profile file; default: the built-in robot the header
    names), and judges it."""
    path = Path(out_dir)
    csv_path = path / "joints.csv" if path.is_dir() else path
    columns, times, q = read_trajectory(csv_path)
    times, q, left_out = shorten_tail(times, q)
    robot = robot_of(columns, robot)
    key = (robot, weak)
    if key not in _MODELS:
        _MODELS[key] = build(robot, weak)
    pm = _MODELS[key]
    order = [columns.index(c) for c in pm.columns]
    playback = play(pm, times, q[:, order], settle=settle, hold=hold)
    playback.tail_left_out_s = left_out
    failures = judge(playback)
    return Verdict(str(out_dir), robot, "weak" if weak else "nominal", not failures, failures, playback)
