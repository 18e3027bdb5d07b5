"""The task registry: name -> :class:`Task` (dm_control suite style, one module per task).

A task says what happens to the box between the hand's grasp and its release, as minimum-jerk
keyframes (movements at human speed, :mod:`benchmark.world.tasks.human`) of the box's displacement and rotation relative to its start pose, and whether the box
is lifted off the table and whether the hand lets it go at the end. The reach, grasp and load
phases before and the release after are common to every task (:class:`~benchmark.world.tasks.motion.Phases`).
"""

from __future__ import annotations

from benchmark.world.tasks import excite, free, lift, place, release, rotate, shake
from benchmark.world.tasks.motion import Motion, Phases, min_jerk
from benchmark.world.tasks.task import Task


def _registry() -> dict:
    tasks = [lift.TASK, place.TASK, release.TASK, rotate.TASK, free.TASK, shake.TASK, *excite.TASKS]
    return {t.name: t for t in tasks}


TASKS: dict = _registry()

__all__ = ["TASKS", "Task", "Motion", "Phases", "min_jerk"]
