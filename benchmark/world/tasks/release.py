"""release: lift the box, hold it, put it back down where it was and let go."""

from __future__ import annotations

import numpy as np

from benchmark.world.tasks.human import Plan
from benchmark.world.tasks.motion import Phases
from benchmark.world.tasks.place import PRESS_M
from benchmark.world.tasks.task import Task


def keyframes(phases: Phases, rng: np.random.Generator) -> list:
    """Up ~12 cm, hold for about half the remaining time, down onto the table (pressing lightly), hold."""
    up = [0.0, 0.0, 0.12 + 0.03 * rng.uniform(-1, 1)]
    window = phases.move_end - phases.load_end
    plan = Plan(rng).move(up).hold(0.45 * window * (1.0 + 0.2 * rng.uniform(-1, 1))).move([0.0, 0.0, -PRESS_M])
    return plan.keyframes(phases.load_end, phases.move_end)


TASK = Task(name="release", description="lift the box, put it back down and let go", default_duration_s=10.0,
            lifts=True, releases=True, keyframes=keyframes)
