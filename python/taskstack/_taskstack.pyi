"""Type stubs of the native module ``taskstack._taskstack`` (Rust, PyO3). Units: metres,
radians, seconds."""

from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

__version__: str

def imitate_clip(
    path: str,
    robot: str = "nao",
    hold: Union[float, str, None] = None,
    offline: bool = False,
    **options: Any,
) -> Dict[str, Any]:
    """The arrays of ``taskstack.ImitationResult`` as a dict, ``metrics_json`` a JSON string.
    ``options``: the keywords of ``taskstack.imitate_clip`` after ``offline``."""
    ...

def read_clip(path: str) -> Tuple[np.ndarray, List[str], np.ndarray]:
    """A clip's frame times (N, s), the human joint names (J) and their positions (N, J, 3;
    m, world z up; NaN where a joint is missing). Raises FileNotFoundError, OSError or
    ValueError as ``imitate_clip``."""
    ...

class Imitator:
    """A live imitator: one human frame in, one robot frame out (the thread that made it only)."""

    def __init__(self, robot: str = "nao", capture: str = "optical", **options: Any) -> None:
        """``robot``: "nao", "g1" or a profile path; ``capture``: "optical" (motion capture,
        120 Hz, mm noise) or "kinect" (depth camera, 30 Hz, cm noise), which sets the support
        detection's thresholds; ``options``: ``method``, ``walk``, ``dynamic_walk``,
        ``walking_arms``, ``step_distance``, ``step_heading``, ``step_pivot``, ``step_slide``,
        ``zmp_balance``, ``damping``, ``damping_momentum``, ``velocity_fraction``,
        ``upper_body_fraction``, ``task_speed``, ``swing_speed``,
        ``tracking_speed``, ``tracking_acceleration``, ``iterations``, ``calibration``,
        ``retargeting``, ``sway_shaping``, as ``taskstack.imitate_clip``'s (an unknown one is a
        TypeError; one of the other method's is a ValueError)."""
        ...
    @property
    def joint_names(self) -> List[str]:
        """The robot's joint names, in the order of ``q``."""
        ...
    @staticmethod
    def human_joint_names() -> List[str]:
        """The human joint names a frame may hold ("LShoulder", "RAnkle", ...)."""
        ...
    def step(
        self,
        time: float,
        positions: Union[Mapping[str, Sequence[float]], npt.ArrayLike],
        names: Optional[Sequence[str]] = None,
    ) -> Dict[str, Any]:
        """Imitates one human frame at ``time`` (s, increasing): ``positions`` a dict of human
        joint name -> (x, y, z) in metres (world: z up), or a (J, 3) array with its ``names``.
        Missing joints are left out of the dict, or NaN rows of the array.

        Returns a dict: ``time`` (s), ``q`` (J, rad), ``servo_targets`` (J, rad: ``q`` plus the
        static sag of the robot's position servos, what ``joints.csv`` holds; equal to ``q``
        for a robot whose profile states no servo stiffness), ``phase`` (str), ``root_pos``
        (3, m) and
        ``root_quat`` (4, x y z w) of the floating base, ``left_sole`` and ``right_sole``
        (4 x 4 world placements), ``com`` (3, m), ``contacts`` ([left, right] on the floor),
        ``awaiting_contact`` (feed the same frame again: a hand is being placed),
        ``effectors`` (the robot's "l_hand", "r_hand", "l_ankle", "r_ankle": (3,) world
        positions, m) and ``human_effectors`` (the scaled human's same joints, where known).

        Raises ValueError for an unknown joint name, a non-finite position, a bad shape, or a
        frame the imitator refuses (time not after the previous one)."""
        ...

class Model:
    """A kinematic tree; every quantity is in its base frame (the root link)."""

    @staticmethod
    def nao(root: str = "r_sole") -> "Model":
        """The NAO H25 V5 (DH tables), rooted at "r_sole", "l_sole" or "torso"."""
        ...
    @staticmethod
    def g1(root: Optional[str] = None) -> "Model":
        """The Unitree G1 (29 DoF, bundled URDF), rooted at a link ("left_sole", "right_sole";
        None: the pelvis)."""
        ...
    @staticmethod
    def from_urdf(path: str, root: Optional[str] = None) -> "Model":
        """Any URDF file, rooted at the link ``root`` (None: the URDF's root); every link is a
        frame."""
        ...
    @property
    def nv(self) -> int: ...
    @property
    def variable_names(self) -> List[str]: ...
    @property
    def frame_names(self) -> List[str]: ...
    @property
    def limits(self) -> Tuple[np.ndarray, np.ndarray]:
        """Lower and upper joint limits (rad), two arrays of ``nv``."""
        ...
    @property
    def total_mass(self) -> float:
        """kg."""
        ...
    def fk(self, q: Sequence[float], frame: str) -> np.ndarray:
        """The 4 x 4 placement of ``frame`` at ``q`` (m)."""
        ...
    def fk_all(self, q: Sequence[float]) -> Dict[str, np.ndarray]:
        """Every frame's 4 x 4 placement at ``q``."""
        ...
    def com(self, q: Sequence[float]) -> np.ndarray:
        """The centre of mass (3, m)."""
        ...
    def jacobian(self, q: Sequence[float], frame: str) -> np.ndarray:
        """(6, nv): the frame origin's linear velocity (rows 0-2) and the frame's angular
        velocity (rows 3-5) per joint velocity."""
        ...
    def com_jacobian(self, q: Sequence[float]) -> np.ndarray:
        """(3, nv): the CoM's velocity per joint velocity."""
        ...

class Task:
    """A task of a ``TaskSet`` level; targets in the model's base frame."""

    @staticmethod
    def position(frame: str, target: Sequence[float]) -> "Task":
        """The frame's origin at ``target`` (m)."""
        ...
    @staticmethod
    def orientation(frame: str, rotation: npt.ArrayLike) -> "Task":
        """The frame's axes at the 3 x 3 rotation matrix ``rotation``."""
        ...
    @staticmethod
    def pose(frame: str, placement: npt.ArrayLike) -> "Task":
        """The frame at the 4 x 4 homogeneous ``placement`` (m)."""
        ...
    @staticmethod
    def com(target: Sequence[float]) -> "Task":
        """The centre of mass at ``target`` (m)."""
        ...
    @staticmethod
    def com_ground(xy: Sequence[float]) -> "Task":
        """The CoM's ground projection at ``xy`` (m); its height free."""
        ...
    @staticmethod
    def posture(joints: Sequence[str], target: Sequence[float]) -> "Task":
        """The named joints at ``target`` (rad)."""
        ...

class TaskSet:
    """Levels of tasks on one model, the first level the highest priority."""

    def __init__(self, model: Model) -> None: ...
    def level(self, name: str, tasks: Sequence[Task]) -> "TaskSet":
        """Adds a level below the existing ones; returns the set (chainable)."""
        ...
    def solve(
        self, q: Sequence[float], tolerance: float = 1e-4, max_iterations: int = 50
    ) -> Dict[str, Any]:
        """Gauss-Newton iterations of the prioritized solve within the joint limits, from
        ``q`` (rad). Returns ``q`` (nv), ``task_errors`` (per task, m or rad), ``iterations``,
        ``stop`` ("converged", "stalled" or "iteration_limit")."""
        ...

class LiveSession:
    """A live session (the CLI's ``taskstack live``): human frames streamed in, one frame a
    line, imitated as each arrives; iterate it for the robot frames (the dicts of
    ``Imitator.step``) until the stream ends (the thread that made it only)."""

    def __init__(
        self,
        listen: Optional[str] = None,
        connect: Optional[str] = None,
        udp: Optional[str] = None,
        robot: str = "nao",
        bvh_header: Optional[str] = None,
        once: bool = False,
        end_after: Optional[float] = None,
        **options: Any,
    ) -> None:
        """Exactly one input, ``"HOST:PORT"``: ``listen`` (a TCP server, one source at a time),
        ``connect`` (a TCP client that reconnects) or ``udp``. The lines: a BVH header then
        motion lines (or ``bvh_header``, a BVH file whose header the stream's lines follow), or
        Kinect v2 CSV lines; the first line tells which. ``once``: end when the first TCP source
        leaves; ``end_after``: end after this long without a frame (s). ``options``: those of
        ``Imitator``. Waits for the stream's first line (Python threads run meanwhile). Faults
        are counted (``counts``) and bridged as ``taskstack.live`` documents: malformed lines
        skipped, a gap held, a long gap brings the robot back onto both feet. Raises ValueError
        for bad options or a malformed header, OSError for an address that cannot be bound."""
        ...
    @property
    def joint_names(self) -> List[str]:
        """The robot's joint names, in the order of ``q``."""
        ...
    @property
    def counts(self) -> Dict[str, int]:
        """frames, malformed, out_of_range, stale, gaps, held_frames, stands, connections,
        disconnects, time_shifts."""
        ...
    def __iter__(self) -> "LiveSession": ...
    def __next__(self) -> Dict[str, Any]: ...
