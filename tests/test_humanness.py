"""The world is human: lift peaks, grip fluctuation in holds, grip-load coupling, Newton-Euler.

Measured on this machine (standard suite's seeds, truth only): lift peak acceleration 2.9-4.9
m/s^2; thumb grip coefficient of variation in holds 2.1-4.8 %; shake grip-load correlation
0.90-0.95 with the grip leading by 67-100 ms; Newton-Euler residuals below 2e-14 N.
"""

import numpy as np
import pytest

from benchmark.world.humanness import episode_humanness, holds
from benchmark.world.scenario import Scenario
from benchmark.world.simulate import simulate
from benchmark.world.tasks import TASKS


@pytest.fixture(scope="module")
def lifts():
    return [episode_humanness(simulate(Scenario(task="lift", user=u, grasp=g, mass=m, seed=900 + u)).truth, 30.0)
            for u, g, m in ((0, 0, 0), (1, 2, 3), (2, 3, 5), (3, 1, 1))]


def test_lift_reaches_human_peak_accelerations(lifts):
    peaks = [h.peak_acc for h in lifts]
    assert min(peaks) >= 2.0  # the bar; measured 2.9-4.9 m/s^2 on the standard suite
    assert max(peaks) <= 9.0


def test_grip_fluctuates_by_a_few_percent_in_holds(lifts):
    cv = np.median([h.grip_cv for h in lifts])
    assert 0.01 <= cv <= 0.06  # measured 2.1-4.8 %; before the living grip 0.0-0.4 %


def test_grip_follows_the_load_on_shake_and_leads_it():
    hs = [episode_humanness(simulate(Scenario(task="shake", user=u, grasp=g, mass=m, seed=910 + u)).truth, 30.0)
          for u, g, m in ((0, 0, 2), (2, 3, 3), (4, 1, 0))]
    assert np.median([h.grip_load_corr for h in hs]) >= 0.8  # measured 0.90-0.95
    assert all(h.grip_lead_s >= 0 for h in hs)


@pytest.mark.parametrize("task", sorted(TASKS))
def test_truth_obeys_newton_euler_on_every_task(task):
    h = episode_humanness(simulate(Scenario(task=task, seed=7, duration_s=5.0)).truth, 30.0)
    assert h.newton_euler_n <= 1e-9


def test_holds_are_runs_of_at_least_a_second():
    mask = np.array([0] * 5 + [1] * 40 + [0] * 3 + [1] * 10 + [0], bool)
    assert holds(mask, 30.0) == [slice(5, 45)]
