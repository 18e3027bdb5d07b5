"""Simulation: a scenario in, an episode with its ground truth out.

:func:`simulate` resolves the scenario's grasp for its person (a named grasp's stored plan, or the
drawn grasp that this person's hand makes and holds, :mod:`benchmark.world.grasp_plan`) and runs
the physics (:mod:`benchmark.world.physics`): the synthetic human reaches, grasps, loads,
manipulates and possibly releases the box along the task's minimum-jerk motion, and the
:class:`~benchmark.world.truth.Truth` is recorded at the frame times t_k = k / fps.
"""

from __future__ import annotations

from benchmark.world import physics
from benchmark.world.episode import Episode
from benchmark.world.grasp_plan import plan_grasp
from benchmark.world.physics import SimStats, duration_of, steps_per_frame  # noqa: F401 (the world's entry points)
from benchmark.world.scenario import Scenario


def simulate(scenario: Scenario, progress: bool = False) -> Episode:
    """Simulates a scenario and records its ground truth.

    Args:
        scenario: Task, user, grasp, mass, seed and duration.
        progress: Show a progress bar (tqdm) on stderr.

    Returns:
        An :class:`Episode` with ``truth``, ``object_model`` and ``hand_model`` (no depth yet).

    Raises:
        ScenarioError: If the task, user, grasp or mass does not exist, or no drawn grasp of that
            index holds in the person's hand.
        SimulationError: If the physics diverges, the hand drops the box or its palm touches it.
    """
    return run(scenario, progress)[0]


def run(scenario: Scenario, progress: bool = False) -> tuple[Episode, SimStats]:
    """:func:`simulate`, also returning the :class:`~benchmark.world.physics.SimStats` (speed)."""
    physics.validate(scenario)
    return physics.run(scenario, plan_grasp(scenario), progress)
