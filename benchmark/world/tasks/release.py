"""release: lift the box, hold it, put it back down where it was and let go."""

from __future__ import annotations

import numpy as np

from benchmark.world.tasks import Task
from benchmark.world.tasks.motion import Phases, timed
from benchmark.world.tasks.place import PRESS_M


def keyframes(phases: Phases, rng: np.random.Generator) -> list:
    """Up ~12 cm, hold, down onto the table (pressing lightly), hold."""
    zero = np.zeros(3)
    up = np.array([0.0, 0.0, 0.12 + 0.03 * rng.uniform(-1, 1)])
    down = np.array([0.0, 0.0, -PRESS_M])
    way = [(zero, zero), (up, zero), (up, zero), (down, zero), (down, zero)]
    return timed(phases.load_end, phases.move_end, way, [1.0, 0.8, 1.0, 0.4])


TASK = Task(name="release", description="lift the box, put it back down and let go", default_duration_s=10.0,
            lifts=True, releases=True, keyframes=keyframes)
