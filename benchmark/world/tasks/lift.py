"""lift: grasp the box, lift it about 15 cm, hold it still in the air until the end."""

from __future__ import annotations

import numpy as np

from benchmark.world.tasks import Task
from benchmark.world.tasks.motion import Phases

LIFT_HEIGHT_M = 0.15


def keyframes(phases: Phases, rng: np.random.Generator) -> list:
    """Up in the first 40 % of the manipulation window (at least 0.6 s), then hold."""
    t0, t1 = phases.load_end, phases.move_end
    up = t0 + max(0.6, 0.4 * (t1 - t0))
    height = LIFT_HEIGHT_M * (1.0 + 0.1 * rng.uniform(-1, 1))
    zero = np.zeros(3)
    return [(t0, zero, zero), (min(up, t1), np.array([0.0, 0.0, height]), zero)]


TASK = Task(name="lift", description="lift the box ~15 cm and hold it", default_duration_s=10.0,
            lifts=True, releases=False, keyframes=keyframes, min_duration_s=1.0)
