#!/usr/bin/env python3
"""PlaCo's hard CoM-in-polygon constraint against taskstack's CoM-polygon inequality, in one run.

Solves the right-support benchmark problem (`problem_rs.json`: right sole fixed, both hands and
the left ankle following per-frame targets, a posture below) with the CoM's ground projection
kept inside the right sole's outline shrunk by MARGIN:

* PlaCo 0.9.3: `add_com_polygon_constraint` (hard, in its QP), the right sole as a hard frame
  task, the hands and ankle as soft position tasks (weight 1), the posture as a soft joints task
  (weight 1e-6, so that it barely pulls the hands off their targets), joint limits on; the file's protocol (warm start, stop at 1e-4 m, a 1e-7 m
  stall or 50 iterations), one `solve(True)` per iteration.
* taskstack: `taskstack solve PROBLEM --com-polygon MARGIN --repeats 3` (release build).

Prints each solver's median time per frame and the ratio. Usage (the PlaCo environment is in
benches/placo/requirements.txt; see the README there):

    python benches/placo/com_polygon.py tests/data/bench/problem_rs.json [--margin 0.01]
"""

import argparse
import json
import re
import subprocess
import tempfile
import time
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import placo

# The NAO's right sole outline (sole frame = world here, m): the foot pressure sensors, as in
# taskstack's `nao::sole_outline(Side::Right)`, clockwise seen from above (PlaCo's polygon
# constraint finds a counter-clockwise polygon infeasible).
RIGHT_SOLE = [[0.07025, 0.0231], [0.07025, -0.0299], [-0.02965, -0.0299], [-0.03025, 0.0191]]
LOCKED = ("LHand", "RHand")


def geometry_free(urdf, points):
    """The URDF without its meshes (not shipped) and with the problem's points as fixed links."""
    root = ET.parse(urdf).getroot()
    for link in root.findall("link"):
        for tag in ("visual", "collision"):
            for element in link.findall(tag):
                link.remove(element)
    for spec in points.values():
        ET.SubElement(root, "link", name=spec["urdf_point_link"])
        joint = ET.SubElement(root, "joint", name=spec["urdf_point_link"] + "_joint", type="fixed")
        ET.SubElement(joint, "parent", link=spec["link"])
        ET.SubElement(joint, "child", link=spec["urdf_point_link"])
        ET.SubElement(joint, "origin", xyz=" ".join(map(str, spec["offset"])), rpy="0 0 0")
    out = tempfile.NamedTemporaryFile("w", suffix=".urdf", delete=False)
    out.write(ET.tostring(root, encoding="unicode"))
    out.close()
    return out.name


def placo_median_us(problem, urdf, margin):
    urdf = geometry_free(urdf, problem["points"])
    robot = placo.RobotWrapper(urdf, placo.Flags.ignore_collisions)
    names = problem["joint_order"]
    free = problem["free_variables"]
    for name, value in zip(names, problem["q_init"]):
        robot.set_joint(name, value)
    robot.update_kinematics()
    robot.set_T_world_frame("r_sole", np.eye(4))
    robot.update_kinematics()
    solver = placo.KinematicsSolver(robot)
    solver.enable_joint_limits(True)
    for joint in robot.joint_names():
        if joint not in names:
            solver.mask_dof(joint)
    sole = solver.add_frame_task("r_sole", np.eye(4))
    sole.configure("r_sole", "hard", 1.0, 1.0)
    solver.add_gear_task().set_gear("RHipYawPitch", "LHipYawPitch", 1.0)
    polygon = solver.add_com_polygon_constraint([np.array(p) for p in RIGHT_SOLE], margin)
    polygon.configure("com_polygon", "hard", 1.0)
    tasks = {}
    for point, spec in problem["points"].items():
        task = solver.add_position_task(spec["urdf_point_link"], np.zeros(3))
        task.configure(point, "soft", 1.0)
        tasks[point] = (task, spec["urdf_point_link"])
    posture = solver.add_joints_task()
    posture.set_joints({n: v for n, v in zip(names, problem["q_ref"]) if n in free})
    posture.configure("posture", "soft", 1e-6)
    protocol = problem["protocol"]["stop"]
    targets = problem["frames"]["targets"]
    times, iterations, converged = [], 0, 0
    for frame in range(problem["frames"]["count"]):
        for point, (task, _) in tasks.items():
            task.target_world = np.array(targets[point][frame])
        start = time.perf_counter()
        previous = None
        for _ in range(protocol["max_iter"]):
            errors = [np.linalg.norm(t.target_world - robot.get_T_world_frame(link)[:3, 3])
                      for t, link in tasks.values()]
            if max(errors) <= protocol["task_tol_m"]:
                converged += 1
                break
            if previous is not None and max(abs(a - b) for a, b in zip(errors, previous)) <= protocol["stall_tol_m"]:
                break
            previous = errors
            iterations += 1
            solver.solve(True)
            robot.update_kinematics()
        times.append(time.perf_counter() - start)
    frames = len(times)
    print(f"PlaCo: {frames} frames, {converged} reached {protocol['task_tol_m']} m, "
          f"{iterations / frames:.2f} iterations per frame")
    return 1e6 * float(np.median(times))


def taskstack_median_us(problem_path, margin, binary):
    out = subprocess.run(
        [binary, "solve", str(problem_path), "--com-polygon", str(margin), "--repeats", "3"],
        check=True, capture_output=True, text=True).stdout
    return float(re.search(r"median ([0-9.]+) µs", out).group(1))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("problem", type=Path)
    parser.add_argument("--margin", type=float, default=0.01, help="polygon margin (m)")
    parser.add_argument("--taskstack", default="target/release/taskstack")
    args = parser.parse_args()
    problem = json.loads(args.problem.read_text())
    urdf = Path(__file__).resolve().parents[2] / "tests" / "data" / "nao.urdf"
    ours = taskstack_median_us(args.problem, args.margin, args.taskstack)
    theirs = placo_median_us(problem, urdf, args.margin)
    print(f"{problem['problem']}: taskstack {ours:.1f} µs, PlaCo {theirs:.1f} µs per frame "
          f"(median); PlaCo / taskstack = {theirs / ours:.1f}")


if __name__ == "__main__":
    main()
