"""free: an unguided, smooth random composition of lifting, carrying, turning and placing."""

from __future__ import annotations

import numpy as np

from benchmark.world.tasks.human import Plan
from benchmark.world.tasks.motion import Phases
from benchmark.world.tasks.task import Task


def keyframes(phases: Phases, rng: np.random.Generator) -> list:
    """Lift, random poses (within 10 cm sideways, 8-20 cm up, 25 degrees), set down (:meth:`Plan.set_down`), hold.

    One random pose per ~1.2 s of manipulation time (at most 5), movements at human speed with
    dwells of 0.2-1 s between them.
    """
    plan = Plan(rng).move([0.0, 0.0, 0.12]).hold()
    n = int(np.clip((phases.move_end - phases.load_end) / 1.2 - 2, 1, 5))
    for _ in range(int(rng.integers(max(1, n - 1), n + 1))):
        d = np.array([rng.uniform(-0.10, 0.10), rng.uniform(-0.08, 0.08), rng.uniform(0.08, 0.20)])
        r = rng.uniform(-1.0, 1.0, 3) * np.array([0.3, 0.25, 0.45])
        plan.move(d, r, optional=True).hold(rng.uniform(0.2, 1.0))
    end = np.array([rng.uniform(-0.08, 0.08), rng.uniform(-0.05, 0.05), 0.0])
    yaw = np.array([0.0, 0.0, rng.uniform(-0.3, 0.3)])
    plan.move(end + [0, 0, 0.05], yaw).set_down(end)
    return plan.keyframes(phases.load_end, phases.move_end)


TASK = Task(name="free", description="a smooth random composition of lifts, carries, turns and a put-down",
            default_duration_s=10.0, lifts=True, releases=True, keyframes=keyframes)
