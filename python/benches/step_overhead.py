"""The Python call overhead of `Imitator.step`: per-frame wall time of a live loop in Python
against the Rust step time the imitation measures itself (`metrics["solve_time_us"]`, the
median and 99th percentile of `Imitator::step` inside Rust), on the same clip.

    python python/benches/step_overhead.py [CLIP] [--robot nao|g1] [--repeats N]
"""

import argparse
import time
from pathlib import Path

import numpy as np

import taskstack

ROOT = Path(__file__).resolve().parents[2]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("clip", nargs="?", default=str(ROOT / "tests/data/mocap/cmu_07_04_slow_walk.bvh"))
    ap.add_argument("--robot", default="nao")
    ap.add_argument("--repeats", type=int, default=3)
    a = ap.parse_args()
    times, names, positions = taskstack.read_clip(a.clip)
    capture = "kinect" if a.clip.endswith(".csv") else "optical"
    steps = []
    for _ in range(a.repeats):
        imitator = taskstack.Imitator(robot=a.robot, capture=capture)
        for t, frame in zip(times, positions):
            start = time.perf_counter()
            imitator.step(t, frame, names=names)
            steps.append(time.perf_counter() - start)
    py = np.array(steps) * 1e6
    rust = taskstack.imitate_clip(a.clip, robot=a.robot, hold=0).metrics["solve_time_us"]
    print(f"{Path(a.clip).name} on {a.robot}, {len(times)} frames x {a.repeats}")
    print(f"Python Imitator.step: median {np.median(py):.1f} us, p99 {np.percentile(py, 99):.1f} us")
    print(f"Rust Imitator::step:  median {rust['median']:.1f} us, p99 {rust['p99']:.1f} us")
    print(f"overhead (median): {np.median(py) - rust['median']:.1f} us per step")


if __name__ == "__main__":
    main()
