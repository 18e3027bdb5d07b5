"""Task motions: minimum-jerk keyframe interpolation with exact derivatives, and the task registry."""

import numpy as np
import pytest

from benchmark.world.tasks import TASKS
from benchmark.world.tasks.motion import Motion, cruise, min_jerk, timed
from fsv.hand import axis_angle_to_rot


def test_min_jerk_derivatives_match_finite_differences():
    s = np.linspace(0.05, 0.95, 19)
    h = 1e-6
    p, dp, ddp = min_jerk(s)
    np.testing.assert_allclose(dp, (min_jerk(s + h)[0] - min_jerk(s - h)[0]) / (2 * h), atol=1e-6)
    np.testing.assert_allclose(ddp, (min_jerk(s + h)[1] - min_jerk(s - h)[1]) / (2 * h), atol=1e-5)
    np.testing.assert_allclose(min_jerk(np.array([0.0, 1.0]))[0], [0, 1])
    np.testing.assert_allclose(min_jerk(np.array([0.0, 1.0]))[1:], 0.0)


def test_motion_velocity_acceleration_and_rates_are_derivatives_of_the_pose():
    R0 = axis_angle_to_rot(np.array([0.0, 0.0, 1.0]), 0.3)
    motion = Motion(np.array([0.1, 0, 0.03]), R0, [
        (0.5, np.zeros(3), np.zeros(3)), (1.5, np.array([0.1, -0.05, 0.2]), np.array([0.3, -0.2, 0.5])),
        (2.2, np.array([0.0, 0.05, 0.1]), np.array([-0.2, 0.1, 0.0]))])
    t = np.linspace(0.61, 2.11, 31)  # off the keyframes, where the third derivative jumps
    h = 1e-5
    pos, rot, vel, acc, omega, alpha = motion.evaluate(t)
    pp, rp, vp, _, wp, _ = motion.evaluate(t + h)
    pm, rm, vm, _, wm, _ = motion.evaluate(t - h)
    np.testing.assert_allclose(vel, (pp - pm) / (2 * h), atol=1e-6)
    np.testing.assert_allclose(acc, (vp - vm) / (2 * h), atol=1e-4)
    np.testing.assert_allclose(alpha, (wp - wm) / (2 * h), atol=1e-4)
    dR = np.einsum("tij,tkj->tik", rp, rm)  # R(t+h) R(t-h)^T = exp(2h [omega]x), world frame
    w_fd = np.stack([dR[:, 2, 1] - dR[:, 1, 2], dR[:, 0, 2] - dR[:, 2, 0], dR[:, 1, 0] - dR[:, 0, 1]], 1) / (4 * h)
    np.testing.assert_allclose(omega, w_fd, atol=1e-6)
    # at keyframe 1 the box is where the keyframe says and at rest
    p1, r1, v1, a1, w1, _ = motion(1.5)
    np.testing.assert_allclose(p1, [0.2, -0.05, 0.23], atol=1e-12)
    np.testing.assert_allclose(r1, axis_angle_to_rot(np.array([0.3, -0.2, 0.5]) / np.linalg.norm([0.3, -0.2, 0.5]),
                                                     np.linalg.norm([0.3, -0.2, 0.5])) @ R0, atol=1e-12)
    np.testing.assert_allclose(np.concatenate([v1, a1, w1]), 0.0, atol=1e-12)


def test_timed_spreads_segments_by_weight():
    kf = timed(1.0, 4.0, [(np.zeros(3), np.zeros(3))] * 3, [1.0, 2.0])
    assert [k[0] for k in kf] == pytest.approx([1.0, 2.0, 4.0])
    with pytest.raises(ValueError):
        timed(0, 1, [(np.zeros(3), np.zeros(3))] * 3, [1.0])


def test_registry_has_the_paper_tasks_and_six_axis_excitations():
    for name in ("lift", "place", "release", "rotate", "free"):
        assert name in TASKS
    assert {f"excite-{k}{a}" for k in "tr" for a in "xyz"} <= set(TASKS)
    assert all(t.default_duration_s == 10.0 for t in TASKS.values())


@pytest.mark.parametrize("name", sorted(TASKS))
@pytest.mark.parametrize("duration", ["min", 10.0])
def test_keyframes_fit_the_manipulation_window(name, duration):
    task = TASKS[name]
    duration = task.min_duration_s if duration == "min" else duration
    ph = task.phases(duration)
    assert 0 < ph.reach_end < ph.close_end < ph.load_end < ph.move_end <= ph.unload_end <= ph.open_end <= ph.duration
    kf = task.keyframes(ph, np.random.default_rng(0))
    times = np.array([k[0] for k in kf])
    assert times[0] >= ph.load_end - 1e-12 and times[-1] <= ph.move_end + 1e-12
    assert np.all(np.diff(times) > 0)
    d = np.array([k[1] for k in kf])
    np.testing.assert_allclose(d[0], 0.0)  # the manipulation starts where the box lies
    if task.lifts:
        assert d[:, 2].max() >= 0.08
    if task.releases:
        assert d[-1, 2] <= 0.0  # put back on the table before letting go


@pytest.mark.parametrize("ramp", [0.1, 0.3, 0.5])
def test_cruise_runs_at_constant_speed_between_smooth_ramps(ramp):
    s = np.linspace(0.01, 0.99, 99)
    h = 1e-6
    p, dp, ddp = cruise(s, ramp)
    np.testing.assert_allclose(dp, (cruise(s + h, ramp)[0] - cruise(s - h, ramp)[0]) / (2 * h), atol=1e-6)
    np.testing.assert_allclose(ddp, (cruise(s + h, ramp)[1] - cruise(s - h, ramp)[1]) / (2 * h), atol=1e-4)
    ends = cruise(np.array([0.0, 1.0]), ramp)
    np.testing.assert_allclose(ends[0], [0.0, 1.0], atol=1e-15)
    np.testing.assert_allclose(ends[1:], 0.0, atol=1e-15)  # starts and ends at rest
    middle = (s > ramp) & (s < 1 - ramp)
    np.testing.assert_allclose(dp[middle], 1.0 / (1.0 - ramp), rtol=1e-12)  # the constant speed
    np.testing.assert_allclose(ddp[middle], 0.0, atol=1e-12)
    with pytest.raises(ValueError):
        cruise(s, 0.6)


def test_a_keyframe_with_a_ramp_ends_a_constant_speed_segment():
    # 24 mm down in 1.1 s with 0.1 s ramps: 2.4 cm/s between them; the other segment stays minimum-jerk
    motion = Motion(np.zeros(3), np.eye(3), [(0.0, np.zeros(3), np.zeros(3)), (1.0, np.array([0, 0, 0.1]), np.zeros(3)),
                                             (2.1, np.array([0, 0, 0.076]), np.zeros(3), 0.1)])
    _, _, vel, acc, _, _ = motion.evaluate(np.linspace(1.1, 2.0, 91))
    np.testing.assert_allclose(vel[:, 2], -0.024, rtol=1e-12)
    np.testing.assert_allclose(acc, 0.0, atol=1e-12)
    pos, _, vel, _, _, _ = motion.evaluate(np.array([0.5, 1.0, 2.1]))
    np.testing.assert_allclose(pos[:, 2], [0.05, 0.1, 0.076], atol=1e-15)
    np.testing.assert_allclose(vel[1:], 0.0, atol=1e-15)
    assert vel[0, 2] == pytest.approx(1.875 * 0.1)  # the minimum-jerk segment's peak
