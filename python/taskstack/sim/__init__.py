"""Physics playback of taskstack outputs on MuJoCo (``pip install taskstack[sim]``).

* :mod:`taskstack.sim.model`: the MuJoCo model of the NAO or the G1, generated from the URDF
  the crate's models come from (recipe and every constant in its docs); nominal or weak.
* :mod:`taskstack.sim.player`: plays a ``joints.csv`` from the first posture, standing, and
  measures what the checks need.
* :mod:`taskstack.sim.checks`: the checks, their thresholds, the verdict.

``python -m taskstack.sim OUT_DIR...`` (or ``taskstack check OUT_DIR...``) checks runs.
"""

from .checks import THRESHOLDS, Verdict, check_run, judge
from .model import PhysicsModel, build
from .player import Playback, play

__all__ = ["THRESHOLDS", "PhysicsModel", "Playback", "Verdict", "build", "check_run", "judge", "play"]
