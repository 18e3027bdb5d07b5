"""fsv.grip: a person's grip line, fitted to the frames of a calibration recording."""

import numpy as np
import pytest

from fsv import GripCalibration, InputError
from fsv.grip import MIN_CALIBRATION_SAMPLES, fit_grip


def _recording(n=200, baseline=7.0, gain=1.6, seed=0):
    """Frames whose internal-force amount lies exactly on baseline + gain * load, spread over three
    or four fingers in varying shares."""
    rng = np.random.default_rng(seed)
    load = rng.uniform(2.0, 8.0, n)
    active = np.ones((n, 4), bool)
    active[::3, 3] = False
    shares = np.where(active, rng.uniform(0.2, 1.0, (n, 4)), 0.0)
    shares /= np.linalg.norm(shares, axis=1, keepdims=True)
    internal = (baseline + gain * load)[:, None] * shares
    return load, internal, active


def test_fit_grip_recovers_the_line_the_frames_lie_on():
    load, internal, active = _recording()
    c = fit_grip(load, internal, active)
    assert abs(c.baseline_n - 7.0) < 1e-9 and abs(c.gain - 1.6) < 1e-9
    assert c.samples == 200
    np.testing.assert_array_equal(c.vector(), [c.baseline_n, c.gain])


def test_fit_grip_leaves_out_frames_without_two_fingers_and_ignores_inactive_values():
    load, internal, active = _recording()
    active[:10] = [True, False, False, False]  # one finger: not a grasp
    internal[:10] = 1e3
    internal[10:, 3] = np.where(active[10:, 3], internal[10:, 3], 1e6)  # values of fingers not in contact
    c = fit_grip(load, internal, active)
    assert c.samples == 190 and abs(c.baseline_n - 7.0) < 1e-9 and abs(c.gain - 1.6) < 1e-9


def test_fit_grip_names_what_is_wrong():
    load, internal, active = _recording(n=MIN_CALIBRATION_SAMPLES - 1)
    with pytest.raises(InputError, match=f"at least {MIN_CALIBRATION_SAMPLES} frames"):
        fit_grip(load, internal, active)
    load, internal, active = _recording()
    with pytest.raises(InputError, match="different loads"):
        fit_grip(np.full_like(load, 3.0), internal, active)
    with pytest.raises(InputError, match=r"load \(N,\), internal and active \(N, K\)"):
        fit_grip(load[:-1], internal, active)


def test_a_calibration_is_finite():
    with pytest.raises(InputError, match="baseline_n must be a finite number"):
        GripCalibration(float("nan"), 1.0)
    with pytest.raises(InputError, match="samples must be an integer >= 0"):
        GripCalibration(1.0, 1.0, samples=-1)
    assert GripCalibration(np.float64(2), 1).gain == 1.0
