"""Human-speed task plans: movement durations from peak accelerations, fitting into short episodes;
the set-down's guarded approach, and how gently the simulated box touches down."""

import numpy as np
import pytest

from benchmark.suites.registry import SMOKE, get_suite
from benchmark.world.simulate import simulate
from benchmark.world.tasks import TASKS, Motion
from benchmark.world.tasks.human import (
    APPROACH_HEIGHT_M,
    APPROACH_HURRIED_M_S,
    APPROACH_RAMP_S,
    APPROACH_SPEED,
    MIN_DWELL_S,
    MIN_JERK_PEAK_ACC,
    PRESS_M,
    TRANSPORT_PEAK_ACC,
    Plan,
    move_duration,
)
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


def test_an_approach_runs_at_its_speed_and_is_the_first_movement_to_hurry():
    plan = Plan(np.random.default_rng(0)).move([0, 0, 0.1], duration=1.0).approach([0, 0, -0.002], 0.02)
    assert plan.durations[1] == pytest.approx(0.102 / 0.02 + APPROACH_RAMP_S)
    k = plan.keyframes(0.0, 7.0)
    assert [x[0] for x in k] == pytest.approx([0.0, 1.0, 6.2])
    assert len(k[1]) == 3 and len(k[2]) == 4 and k[2][3] == APPROACH_RAMP_S  # the approach's keyframe carries its ramp
    _, _, vel, _, _, _ = Motion(np.zeros(3), np.eye(3), k).evaluate(np.linspace(1.2, 6.0, 49))
    np.testing.assert_allclose(vel[:, 2], -0.02, rtol=1e-12)
    k = plan.keyframes(0.0, 3.65)  # too short: the approach hurries (4 cm/s), the minimum-jerk move keeps its time
    assert [x[0] for x in k] == pytest.approx([0.0, 1.0, 3.65])
    _, _, vel, _, _, _ = Motion(np.zeros(3), np.eye(3), k).evaluate(np.linspace(1.2, 3.45, 25))
    np.testing.assert_allclose(vel[:, 2], -0.04, rtol=1e-12)
    fastest = 1.0 + 0.102 / APPROACH_HURRIED_M_S + APPROACH_RAMP_S
    k = plan.keyframes(0.0, 0.5 * fastest)  # the approach at its fastest does not suffice: everything speeds up
    assert [x[0] for x in k] == pytest.approx([0.0, 0.5, 0.5 * fastest])


@pytest.mark.parametrize("name", ["place", "release", "free"])
def test_the_set_down_lowers_to_the_approach_height_then_approaches_slowly(name):
    task = TASKS[name]
    ph = task.phases(task.default_duration_s)
    k = task.keyframes(ph, np.random.default_rng(3))
    assert k[-2][1][2] == pytest.approx(APPROACH_HEIGHT_M) and k[-1][1][2] == pytest.approx(-PRESS_M)
    np.testing.assert_allclose(k[-1][1][:2], k[-2][1][:2])  # straight down
    speed = (APPROACH_HEIGHT_M + PRESS_M) / (k[-1][0] - k[-2][0] - k[-1][3])
    assert APPROACH_SPEED.lo <= speed <= APPROACH_SPEED.hi


def _touchdown(truth) -> tuple[float, float]:
    """The box's downward speed in the frame before the table touches it again after the lift [m/s],
    and the largest frame-mean acceleration within two frames of that touch [m/s^2]."""
    lifted = np.argmax(truth.box_pos[:, 2] > truth.box_pos[0, 2] + 0.01)
    k = lifted + np.argmax(np.linalg.norm(truth.env_force[lifted:], axis=1) > 0)
    acc = truth.net_wrench_mean[:, :3] / truth.mass + truth.gravity
    return -truth.box_vel[k - 1, 2], np.linalg.norm(acc[k - 2 : k + 3], axis=1).max()


@pytest.mark.parametrize("task", ["place", "release"])
def test_the_box_touches_down_gently(task):
    # smoke's set-down episodes (4 s). Before the guarded approach the plan's minimum-jerk descent
    # ended 2 mm into the table and the box met it at speed: place 0.68 m/s in the frame before the
    # touch and 9.7 m/s^2 over a frame, release 0.45 m/s and 6.5 m/s^2
    scenario = next(s for s in SMOKE.scenarios if s.task == task)
    speed, acc = _touchdown(simulate(scenario).truth)
    assert 0.0 < speed < 0.05  # measured: place 0.021 m/s, release 0.022 m/s (their approaches: 2.4, 2.7 cm/s)
    assert acc < 1.5  # measured: place 0.29 m/s^2, release 0.19 m/s^2


def test_a_free_task_sets_the_box_down_gently_too():
    # dev's first free episode (10 s): before the guarded approach it met the table at 0.15-0.40 m/s
    # like every dev and standard free episode (3.7-8.8 m/s^2 over a frame)
    scenario = next(s for s in get_suite("dev").scenarios if s.task == "free")
    speed, acc = _touchdown(simulate(scenario).truth)
    assert 0.0 < speed < 0.05  # measured 0.018 m/s
    assert acc < 1.5  # measured 0.36 m/s^2
