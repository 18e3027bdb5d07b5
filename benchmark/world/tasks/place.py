"""place: pick the box up, carry it ~15 cm sideways, put it down there and let go."""

from __future__ import annotations

import numpy as np

from benchmark.world.tasks.human import Plan
from benchmark.world.tasks.motion import Phases
from benchmark.world.tasks.task import Task


def keyframes(phases: Phases, rng: np.random.Generator) -> list:
    """Lift, carry along a random horizontal direction (mostly +x) turning a little, set down
    (lowered at human speed, then a slow guarded approach: :meth:`Plan.set_down`), hold on the
    table: movements at human speed with brief dwells between them."""
    height = 0.10 + 0.03 * rng.uniform()
    heading = rng.uniform(-0.5, 0.5)
    dist = 0.13 + 0.04 * rng.uniform()
    goal = dist * np.array([np.cos(heading), np.sin(heading), 0.0])
    yaw = np.array([0.0, 0.0, rng.uniform(-0.3, 0.3)])
    plan = Plan(rng).move([0, 0, height]).hold().move(goal + [0, 0, height], yaw).hold().set_down(goal)
    return plan.keyframes(phases.load_end, phases.move_end)


TASK = Task(name="place", description="pick and place: carry the box ~15 cm sideways and put it down",
            default_duration_s=10.0, lifts=True, releases=True, keyframes=keyframes)
