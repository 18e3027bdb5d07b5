"""Human-speed task plans: movement durations from peak accelerations, fitting into short episodes."""

import numpy as np
import pytest

from benchmark.world.tasks import TASKS, Motion
from benchmark.world.tasks.human import MIN_DWELL_S, MIN_JERK_PEAK_ACC, TRANSPORT_PEAK_ACC, Plan, move_duration
from benchmark.world.tasks.motion import min_jerk


def test_min_jerk_peaks():
    s = np.linspace(0, 1, 200001)
    _, dp, ddp = min_jerk(s)
    assert np.max(np.abs(ddp)) == pytest.approx(MIN_JERK_PEAK_ACC, rel=1e-6)
    assert np.max(dp) == pytest.approx(1.875, rel=1e-6)


def test_a_movement_peaks_at_its_drawn_acceleration():
    T = move_duration(0.15, 4.0)
    motion = Motion(np.zeros(3), np.eye(3), [(0.0, np.zeros(3), np.zeros(3)), (T, np.array([0, 0, 0.15]), np.zeros(3))])
    _, _, _, acc, _, _ = motion.evaluate(np.linspace(0, T, 20001))
    assert np.max(np.abs(acc[:, 2])) == pytest.approx(4.0, rel=1e-4)


def test_plan_draws_durations_in_the_human_range():
    plan = Plan(np.random.default_rng(0)).move([0, 0, 0.15])
    T = plan.durations[0]
    assert move_duration(0.15, TRANSPORT_PEAK_ACC.hi) <= T <= move_duration(0.15, TRANSPORT_PEAK_ACC.lo)


def test_a_long_plan_shortens_holds_then_leaves_out_optional_movements_then_speeds_up():
    rng = np.random.default_rng(0)
    plan = Plan(rng).move([0, 0, 0.1], duration=1.0).hold(2.0).move([0.1, 0, 0.1], duration=1.0, optional=True)
    plan.hold(1.0).move([0.1, 0, 0.0], duration=1.0)
    k = plan.keyframes(0.0, 4.0)  # holds shrink from 3 s to 1 s, in proportion to their room above the minimum
    first = 2.0 - (2.0 - MIN_DWELL_S) * 2.0 / (3.0 - 2 * MIN_DWELL_S)
    assert [t for t, _, _ in k] == pytest.approx([0.0, 1.0, 1.0 + first, 2.0 + first, 3.0, 4.0])
    k = plan.keyframes(0.0, 2.5)  # holds at their minimum do not suffice: the optional carry is left out
    assert [t for t, _, _ in k] == pytest.approx([0.0, 1.0, 1.0 + MIN_DWELL_S, 2.0 + MIN_DWELL_S])
    np.testing.assert_allclose(k[-1][1], [0.1, 0, 0.0])
    k = plan.keyframes(0.0, 1.0)  # the required movements alone do not fit: they speed up
    assert k[-1][0] == pytest.approx(1.0) and len(k) == 4


@pytest.mark.parametrize("name", sorted(TASKS))
def test_every_task_plans_within_its_window(name):
    task = TASKS[name]
    for duration in (task.min_duration_s, 4.0, task.default_duration_s):
        ph = task.phases(duration)
        k = task.keyframes(ph, np.random.default_rng(5))
        t = [x[0] for x in k]
        assert t[0] == pytest.approx(ph.load_end) and t[-1] <= ph.move_end + 1e-9
        assert np.all(np.diff(t) > 0)
