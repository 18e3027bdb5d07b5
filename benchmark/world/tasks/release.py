"""release: lift the box, hold it, put it back down where it was and let go."""

from __future__ import annotations

import numpy as np

from benchmark.world.tasks.human import Plan
from benchmark.world.tasks.motion import Phases
from benchmark.world.tasks.task import Task


def keyframes(phases: Phases, rng: np.random.Generator) -> list:
    """Up ~12 cm, hold for about half the remaining time, set down where it was (lowered at human
    speed, then a slow guarded approach onto the table, pressing lightly: :meth:`Plan.set_down`), hold."""
    up = [0.0, 0.0, 0.12 + 0.03 * rng.uniform(-1, 1)]
    window = phases.move_end - phases.load_end
    plan = Plan(rng).move(up).hold(0.45 * window * (1.0 + 0.2 * rng.uniform(-1, 1))).set_down(np.zeros(3))
    return plan.keyframes(phases.load_end, phases.move_end)


TASK = Task(name="release", description="lift the box, put it back down and let go", default_duration_s=10.0,
            lifts=True, releases=True, keyframes=keyframes)
