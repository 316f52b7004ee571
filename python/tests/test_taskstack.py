"""The Python package against the command-line tool and against itself.

The `taskstack` binary (``TASKSTACK_BIN``, else ``release/taskstack`` or ``debug/taskstack``
under ``CARGO_TARGET_DIR`` or this repository's ``target``) is the reference for the imitation's joint
angles and for forward kinematics: the Python package must give its numbers.
"""

import csv
import json
import math
import os
import shutil
import subprocess
import tempfile
from pathlib import Path

import numpy as np
import pytest

import taskstack

ROOT = Path(__file__).resolve().parents[2]
MOCAP = ROOT / "tests" / "data" / "mocap"
KINECT = MOCAP / "kinect2_labanotation_ges01_wavehand.csv"
STAND_ON_ONE_LEG = MOCAP / "cmu_05_02_stand_arm_gestures_turn_single_leg.bvh"


def cli() -> Path:
    """The taskstack binary; the tests fail (not skip) without one."""
    targets = [Path(os.environ["CARGO_TARGET_DIR"])] if "CARGO_TARGET_DIR" in os.environ else []
    targets.append(ROOT / "target")
    candidates = [os.environ.get("TASKSTACK_BIN")] + [
        str(t / p / "taskstack") for t in targets for p in ("release", "debug")
    ]
    for c in candidates:
        if c and Path(c).is_file():
            return Path(c)
    pytest.fail("no taskstack binary: build it (cargo build --release) or set TASKSTACK_BIN")


@pytest.fixture
def tmp():
    path = Path(tempfile.mkdtemp(prefix="taskstack-py-"))
    yield path
    shutil.rmtree(path, ignore_errors=True)


def cli_joints(clip: Path, out: Path, *args: str):
    """The joint angles of `taskstack imitate CLIP ARGS` (header, rows)."""
    run = subprocess.run(
        [str(cli()), "-q", "imitate", str(clip), "--out", str(out), *args],
        capture_output=True,
        text=True,
    )
    assert run.returncode == 0, run.stderr
    with open(out / "joints.csv") as f:
        rows = list(csv.reader(f))
    return rows[0], np.array(rows[1:], dtype=float)


@pytest.mark.parametrize(
    "clip, robot, args, kwargs",
    [
        (KINECT, "nao", ["--hold", "0.5"], {"hold": 0.5}),
        (STAND_ON_ONE_LEG, "nao", [], {}),
        (KINECT, "g1", ["--hold", "0.25"], {"hold": 0.25}),
        (KINECT, "g1", ["--hold", "0.25", "--no-sway-shaping"], {"hold": 0.25, "sway_shaping": False}),
        (KINECT, "nao", ["--hold", "0", "--method", "koenemann"], {"hold": 0, "method": "koenemann"}),
        (
            STAND_ON_ONE_LEG,
            "nao",
            ["--hold", "0", "--dynamic-walk", "--walking-arms"],
            {"hold": 0, "dynamic_walk": True, "walking_arms": True},
        ),
        (
            STAND_ON_ONE_LEG,
            "nao",
            ["--hold", "0", "--walk", "--step-pivot", "0.1", "--step-slide", "0.02"],
            {"hold": 0, "walk": True, "step_pivot": 0.1, "step_slide": 0.02},
        ),
        (
            KINECT,
            "nao",
            ["--hold", "0", "--no-zmp-balance", "--tracking-speed", "1.0"],
            {"hold": 0, "zmp_balance": False, "tracking_speed": 1.0},
        ),
        (
            KINECT,
            "nao",
            ["--hold", "0", "--damping", "0.1", "--damping-momentum", "0.8"],
            {"hold": 0, "damping": 0.1, "damping_momentum": 0.8},
        ),
    ],
)
def test_imitate_clip_gives_the_cli_joint_angles(tmp, clip, robot, args, kwargs):
    header, rows = cli_joints(clip, tmp / "out", "--robot", robot, *args)
    r = taskstack.imitate_clip(clip, robot=robot, **kwargs)
    assert header == ["time"] + r.joint_names
    assert r.q.shape == r.servo_targets.shape == (rows.shape[0], len(r.joint_names))
    # joints.csv has six decimals: the same numbers to within its rounding (half a unit of
    # the sixth decimal; numpy and Rust round a value on the .5 boundary differently).
    assert np.max(np.abs(r.servo_targets - rows[:, 1:])) <= 0.5e-6 + 1e-12
    # The NAO's profile states no servo stiffness; the G1's servos sag by a few mrad, and its
    # commands follow the plan through the sway shaper, 0.52 s late on average: on the first
    # frame (the shaper holds it) only the sag is left.
    sag = np.max(np.abs(r.servo_targets - r.q))
    first = np.max(np.abs(r.servo_targets[0] - r.q[0]))
    assert (sag == 0.0) if robot == "nao" else (1e-3 < first < 0.05 and sag >= first), sag
    # Without the shaper the commands are the plan plus the sag on every frame.
    assert kwargs.get("sway_shaping", True) or sag < 0.05, sag
    assert np.max(np.abs(r.time - rows[:, 0])) <= 0.5e-6 + 1e-12
    with open(tmp / "out" / "metrics.json") as f:
        metrics = json.load(f)
    assert r.metrics["frames"] == metrics["frames"] == len(r.time)
    assert len(r.phase) == len(r.time)
    # motion.npz loads with numpy, its arrays consistent, at the clip's own rate.
    npz = np.load(tmp / "out" / "motion.npz")
    n = len(npz["time"])
    assert list(npz["joint_names"]) == r.joint_names
    assert npz["dof_pos"].shape == (n, len(r.joint_names)) and npz["root_pos"].shape == (n, 3)
    assert npz["root_quat"].shape == (n, 4) and npz["contacts"].shape == (n, 2)
    assert npz["contacts"].dtype == bool and float(npz["fps"]) == r.fps
    assert np.allclose(np.diff(npz["time"]), 1.0 / r.fps)
    # Its first frame is the run's first frame.
    assert np.array_equal(npz["dof_pos"][0], r.q[0]) and np.array_equal(npz["root_pos"][0], r.root_pos[0])


def test_the_result_has_consistent_shapes_and_a_standing_sole_on_the_floor():
    r = taskstack.imitate_clip(STAND_ON_ONE_LEG, hold=0.5)
    n, j = r.q.shape
    assert r.time.shape == (n,) and r.root_pos.shape == (n, 3) and r.root_quat.shape == (n, 4)
    assert r.contacts.shape == (n, 2) and r.contacts.dtype == bool
    assert np.allclose(np.linalg.norm(r.root_quat, axis=1), 1.0, atol=1e-12)
    assert r.fps == 120.0
    # Rebuild the soles from the base pose and the joints with the NAO rooted at its torso
    # (the floating base), an independent forward-kinematics path.
    torso = taskstack.Model.nao("torso")
    order = [r.joint_names.index(v) for v in torso.variable_names]
    for i in range(0, n, 10):
        x, y, z, w = r.root_quat[i]
        R = np.array(
            [
                [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
            ]
        )
        for side, sole in enumerate(["l_sole", "r_sole"]):
            p = R @ torso.fk(r.q[i, order], sole)[:3, 3] + r.root_pos[i]
            if r.contacts[i, side]:
                assert abs(p[2]) <= 1e-3, (i, sole, p)
    # 05_02 stands on the right leg: a frame with only the right sole down.
    assert any((not left) and right for left, right in r.contacts)


def test_bad_input_raises_python_exceptions_with_the_rust_message(tmp):
    with pytest.raises(FileNotFoundError, match="no_such_clip.bvh"):
        taskstack.imitate_clip(tmp / "no_such_clip.bvh")
    notes = tmp / "notes.bvh"
    notes.write_text("these are my notes, not a clip\n")
    with pytest.raises(ValueError, match="notes.bvh:1"):
        taskstack.imitate_clip(notes)
    for bad in [math.inf, math.nan, -1.0, "soon"]:
        with pytest.raises(ValueError, match="hold"):
            taskstack.imitate_clip(KINECT, hold=bad)
    with pytest.raises(ValueError, match="method"):
        taskstack.imitate_clip(KINECT, method="magic")
    with pytest.raises(ValueError, match="velocity_fraction"):
        taskstack.imitate_clip(KINECT, velocity_fraction=0.0)
    with pytest.raises(ValueError, match="dynamic_walk"):
        taskstack.imitate_clip(KINECT, walking_arms=True)
    for name in ["step_distance", "step_heading", "step_pivot", "step_slide"]:
        with pytest.raises(ValueError, match=name.replace("step_", "footsteps.")):
            taskstack.imitate_clip(KINECT, **{name: -0.1})
    for bad in [-0.1, 1.5, math.nan]:
        with pytest.raises(ValueError, match="damping_momentum"):
            taskstack.imitate_clip(KINECT, damping_momentum=bad)
    with pytest.raises(ValueError, match="damping"):
        taskstack.imitate_clip(KINECT, damping=0.0)
    # A setting of the other method is refused, not ignored.
    with pytest.raises(ValueError, match="walk: not a setting of method \"koenemann\""):
        taskstack.imitate_clip(KINECT, method="koenemann", walk=True)
    with pytest.raises(ValueError, match="swing_speed: not a setting of method \"poubel\""):
        taskstack.Imitator(swing_speed=0.2)
    with pytest.raises(ValueError, match="swing_speed"):
        taskstack.Imitator(method="koenemann", swing_speed=-1.0)
    with pytest.raises(FileNotFoundError, match="missing_profile.toml"):
        taskstack.imitate_clip(KINECT, robot=str(tmp / "missing_profile.toml"))
    with pytest.raises(TypeError, match="velocity_fractoin"):
        taskstack.Imitator(velocity_fractoin=0.5)
    imitator = taskstack.Imitator()
    with pytest.raises(ValueError, match="unknown human joint"):
        imitator.step(0.0, {"LeftElbowThing": [0.0, 0.0, 1.0]})
    with pytest.raises(ValueError, match="not finite"):
        imitator.step(0.0, {"LShoulder": [0.0, math.inf, 1.0]})
    with pytest.raises(ValueError, match="shape"):
        imitator.step(0.0, np.zeros((2, 3)), names=["LShoulder"])
    model = taskstack.Model.nao()
    with pytest.raises(ValueError, match="23 variables"):
        model.fk([0.0] * 3, "l_sole")
    with pytest.raises(ValueError, match="frame"):
        model.fk([0.0] * model.nv, "no_such_frame")
    with pytest.raises(ValueError, match="rotation"):
        taskstack.Task.orientation("torso", np.ones((3, 3)))
    with pytest.raises(ValueError):
        taskstack.TaskSet(model).level("reach", [taskstack.Task.position("no_such_frame", [0, 0, 0])])


def test_a_live_imitator_fed_a_clip_frame_by_frame_gives_the_clips_run():
    times, names, positions = taskstack.read_clip(KINECT)
    assert positions.shape == (len(times), len(names), 3)
    imitator = taskstack.Imitator(capture="kinect")
    qs = []
    for t, frame in zip(times, positions):
        out = imitator.step(t, frame, names=names)
        assert out["q"].shape == (len(imitator.joint_names),)
        # The NAO's profile states no servo stiffness: its servo targets are its postures.
        assert np.array_equal(out["servo_targets"], out["q"])
        assert out["root_quat"].shape == (4,) and out["left_sole"].shape == (4, 4)
        assert set(out["effectors"]) == {"l_hand", "r_hand", "l_ankle", "r_ankle"}
        qs.append(out["q"])
    batch = taskstack.imitate_clip(KINECT, hold=0)
    assert np.array_equal(np.array(qs), batch.q)
    # The dict form of a frame gives the same step.
    again = taskstack.Imitator(capture="kinect")
    first = {n: p for n, p in zip(names, positions[0]) if not np.isnan(p).any()}
    assert np.array_equal(again.step(times[0], first)["q"], qs[0])


def test_a_live_session_fed_over_tcp_gives_the_clips_run():
    import socket
    import threading

    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    lines = KINECT.read_text().splitlines(keepends=True)

    def source():
        # The session binds when it is made; a refused connection is tried again.
        for _ in range(200):
            try:
                with socket.create_connection(("127.0.0.1", port)) as s:
                    s.sendall(b"not a frame\n" + "".join(lines).encode())
                return
            except ConnectionRefusedError:
                threading.Event().wait(0.01)

    sender = threading.Thread(target=source)
    sender.start()
    session = taskstack.LiveSession(listen=f"127.0.0.1:{port}", once=True)
    qs = [frame["q"] for frame in session]
    sender.join()
    batch = taskstack.imitate_clip(KINECT, hold=0)
    assert np.array_equal(np.array(qs), batch.q)
    assert session.counts["frames"] == len(qs) and session.counts["malformed"] == 1
    with pytest.raises(ValueError):
        taskstack.LiveSession(listen="127.0.0.1:1", udp="127.0.0.1:2")


def test_model_fk_gives_the_cli_fk_numbers():
    model = taskstack.Model.nao("r_sole")
    rng = np.random.default_rng(7)
    lower, upper = model.limits
    q = lower + rng.random(model.nv) * (upper - lower)
    line = json.dumps({"q": dict(zip(model.variable_names, q.tolist()))}) + "\n"
    run = subprocess.run(
        [str(cli()), "fk", "--robot", "nao", "--root", "right"],
        input=line,
        capture_output=True,
        text=True,
    )
    assert run.returncode == 0, run.stderr
    reference = json.loads(run.stdout)
    for frame, xyz in reference["frames"].items():
        assert np.allclose(model.fk(q, frame)[:3, 3], xyz, atol=1e-9), frame
    assert np.allclose(model.com(q), reference["com"], atol=1e-9)


def test_jacobians_match_finite_differences():
    model = taskstack.Model.g1("left_sole")
    q = np.linspace(-0.2, 0.2, model.nv)
    J = model.jacobian(q, "right_sole")
    Jc = model.com_jacobian(q)
    h = 1e-6
    for k in range(model.nv):
        dq = np.zeros(model.nv)
        dq[k] = h
        plus, minus = model.fk(q + dq, "right_sole"), model.fk(q - dq, "right_sole")
        assert np.allclose((plus[:3, 3] - minus[:3, 3]) / (2 * h), J[:3, k], atol=1e-6)
        # Angular velocity: the skew part of dR Rᵀ.
        W = (plus[:3, :3] - minus[:3, :3]) / (2 * h) @ model.fk(q, "right_sole")[:3, :3].T
        assert np.allclose([W[2, 1], W[0, 2], W[1, 0]], J[3:, k], atol=1e-6)
        assert np.allclose((model.com(q + dq) - model.com(q - dq)) / (2 * h), Jc[:, k], atol=1e-6)


def test_a_task_set_reaches_its_levels_in_priority_order():
    model = taskstack.Model.nao("r_sole")
    ts = (
        taskstack.TaskSet(model)
        .level("balance", [taskstack.Task.com_ground([0.0, 0.05])])
        .level("reach", [taskstack.Task.position("l_hand", [0.15, 0.10, 0.35])])
    )
    out = ts.solve(np.zeros(model.nv))
    assert out["stop"] == "converged"
    q = out["q"]
    assert np.allclose(model.com(q)[:2], [0.0, 0.05], atol=1e-4)
    assert np.allclose(model.fk(q, "l_hand")[:3, 3], [0.15, 0.10, 0.35], atol=1e-4)
    lower, upper = model.limits
    assert np.all(q >= lower) and np.all(q <= upper)
