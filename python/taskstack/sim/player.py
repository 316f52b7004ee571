"""Plays a joint trajectory on a :class:`~taskstack.sim.model.PhysicsModel` and measures it.

The robot starts standing in the trajectory's first posture: its soles flat on the floor
(those within 5 mm and 2° of the lower one are both put down, the rest hang), the right sole's
origin over the world origin. It holds that posture for ``settle`` seconds, plays the
trajectory (targets interpolated linearly at every 1 ms step; a target faster than its joint
can follow is played as written, the servo's torque limit and damping slow the joint), then
holds the last posture for ``hold`` seconds.

Measured at every step (see :mod:`taskstack.sim.checks` for what is judged):

* the base's height and tilt (angle of its z axis from the vertical);
* per sole: the normal force of its floor contacts, its tilt while it touches, its slip and
  turn while it carries at least 20 % of the weight (the sliding of the contact point under it
  since the load came on: the world motion of the sole-fixed point that was the centre of
  pressure then; the yaw change since then);
* the measured ZMP (the centre of pressure of the floor's forces on the soles) and its signed
  distance to the convex hull of the outlines of the soles in contact: where the floor pushes,
  which a dynamic motion keeps inside the support while its CoM may pass outside it, and which
  a foot rolling onto an edge brings to that edge;
* the CoM's signed distance to the convex hull of the soles' floor contact points, over the
  whole run and during the final hold (where a robot standing still has it inside);
* the first body other than a sole touching the floor.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Dict, List, Optional, Sequence

import mujoco
import numpy as np

from .geometry import convex_hull, signed_distance
from .model import PhysicsModel

#: A foot carrying at least this share of the weight is loaded (slip and turn are measured).
LOADED_SHARE = 0.2
#: A contact pushing less than this (N) is not a contact.
CONTACT_FORCE = 1.0
#: Soles within this height (m) and tilt (rad) of the lower one start on the floor together.
BOTH_FEET_HEIGHT, BOTH_FEET_TILT = 0.005, math.radians(2.0)
#: A measured ZMP closer than this (m) to the edge of the soles in contact counts as on the edge.
ZMP_EDGE_M = 0.002
#: Period of the recorded time series (s).
SERIES_PERIOD = 0.01
#: A target this far (rad) beyond a joint limit is not a violation: joints.csv rounds to six
#: decimals, so a target at its limit may read up to 5e-7 rad beyond it.
LIMIT_SLACK = 1e-6
#: Frames a second of the simulated robot recorded for the viewer.
DRAW_RATE = 30


@dataclass
class Playback:
    """What a playback measured (SI units; angles in degrees where named ``_deg``)."""

    duration: float
    #: Seconds of the run's constant final stretch beyond the ones played (``checks.shorten_tail``).
    tail_left_out_s: float = 0.0
    fell_at: Optional[float] = None
    fall_reason: str = ""
    max_tilt_deg: float = 0.0
    max_foot_tilt_deg: float = 0.0
    max_slip_m: float = 0.0
    max_turn_deg: float = 0.0
    #: Share of the play and the hold with the measured ZMP at least ``ZMP_EDGE_M`` inside the
    #: soles in contact (of the steps with a sole in contact); its smallest margin (m).
    zmp_inside_share: float = 1.0
    min_zmp_margin_m: float = math.inf
    #: Share of the play and the hold with the CoM ground point inside the contact hull, and
    #: the same share over the final hold alone (the robot ends standing still).
    com_inside_share: float = 1.0
    com_inside_share_hold: float = 1.0
    min_com_margin_m: float = math.inf
    non_foot_contact: Optional[str] = None
    non_foot_contact_at: Optional[float] = None
    limit_violations: int = 0
    #: The largest |target − angle| (rad) of any joint after the settle, its joint and time: how
    #: far the servos were from the plan.
    max_tracking_error: float = 0.0
    max_tracking_joint: str = ""
    max_tracking_time: float = 0.0
    #: Rows every 10 ms: time, base height, base tilt (deg), CoM margin (m), left and right
    #: sole normal force (N), measured ZMP margin (m; -inf without a sole on the floor).
    series: List[Sequence[float]] = field(default_factory=list)
    #: The simulated robot for a viewer, ``DRAW_RATE`` frames a second from ``draw_t0`` (s):
    #: per frame the drawn bodies' origins (x y z in integer mm, world), and the segments
    #: (pairs of indices into a frame's points) that draw the robot.
    draw_t0: float = 0.0
    draw_frames: List[List[int]] = field(default_factory=list)
    draw_segments: List[Sequence[int]] = field(default_factory=list)


def _tilt_deg(xmat: np.ndarray) -> float:
    """Angle (°) of a body's z axis from the vertical, from its row-major rotation matrix."""
    return math.degrees(math.acos(max(-1.0, min(1.0, float(xmat[8])))))


def _zmp_margin(pm: PhysicsModel, data: mujoco.MjData, force: List[float], cop: List[np.ndarray]) -> float:
    """Signed distance (m, > 0 inside) of the measured ZMP (the centre of pressure of the soles'
    floor forces) to the hull of the outlines of the soles in contact; -inf with none."""
    on = [side for side in range(2) if force[side] > 0]
    if not on:
        return -math.inf
    zmp = sum(cop[side] for side in on)[:2] / sum(force[side] for side in on)
    corners = []
    for side in on:
        body = pm.sole_bodies[side]
        # The outline lies in the sole's x-y plane: its world x, y take the rotation's top-left
        # 2 x 2 block.
        R = data.xmat[body].reshape(3, 3)[:2, :2]
        corners.append(pm.sole_outlines[side] @ R.T + data.xpos[body][:2])
    # One sole: its outline, kept counter-clockwise (``model.build``), is its hull.
    hull = corners[0] if len(corners) == 1 else convex_hull(np.vstack(corners))
    return signed_distance(hull, zmp)


def drawing(pm: PhysicsModel, data: mujoco.MjData):
    """The bodies drawn (the links: at least 1 g, and the soles) and the segments joining each
    to its nearest drawn ancestor, for the posture in ``data``."""
    m = pm.model
    keep = [b for b in range(1, m.nbody) if m.body_mass[b] >= 0.001 or b in pm.sole_bodies]
    index = {b: i for i, b in enumerate(keep)}
    segments = []
    for b in keep:
        parent = int(m.body_parentid[b])
        while parent > 0 and parent not in index:
            parent = int(m.body_parentid[parent])
        if parent in index and np.linalg.norm(data.xpos[b] - data.xpos[parent]) >= 0.005:
            segments.append((index[parent], index[b]))
    return keep, segments


def place(pm: PhysicsModel, data: mujoco.MjData, q0: np.ndarray) -> None:
    """Sets the posture ``q0`` standing (module docs)."""
    m = pm.model
    data.qpos[:] = 0
    data.qpos[3] = 1.0
    pm.set_joints(data.qpos, q0)
    mujoco.mj_forward(m, data)
    soles = [(data.xpos[b].copy(), data.xmat[b].reshape(3, 3).copy()) for b in pm.sole_bodies]
    low = min(range(2), key=lambda i: soles[i][0][2])
    down = [
        i for i in range(2)
        if soles[i][0][2] - soles[low][0][2] <= BOTH_FEET_HEIGHT
        and math.acos(min(1.0, float(np.dot(soles[i][1][:, 2], soles[low][1][:, 2])))) <= BOTH_FEET_TILT
    ]
    normal = sum(soles[i][1][:, 2] for i in down)
    normal = normal / np.linalg.norm(normal)
    # The rotation taking the soles' mean normal to the vertical.
    axis = np.cross(normal, [0.0, 0.0, 1.0])
    angle = math.atan2(np.linalg.norm(axis), normal[2])
    quat = np.zeros(4)
    if np.linalg.norm(axis) > 1e-12:
        mujoco.mju_axisAngle2Quat(quat, axis / np.linalg.norm(axis), angle)
    else:
        quat[:] = [1, 0, 0, 0]
    data.qpos[3:7] = quat
    mujoco.mj_forward(m, data)
    lowest = min(data.xpos[pm.sole_bodies[i]][2] for i in down)
    right = data.xpos[pm.sole_bodies[1]]
    data.qpos[0:3] = [-right[0], -right[1], -lowest]
    data.qvel[:] = 0
    mujoco.mj_forward(m, data)


def play(
    pm: PhysicsModel,
    times: np.ndarray,
    targets: np.ndarray,
    settle: float = 1.0,
    hold: float = 1.0,
) -> Playback:
    """Plays ``targets`` (N x len(pm.columns), rad) at ``times`` (N, s, increasing) on ``pm``."""
    m = pm.model
    data = mujoco.MjData(m)
    out = Playback(duration=float(times[-1] - times[0]))
    # A target at a limit is written rounded to joints.csv's six decimals: up to 5e-7 beyond.
    slack = LIMIT_SLACK
    out.limit_violations = int(np.sum((targets < pm.lower - slack) | (targets > pm.upper + slack)))
    targets = np.clip(targets, pm.lower, pm.upper)
    place(pm, data, targets[0])
    dt = m.opt.timestep
    steps_settle = int(round(settle / dt))
    steps_play = int(math.ceil((times[-1] - times[0]) / dt))
    steps = steps_settle + steps_play + int(round(hold / dt))
    weight = pm.total_mass * 9.81
    h0 = float(data.xpos[pm.base_body][2])
    force6 = np.zeros(6)
    anchor: List[Optional[tuple]] = [None, None]  # (sole-local CoP, its world start, start yaw)
    # Steps of the play and the hold: CoM inside, ZMP inside, with a sole in contact; the hold's.
    inside = zmp_inside = zmp_steps = hold_inside = hold_steps = 0
    hold_from = steps_settle + steps_play
    every = int(round(SERIES_PERIOD / dt))
    drawn, out.draw_segments = drawing(pm, data)
    draw_every = int(round(1.0 / DRAW_RATE / dt))
    out.draw_t0 = float(times[0] + (1 - steps_settle) * dt)
    clock = times[0] + (np.arange(steps) - steps_settle + 1) * dt
    tau = np.clip(clock, times[0], times[-1])
    goals = np.column_stack([np.interp(tau, times, targets[:, c]) for c in range(targets.shape[1])])
    for k in range(steps):
        t = float(clock[k])
        ctrl = goals[k]
        data.ctrl[:] = ctrl
        mujoco.mj_step(m, data)
        base_tilt = _tilt_deg(data.xmat[pm.base_body])
        height = float(data.xpos[pm.base_body][2])
        out.max_tilt_deg = max(out.max_tilt_deg, base_tilt)
        if height < 0.6 * h0 or base_tilt > 45.0:
            out.fell_at = t
            out.fall_reason = (f"base at {height:.3f} m, under 60 % of {h0:.3f} m" if height < 0.6 * h0
                               else f"base tilted {base_tilt:.1f}°")
            break
        force = [0.0, 0.0]
        cop = [np.zeros(3), np.zeros(3)]
        points = []
        for c in range(data.ncon):
            con = data.contact[c]
            if pm.floor_geom not in (con.geom1, con.geom2):
                continue
            other = con.geom2 if con.geom1 == pm.floor_geom else con.geom1
            mujoco.mj_contactForce(m, data, c, force6)
            if force6[0] < CONTACT_FORCE:
                continue
            side = pm.sole_geoms.get(int(other))
            if side is None:
                if out.non_foot_contact is None:
                    out.non_foot_contact = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, int(m.geom_bodyid[other]))
                    out.non_foot_contact_at = t
                continue
            force[side] += force6[0]
            cop[side] += force6[0] * con.pos
            points.append(con.pos[:2].copy())
        for side, body in enumerate(pm.sole_bodies):
            R = data.xmat[body].reshape(3, 3)
            if force[side] > 0:
                out.max_foot_tilt_deg = max(out.max_foot_tilt_deg, _tilt_deg(data.xmat[body]))
            if force[side] >= LOADED_SHARE * weight:
                yaw = math.atan2(R[1, 0], R[0, 0])
                if anchor[side] is None:
                    p = cop[side] / force[side]
                    anchor[side] = (R.T @ (p - data.xpos[body]), p, yaw)
                local, start, yaw0 = anchor[side]
                now = R @ local + data.xpos[body]
                out.max_slip_m = max(out.max_slip_m, float(np.linalg.norm((now - start)[:2])))
                turn = (yaw - yaw0 + math.pi) % (2 * math.pi) - math.pi
                out.max_turn_deg = max(out.max_turn_deg, abs(math.degrees(turn)))
            else:
                anchor[side] = None
        if k >= steps_settle:
            error = np.abs(data.qpos[pm.qpos_address] - ctrl)
            worst = int(np.argmax(error))
            if error[worst] > out.max_tracking_error:
                out.max_tracking_error = float(error[worst])
                out.max_tracking_joint, out.max_tracking_time = pm.columns[worst], t
        # Body 1 is the floating root: its subtree is the whole robot.
        com = data.subtree_com[1][:2]
        margin = signed_distance(convex_hull(np.array(points)) if points else np.zeros((0, 2)), com)
        zmp_margin = _zmp_margin(pm, data, force, cop)
        if k >= steps_settle:
            inside += margin >= 0
            out.min_com_margin_m = min(out.min_com_margin_m, margin)
            if math.isfinite(zmp_margin):
                zmp_steps += 1
                zmp_inside += zmp_margin >= ZMP_EDGE_M
                out.min_zmp_margin_m = min(out.min_zmp_margin_m, zmp_margin)
        if k >= hold_from:
            hold_steps += 1
            hold_inside += margin >= 0
        if k % draw_every == 0:
            out.draw_frames.append(np.round(data.xpos[drawn] * 1000).astype(int).ravel().tolist())
        if k % every == 0:
            out.series.append((t, height, base_tilt, margin, force[0], force[1], zmp_margin))
    out.com_inside_share = inside / max(1, k + 1 - steps_settle)
    out.zmp_inside_share = zmp_inside / zmp_steps if zmp_steps else 0.0
    out.com_inside_share_hold = hold_inside / hold_steps if hold_steps else 0.0
    return out
