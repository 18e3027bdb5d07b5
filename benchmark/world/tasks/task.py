"""A manipulation task: what happens to the box between the grasp and the release."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from benchmark.world.tasks.motion import Phases


@dataclass(frozen=True)
class Task:
    """A manipulation task.

    Attributes:
        name: Registry key.
        description: One line for humans.
        default_duration_s: Episode length when the scenario gives none, [s].
        lifts: Whether the box leaves the table while held.
        releases: Whether the hand puts the box down and lets go at the end.
        keyframes: ``keyframes(phases, rng)`` -> list of ``(t, displacement (3,), rotation vector (3,))``
            of the box relative to its start pose, world frame, within [phases.load_end, phases.move_end].
        min_duration_s: Shortest episode the task accepts, [s]: phases and motions compress with
            the duration, and below this the hand cannot keep up with its own plan.
    """

    name: str
    description: str
    default_duration_s: float
    lifts: bool
    releases: bool
    keyframes: Callable[[Phases, np.random.Generator], list]
    min_duration_s: float = 2.0

    def phases(self, duration_s: float) -> Phases:
        """The prehension phases of an episode of this length."""
        return Phases.for_duration(duration_s, self.releases)
