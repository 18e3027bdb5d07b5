"""lift: grasp the box, lift it 12-18 cm at human speed, hold it still in the air until the end."""

from __future__ import annotations

import numpy as np

from benchmark.world.tasks.human import Plan
from benchmark.world.tasks.motion import Phases
from benchmark.world.tasks.task import Task

LIFT_HEIGHT_M = 0.15


def keyframes(phases: Phases, rng: np.random.Generator) -> list:
    """Up by 15 cm +- 20 % in one movement (peak acceleration from the human range), then hold."""
    height = LIFT_HEIGHT_M * (1.0 + 0.2 * rng.uniform(-1, 1))
    return Plan(rng).move([0.0, 0.0, height]).keyframes(phases.load_end, phases.move_end)


TASK = Task(name="lift", description="lift the box ~15 cm and hold it", default_duration_s=10.0,
            lifts=True, releases=False, keyframes=keyframes, min_duration_s=1.0)
