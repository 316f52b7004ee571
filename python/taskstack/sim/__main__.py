"""``python -m taskstack.sim OUT_DIR...``: play runs on the physics model and judge them.

Each OUT_DIR is an output folder of ``taskstack imitate``/``batch``/``walk`` (its
``joints.csv``) or a ``joints.csv``; the robot is told by the joint names. The checks are
:mod:`taskstack.sim.checks`'. Prints one line per run and model (``--json``: one JSON
document), writes ``OUT_DIR/physics.svg`` (base tilt, ZMP and CoM margins, sole forces over
time) for a folder and adds the simulated robot (the first model's) to
its ``view.html``, drawn in gray beside the plan. Exit status: 0 every run passes, 1 one fails,
2 bad input.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import List

from .checks import InputError, Verdict, check_run
from .plot import write_plot
from .view import add_simulation


def main(argv: List[str] = None) -> int:
    ap = argparse.ArgumentParser(
        prog="taskstack check", description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    ap.add_argument("runs", nargs="+", metavar="OUT_DIR", help="output folders or joints.csv files")
    ap.add_argument("--model", choices=["nominal", "weak", "both"], default="both",
                    help="which physics model (default: both)")
    ap.add_argument("--json", action="store_true", help="print one JSON document")
    ap.add_argument("--robot", help="nao, g1 or a biped profile file (default: told by the joint names)")
    ap.add_argument("--hold", type=float, default=1.0, help="seconds of the last posture after the run (default 1)")
    ap.add_argument("--no-plot", action="store_true",
                    help="do not write OUT_DIR/physics.svg nor add the simulation to view.html")
    a = ap.parse_args(argv)
    if not (0.0 <= a.hold <= 3600.0):
        print(f"taskstack check: --hold {a.hold}: must be 0–3600 s", file=sys.stderr)
        return 2
    models = {"nominal": [False], "weak": [True], "both": [False, True]}[a.model]
    verdicts: List[Verdict] = []
    for run in a.runs:
        per_run = []
        for weak in models:
            try:
                v = check_run(run, weak=weak, hold=a.hold, robot=a.robot)
            except InputError as e:
                print(f"taskstack check: {e}", file=sys.stderr)
                return 2
            per_run.append(v)
            if not a.json:
                print(v.summary(), flush=True)
        if Path(run).is_dir() and not a.no_plot:
            write_plot(Path(run) / "physics.svg", per_run)
            if (Path(run) / "view.html").is_file():
                add_simulation(Path(run) / "view.html", per_run[0])
        verdicts += per_run
    if a.json:
        print(json.dumps({"runs": [v.to_json() for v in verdicts],
                          "passed": all(v.passed for v in verdicts)}))
    return 0 if all(v.passed for v in verdicts) else 1


if __name__ == "__main__":
    sys.exit(main())
