"""rotate: lift the box, then turn it about each of its axes in turn (x, y, z) and back."""

from __future__ import annotations

import numpy as np

from benchmark.world.tasks.human import Plan
from benchmark.world.tasks.motion import Phases
from benchmark.world.tasks.task import Task

ANGLES_RAD = (0.45, 0.35, 0.6)  # about the box's x (long edge), y (grasp axis) and z (vertical)


def keyframes(phases: Phases, rng: np.random.Generator) -> list:
    """Lift ~12 cm; for each axis, turn +angle, -angle, back to level (human speeds, brief dwells; the
    turns that do not fit a short episode are left out); hold."""
    up = np.array([0.0, 0.0, 0.12])
    plan = Plan(rng).move(up).hold()
    for axis, angle in enumerate(ANGLES_RAD):
        a = angle * (1.0 + 0.1 * rng.uniform(-1, 1))
        e = np.eye(3)[axis]
        for turn in (a * e, -a * e, np.zeros(3)):
            plan.move(up, turn, optional=True).hold()
    return plan.keyframes(phases.load_end, phases.move_end)


TASK = Task(name="rotate", description="lift, then rotate about each box axis and back", default_duration_s=10.0,
            lifts=True, releases=False, keyframes=keyframes, min_duration_s=2.5)
