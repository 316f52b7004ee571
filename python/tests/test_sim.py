"""The physics check (`taskstack.sim`): its models are the Rust models' robots, a standing pose
stands, a quasi-static step onto one leg stands, a lean that must fall falls, on both robots;
and the command's exit statuses."""

import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
import pytest

mujoco = pytest.importorskip("mujoco", reason="the simulation extra: pip install './python[sim]'")

import taskstack  # noqa: E402
from taskstack import sim  # noqa: E402
from taskstack._taskstack import robot_description  # noqa: E402

ROBOTS = ["nao", "g1"]
#: A biped nobody tuned, from its profile file: the check builds its model from the profile.
TINY = str(Path(__file__).resolve().parents[2] / "tests" / "data" / "tiny_biped" / "tiny_biped.toml")


@pytest.fixture
def tmp():
    path = Path(tempfile.mkdtemp(prefix="taskstack-sim-"))
    yield path
    shutil.rmtree(path, ignore_errors=True)


def write_run(folder: Path, columns, times, q) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    with open(folder / "joints.csv", "w") as f:
        f.write("time," + ",".join(columns) + "\n")
        for t, row in zip(times, q):
            f.write(f"{t:.6f}," + ",".join(f"{v:.9f}" for v in row) + "\n")
    return folder


def stand(pm):
    return np.array([pm.stand[c] for c in pm.columns])


def smooth(s):
    s = np.clip(s, 0.0, 1.0)
    return s * s * (3 - 2 * s)


def test_the_hull_and_the_signed_distance_on_hand_checked_shapes():
    from taskstack.sim.geometry import convex_hull, signed_distance

    # A 2 x 1 rectangle given with an inner point and a repeated corner: its four corners,
    # counter-clockwise (positive shoelace area 2).
    hull = convex_hull(np.array([[0, 0], [2, 0], [2, 1], [0, 1], [1, 0.5], [2, 1]], dtype=float))
    assert len(hull) == 4
    x, y = hull[:, 0], hull[:, 1]
    assert abs(0.5 * np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y) - 2.0) < 1e-12
    assert abs(signed_distance(hull, np.array([1.0, 0.5])) - 0.5) < 1e-12  # nearest edges y = 0, 1
    assert abs(signed_distance(hull, np.array([1.9, 0.5])) - 0.1) < 1e-12
    assert abs(signed_distance(hull, np.array([3.0, 2.0])) + np.sqrt(2.0)) < 1e-12  # corner (2, 1)
    # A segment (a foot on an edge) has no inside; a point is its distance away.
    segment = convex_hull(np.array([[0.0, 0.0], [1.0, 0.0]]))
    assert abs(signed_distance(segment, np.array([0.5, 0.0]))) < 1e-12
    assert abs(signed_distance(segment, np.array([0.5, 0.3])) + 0.3) < 1e-12
    assert signed_distance(np.zeros((0, 2)), np.array([0.0, 0.0])) == -np.inf


@pytest.mark.parametrize("robot", ROBOTS + [TINY])
def test_the_physics_model_has_the_rust_models_masses_and_frames(tmp, robot):
    pm = sim.build(robot)
    d = robot_description(robot)
    # Masses: the URDF's, as the Rust model reads them.
    assert abs(float(np.sum(pm.model.body_mass)) - d["total_mass"]) < 1e-9
    # Frames: every link's origin, relative to the root link, at a posture with every joint
    # moved, against the Rust model built from the same URDF text.
    urdf = tmp / "robot.urdf"
    urdf.write_text(d["urdf"])
    rust = taskstack.Model.from_urdf(str(urdf))
    rng = np.random.default_rng(3)
    lower, upper = pm.lower, pm.upper
    q = lower + (0.2 + 0.6 * rng.random(len(pm.columns))) * (upper - lower)
    data = mujoco.MjData(pm.model)
    data.qpos[:] = 0
    data.qpos[3] = 1.0
    pm.set_joints(data.qpos, q)
    mujoco.mj_kinematics(pm.model, data)
    by_name = dict(zip(pm.columns, q))
    rust_q = [by_name.get(v, 0.0) for v in rust.variable_names]
    frames = rust.fk_all(rust_q)
    root = data.xpos[1].copy(), data.xmat[1].reshape(3, 3).copy()
    compared = 0
    for b in range(2, pm.model.nbody):
        name = mujoco.mj_id2name(pm.model, mujoco.mjtObj.mjOBJ_BODY, b)
        if name in frames:
            local = root[1].T @ (data.xpos[b] - root[0])
            assert np.allclose(local, frames[name][:3, 3], atol=1e-9), name
            compared += 1
    assert compared >= 20


@pytest.mark.parametrize("robot", ROBOTS + [TINY])
def test_a_standing_pose_stands(tmp, robot):
    pm = sim.build(robot)
    times = np.linspace(0.0, 2.0, 201)
    q = np.tile(stand(pm), (len(times), 1))
    run = write_run(tmp / "stand", pm.columns, times, q)
    for weak in (False, True):
        v = sim.check_run(run, weak=weak, robot=robot)
        assert v.passed, v.summary()
        assert v.playback.com_inside_share == 1.0


@pytest.mark.parametrize("robot", ROBOTS)
def test_a_standing_robots_measured_zmp_is_under_its_com(tmp, robot):
    # Standing still, the floor's centre of pressure is the CoM's ground point (statics): over
    # the last second the ZMP margin (from the contact forces and the soles' outlines) matches
    # the CoM's (from the bodies' masses and the contact points, which sit on those outlines)
    # to a millimetre on average (the G1's stiff servos keep it swaying a few millimetres).
    pm = sim.build(robot)
    times = np.linspace(0.0, 2.0, 201)
    run = write_run(tmp / "stand", pm.columns, times, np.tile(stand(pm), (len(times), 1)))
    v = sim.check_run(run, robot=robot)
    end = np.array(v.playback.series[-100:])
    assert abs(np.mean(end[:, 6]) - np.mean(end[:, 3])) < 1e-3, end[:, [3, 6]]
    assert v.playback.zmp_inside_share == 1.0 and v.playback.min_zmp_margin_m > 0.01


def test_a_long_constant_tail_is_played_for_five_seconds(tmp):
    pm = sim.build("nao")
    q0 = stand(pm)
    times = np.arange(0.0, 33.0 + 1e-9, 0.01)
    q = np.tile(q0, (len(times), 1))
    # The head turns 0.3 rad over the first 3 s, then the posture is held for 30 s.
    head = pm.columns.index("HeadYaw")
    q[:, head] += 0.3 * smooth(times / 3.0)
    run = write_run(tmp / "tail", pm.columns, times, q)
    v = sim.check_run(run, weak=False)
    assert v.passed, v.summary()
    assert abs(v.playback.tail_left_out_s - 25.0) < 0.02, v.playback.tail_left_out_s
    assert abs(v.playback.duration - 8.0) < 0.02, v.playback.duration
    # The check's own hold (1 s) follows the 5 s kept: the series ends 1 s after them.
    assert abs(v.playback.series[-1][0] - 9.0) < 0.02, v.playback.series[-1][0]


def one_leg_trajectory(robot):
    """A quasi-static step onto the right leg, computed with the solver: the CoM over the right
    sole's centre (8 s), the left sole 3 cm up (4 s), held 3 s, then back; the base kept
    upright below the feet and the CoM. Rooted at the right sole, whose frame is the ground."""
    root = {"nao": "r_sole", "g1": "right_sole"}[robot]
    model = taskstack.Model.nao(root) if robot == "nao" else taskstack.Model.g1(root)
    pm = sim.build(robot)
    order = [model.variable_names.index(c) for c in pm.columns]
    q0 = np.zeros(model.nv)
    q0[order] = stand(pm)
    left = {"nao": "l_sole", "g1": "left_sole"}[robot]
    base = robot_description(robot)["base"]
    outline = np.array(robot_description(robot)["soles"][1]["outline"])
    centre = (outline.min(axis=0) + outline.max(axis=0)) / 2
    left0 = model.fk(q0, left)
    lifted = left0.copy()
    lifted[2, 3] += 0.03

    def solve(com_xy, sole):
        ts = (
            taskstack.TaskSet(model)
            .level("feet", [taskstack.Task.pose(left, sole)])
            .level("balance", [taskstack.Task.com_ground(list(com_xy))])
            .level("upright", [taskstack.Task.orientation(base, np.eye(3))])
            .level("posture", [taskstack.Task.posture(model.variable_names, list(q0))])
        )
        out = ts.solve(q0, max_iterations=200)
        assert out["task_errors"][0] < 1e-4 and out["task_errors"][1] < 1e-4, out
        return out["q"]

    shifted = solve(centre, left0)
    up = solve(centre, lifted)
    keys = [(0.0, q0), (1.0, q0), (9.0, shifted), (13.0, up), (16.0, up), (20.0, shifted), (28.0, q0)]
    times = np.arange(0.0, 28.0 + 1e-9, 0.01)
    q = np.empty((len(times), model.nv))
    for (t0, a), (t1, b) in zip(keys, keys[1:]):
        m = (times >= t0) & (times <= t1)
        s = smooth((times[m] - t0) / (t1 - t0))[:, None]
        q[m] = a + (b - a) * s
    return pm, times, q[:, order]


@pytest.mark.parametrize("robot", ROBOTS)
def test_a_quasi_static_step_onto_one_leg_stands(tmp, robot):
    pm, times, q = one_leg_trajectory(robot)
    run = write_run(tmp / "one_leg", pm.columns, times, q)
    v = sim.check_run(run)
    assert v.passed, v.summary()
    # The left sole really left the floor: a stretch with the right sole alone loaded.
    forces = np.array([r[4:6] for r in v.playback.series])
    assert np.any((forces[:, 0] == 0) & (forces[:, 1] > 0))


@pytest.mark.parametrize("robot", ROBOTS + [TINY])
def test_a_lean_that_must_fall_falls(tmp, robot):
    pm = sim.build(robot)
    times = np.arange(0.0, 3.0, 0.01)
    q = np.tile(stand(pm), (len(times), 1))
    # Both ankles pitch 0.6 rad over a second: the body tips forward far past the toes.
    for c, name in enumerate(pm.columns):
        if "ankle" in name.lower() and "pitch" in name.lower():
            q[:, c] = np.clip(q[:, c] + 0.6 * smooth(times - 0.5), pm.lower[c], pm.upper[c])
    run = write_run(tmp / "lean", pm.columns, times, q)
    v = sim.check_run(run, robot=robot)
    assert not v.passed and v.playback.fell_at is not None, v.summary()


def test_the_command_says_pass_fail_and_bad_input_by_its_exit_status(tmp):
    pm = sim.build("nao")
    times = np.linspace(0.0, 1.0, 101)
    good = write_run(tmp / "good", pm.columns, times, np.tile(stand(pm), (len(times), 1)))
    run = [sys.executable, "-m", "taskstack.sim", "--hold", "0.2"]
    assert subprocess.run(run + [str(good)], capture_output=True).returncode == 0
    assert (good / "physics.svg").read_text().startswith("<svg")
    q = np.tile(stand(pm), (len(times), 1))
    q[:, pm.columns.index("LKneePitch")] = pm.upper[pm.columns.index("LKneePitch")] + 0.5
    bad = write_run(tmp / "beyond_limits", pm.columns, times, q)
    done = subprocess.run(run + [str(bad), "--json"], capture_output=True, text=True)
    assert done.returncode == 1, done.stderr
    assert '"passed": false' in done.stdout
    missing = subprocess.run(run + [str(tmp / "nothing")], capture_output=True, text=True)
    assert missing.returncode == 2 and "nothing" in missing.stderr
