"""taskstack: prioritized task-stack inverse kinematics and human-to-humanoid motion imitation.

Python bindings of the Rust crate ``taskstack``. Units everywhere: metres, radians, seconds.
World frame of an imitation: z up, x forward, the floor at z = 0, the first frame's right sole
at the origin.

* :func:`imitate_clip` imitates a clip file (BVH or Kinect v2 CSV) and returns an
  :class:`ImitationResult`: the numbers of ``taskstack imitate`` (its ``joints.csv``, the
  planned postures and their servo targets) with the
  floating base's pose and the soles' contacts, as numpy arrays.
* :class:`Imitator` imitates live, one human frame at a time; :func:`read_clip` reads a clip's
  human joint positions.
* :class:`Model` is a kinematic model (the NAO, the G1, any URDF): forward kinematics,
  Jacobians, centre of mass.
* :class:`Task` and :class:`TaskSet` are the prioritized solver on its own.

Errors are exceptions carrying the Rust message: ``ValueError`` for bad input,
``FileNotFoundError`` / ``OSError`` for files.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from os import PathLike
from typing import Any, Dict, List, Optional, Union

import numpy as np

from ._taskstack import Imitator, LiveSession, Model, Task, TaskSet, __version__, read_clip
from ._taskstack import imitate_clip as _imitate_clip

__all__ = [
    "ImitationResult",
    "Imitator",
    "LiveSession",
    "Model",
    "Task",
    "TaskSet",
    "imitate_clip",
    "read_clip",
    "__version__",
]


@dataclass(frozen=True)
class ImitationResult:
    """One imitated clip, a row per robot frame (N frames, J joints).

    Attributes:
        time: (N,) frame times in seconds (the clip's, then the held frames 1/120 s apart).
        q: (N, J) joint angles in radians, columns named by ``joint_names``: the planned
            postures (``motion.npz``'s ``dof_pos``).
        servo_targets: (N, J) what the robot's position servos are told (rad; ``joints.csv``):
            ``q`` plus the servos' static sag under each posture's load, for a robot whose
            profile states its servos' stiffness (the G1); equal to ``q`` otherwise (the NAO).
        joint_names: the J joint names (the robot model's variable order; for the G1 its
            URDF's joint order).
        root_pos: (N, 3) the floating base's origin in metres (world; NAO ``torso``, G1
            ``pelvis``).
        root_quat: (N, 4) the floating base's orientation, quaternion x y z w (world),
            without sign flips between frames.
        contacts: (N, 2) bool, the left and the right sole on the floor (within 1 mm).
        phase: the robot's support phase per frame (e.g. ``"DS"``, ``"DS to RS: CoM to RFoot"``).
        metrics: the run's metrics, the dict of ``taskstack imitate``'s ``metrics.json``.
    """

    time: np.ndarray
    q: np.ndarray
    servo_targets: np.ndarray
    joint_names: List[str]
    root_pos: np.ndarray
    root_quat: np.ndarray
    contacts: np.ndarray
    phase: List[str]
    metrics: Dict[str, Any]

    @property
    def fps(self) -> float:
        """The clip's own frame rate (Hz, rounded): its frame count over its duration."""
        m = self.metrics
        frames, duration = m["clip_frames"], m["clip_duration_s"]
        return float(round((frames - 1) / duration)) if frames > 1 and duration > 0 else 0.0


def imitate_clip(
    path: Union[str, PathLike],
    robot: str = "nao",
    hold: Union[float, str, None] = "auto",
    method: str = "poubel",
    walk: bool = False,
    dynamic_walk: bool = False,
    walking_arms: bool = False,
    step_distance: Optional[float] = None,
    step_heading: Optional[float] = None,
    step_pivot: Optional[float] = None,
    step_slide: Optional[float] = None,
    zmp_balance: Optional[bool] = None,
    damping: Optional[float] = None,
    damping_momentum: float = 0.0,
    offline: bool = False,
    velocity_fraction: Optional[float] = None,
    upper_body_fraction: Optional[float] = None,
    task_speed: Optional[float] = None,
    swing_speed: Optional[float] = None,
    tracking_speed: Optional[float] = None,
    tracking_acceleration: Optional[float] = None,
    iterations: int = 1,
    calibration: str = "auto",
    retargeting: str = "shift-both-feet",
    sway_shaping: bool = True,
) -> ImitationResult:
    """Imitate a motion clip with a humanoid; the run of ``taskstack imitate`` with the same
    options (same joint angles as its ``joints.csv``).

    Args:
        path: a BVH clip (CMU skeleton) or a Kinect v2 CSV.
        robot: ``"nao"``, ``"g1"`` or the path of a biped profile (TOML next to a URDF).
        hold: after the clip, hold the human's last pose: ``"auto"`` (until the robot has
            finished, at most 60 s) or seconds (0 to 3600).
        method: ``"poubel"`` (support phases and task tables) or ``"koenemann"``.
        walk: the robot's feet follow the human's footprints (quasi-static steps).
        dynamic_walk: experimental, walk with the pattern generator (implies ``walk``).
        walking_arms: experimental, with ``dynamic_walk``: the hands follow the human while
            the robot walks (for kinematic retargeting: the physics judge's weak NAO falls on
            the bundled walks).
        step_distance: with ``walk``, a robot foot farther than this from its target
            footprint (m) takes a step (the CLI's ``--step-distance``; default 0.02).
        step_heading: with ``walk``, a robot foot turned more than this from its target
            footprint's heading (rad) takes a step (default 0.087, 5°).
        step_pivot: with ``walk``, a human foot on the ground keeps the footprint it landed
            with until it has turned more than this (rad) or moved more than ``step_slide``
            (m, the human's world); then it is followed until it lifts (defaults 0.26 and
            0.05: a standing human's foot jitters by up to 12° and 3.2 cm in the bundled
            captures).
        step_slide: see ``step_pivot``.
        zmp_balance: balance that sees the arms' dynamics (the CLI's ``--zmp-balance`` /
            ``--no-zmp-balance``): the ZMP of the CoM and the arms' acceleration stays in the
            support polygon and their vertical moment below what friction holds, so fast
            hands do not tip the robot or turn a loaded foot; the hands then move at the
            robot's balanced speeds (NAO 1 m/s, 5 m/s²) unless ``tracking_speed`` and
            ``tracking_acceleration`` are given. ``None`` (default): on for a robot with
            balanced hand speeds (the NAO) unless ``dynamic_walk``; ``False``: the old, slower
            arms.
        damping: the solver's damping of near-singular levels (the CLI's ``--damping``;
            default: the robot's, NAO 0.02, G1 0.039).
        damping_momentum: share in [0, 1] of the last frame's joint step a damped level
            keeps instead of coming to rest (the CLI's ``--damping-momentum``; default 0).
        offline: read the whole clip first and time weight shifts ahead of the human.
        velocity_fraction: share of the rated joint velocity the legs may use, in (0, 1]
            (default: 0.1 with Poubel's method, the robot's with Koenemann's: NAO 0.1,
            G1 0.012).
        upper_body_fraction: the same for arms, head and torso (default: the robot's).
        task_speed: Poubel's method: fastest speed of any task's target, the CoM, feet, torso
            and the hands where ``tracking_speed`` does not set theirs (m/s; default: the
            robot's, NAO 0.15).
        swing_speed: ``method="koenemann"``: fastest speed of the swing foot's target (m/s;
            default: the robot's task speed).
        tracking_speed: fastest hand target speed (m/s; default: the robot's).
        tracking_acceleration: largest change of the hand targets' speed (m/s²; default: the
            robot's).
        iterations: solver iterations per frame (1 to 100).
        calibration: ``method="koenemann"``: ``"auto"``, ``"first-frame"`` or ``"ideal"``.
        retargeting: ``method="koenemann"``: ``"shift-both-feet"`` or ``"move-one-foot"``.
        sway_shaping: play ``servo_targets`` through the robot's sway shaper when its profile
            states a sway period (the G1; about half that period late, see
            ``taskstack::robots::sway``); ``False``: the commands as planned, for a robot with
            balance feedback of its own (the CLI's ``--no-sway-shaping``).

    Raises:
        FileNotFoundError, OSError: the clip or the profile cannot be read.
        ValueError: a malformed clip, an option out of range or of the other method (Poubel's
            ``walk`` … ``iterations`` with ``method="koenemann"``; ``calibration``,
            ``retargeting``, ``swing_speed`` with ``method="poubel"``), a frame the imitator
            refuses.
    """
    raw = _imitate_clip(
        str(path),
        robot=robot,
        hold=hold,
        method=method,
        walk=walk,
        dynamic_walk=dynamic_walk,
        walking_arms=walking_arms,
        step_distance=step_distance,
        step_heading=step_heading,
        step_pivot=step_pivot,
        step_slide=step_slide,
        zmp_balance=zmp_balance,
        damping=damping,
        damping_momentum=damping_momentum,
        offline=offline,
        velocity_fraction=velocity_fraction,
        upper_body_fraction=upper_body_fraction,
        task_speed=task_speed,
        swing_speed=swing_speed,
        tracking_speed=tracking_speed,
        tracking_acceleration=tracking_acceleration,
        iterations=iterations,
        calibration=calibration,
        retargeting=retargeting,
        sway_shaping=sway_shaping,
    )
    return ImitationResult(
        time=raw["time"],
        q=raw["q"],
        servo_targets=raw["servo_targets"],
        joint_names=list(raw["joint_names"]),
        root_pos=raw["root_pos"],
        root_quat=raw["root_quat"],
        contacts=raw["contacts"],
        phase=list(raw["phase"]),
        metrics=json.loads(raw["metrics_json"]),
    )
