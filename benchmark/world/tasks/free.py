"""free: an unguided, smooth random composition of lifting, carrying, turning and placing."""

from __future__ import annotations

import numpy as np

from benchmark.world.tasks import Task
from benchmark.world.tasks.motion import Phases, timed
from benchmark.world.tasks.place import PRESS_M


def keyframes(phases: Phases, rng: np.random.Generator) -> list:
    """Lift, random poses (within 10 cm sideways, 8-20 cm up, 25 degrees), put down, hold.

    One random pose per ~1.2 s of manipulation time (at most 5), so short episodes move no faster.
    """
    zero = np.zeros(3)
    way = [(zero, zero), (np.array([0.0, 0.0, 0.12]), zero)]
    n = int(np.clip((phases.move_end - phases.load_end) / 1.2 - 2, 1, 5))
    for _ in range(int(rng.integers(max(1, n - 1), n + 1))):
        d = np.array([rng.uniform(-0.10, 0.10), rng.uniform(-0.08, 0.08), rng.uniform(0.08, 0.20)])
        r = rng.uniform(-1.0, 1.0, 3) * np.array([0.3, 0.25, 0.45])
        way.append((d, r))
    end = np.array([rng.uniform(-0.08, 0.08), rng.uniform(-0.05, 0.05), 0.0])
    yaw = np.array([0.0, 0.0, rng.uniform(-0.3, 0.3)])
    way += [(end + [0, 0, 0.05], yaw), (end + [0, 0, -PRESS_M], yaw), (end + [0, 0, -PRESS_M], yaw)]
    weights = list(rng.uniform(0.8, 1.4, len(way) - 1))
    weights[-1] = 0.4
    return timed(phases.load_end, phases.move_end, way, weights)


TASK = Task(name="free", description="a smooth random composition of lifts, carries, turns and a put-down",
            default_duration_s=10.0, lifts=True, releases=True, keyframes=keyframes)
