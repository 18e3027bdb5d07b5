"""The world is human: lift peaks, grip fluctuation in holds, grip-load coupling, Newton-Euler.

Measured on this machine (standard suite's seeds, truth only; results/world): lift peak acceleration
2.8-5.5 m/s^2; thumb grip coefficient of variation in holds (from 1 s after lift-off) 2.3-4.8 % on
lift; shake grip-load correlation 0.50-0.82 (per-digit, the world's control) and 0.53-0.91
(whole-hand) from 1 s after lift-off, the grip leading by 0-133 ms; Newton-Euler residuals below
2e-14 N.
"""

from dataclasses import replace

import numpy as np
import pytest

from benchmark.suites.registry import get_suite
from benchmark.world.humanness import episode_humanness, holds
from benchmark.world.scenario import GRIP_CONTROLS, Scenario
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


@pytest.mark.parametrize("control", GRIP_CONTROLS)
def test_grip_follows_the_load_on_shake_and_leads_it(control):
    """The shake episodes of ``standard`` and ``dev`` (8 people and grasps), from 1 s after lift-off."""
    scenarios = [sc for name in ("standard", "dev") for sc in get_suite(name).scenarios if sc.task == "shake"]
    hs = [episode_humanness(simulate(replace(sc, grip_control=control)).truth, sc.fps) for sc in scenarios]
    assert len(hs) == 8
    # measured medians: whole-hand 0.85 (0.53-0.91), per-digit 0.63 (0.50-0.82). The per-digit grip
    # presses each digit for at least 0.7 of its nearby peak load (benchmark.world.grip.load_envelope),
    # so it is modulated less than the whole-hand one and the living fluctuations weigh more: a
    # weaker coupling than the 0.86 the per-digit control had before (docs/findings.md)
    assert np.median([h.grip_load_corr for h in hs]) >= (0.8 if control == "whole-hand" else 0.55)
    assert all(h.grip_lead_s >= 0 for h in hs)  # measured leads 0-133 ms under both


@pytest.mark.parametrize("task", sorted(TASKS))
def test_truth_obeys_newton_euler_on_every_task(task):
    h = episode_humanness(simulate(Scenario(task=task, seed=7, duration_s=5.0)).truth, 30.0)
    assert h.newton_euler_n <= 1e-9


def test_holds_are_runs_of_at_least_a_second():
    mask = np.array([0] * 5 + [1] * 40 + [0] * 3 + [1] * 10 + [0], bool)
    assert holds(mask, 30.0) == [slice(5, 45)]


def test_effective_margin_is_one_minus_the_load_over_the_slip_limit():
    from types import SimpleNamespace

    from benchmark.world.humanness import effective_margin

    n = np.array([[0.0, 1.0, 0.0], [0.0, -1.0, 0.0]])  # two opposed pads
    f = np.array([[[0.0, 2.0, 0.8], [0.0, -2.0, 0.8]], [[0.0, 0.0, 0.0], [0.0, 0.0, 0.0]]])
    normal = np.broadcast_to(n, f.shape)
    truth = SimpleNamespace(contact_force=f, contact_normal=normal,
                            normal_force=lambda: np.einsum("tkj,tkj->tk", f, normal))
    sm = effective_margin(truth, 0.8)
    assert sm[0] == pytest.approx(1 - 1.6 / (0.8 * 4.0))  # L = 1.6 N on 4 N of grip: 0.5
    assert np.isnan(sm[1])  # no digit presses


def test_per_digit_control_squeezes_closer_to_the_margin_than_the_whole_hand():
    def stats(control):
        ep = simulate(Scenario(task="lift", user=0, grasp=0, mass=2, seed=920, duration_s=3.0, grip_control=control))
        return episode_humanness(ep.truth, 30.0, ep.object_model.friction)

    whole, digits = stats("whole-hand"), stats("per-digit")
    # measured: margin MEASURED_WH -> MEASURED_PD, thumb MEASURED_TWH -> MEASURED_TPD times the box's weight
    # (user 0's drawn margin: 0.29)
    assert digits.effective_margin < whole.effective_margin - 0.1
    assert digits.thumb_per_weight < 0.7 * whole.thumb_per_weight


@pytest.mark.parametrize("user", [0, 2, 3])
def test_the_realised_margin_is_the_persons(user):
    """The world's grip (per-digit) realises the person's drawn relative margin on the named users'
    lifts (drawn 0.29, 0.20, 0.47; the trial's within 10 % of it)."""
    from benchmark.world.people import person

    ep = simulate(Scenario(task="lift", user=user, grasp=0, mass=2, seed=920 + user))
    h = episode_humanness(ep.truth, 30.0, ep.object_model.friction)
    # measured MEASURED_REAL
    assert h.effective_margin == pytest.approx(person(user)["safety_margin"], abs=0.1)
