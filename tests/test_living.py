"""The living grip: per-trial draws, relaxation in holds, drift and tremor."""

import numpy as np
import pytest
from scipy import signal

from benchmark.world import living
from benchmark.world.living import LivingGrip


def test_draws_lie_in_their_ranges_and_the_trial_scale_has_the_stated_spread():
    draws = [LivingGrip.draw(np.random.default_rng(s)) for s in range(400)]
    scale = np.array([d.trial_scale for d in draws])
    assert np.mean(scale) == pytest.approx(1.0, abs=0.02)
    assert np.std(scale) / np.mean(scale) == pytest.approx(living.TRIAL_CV, rel=0.15)
    for d in draws:
        assert living.RELAX_TAU_S[0] <= d.relax_tau_s <= living.RELAX_TAU_S[1]
        assert living.DRIFT_CV[0] <= d.drift_cv <= living.DRIFT_CV[1]
        assert living.TREMOR_CV[0] <= d.tremor_cv <= living.TREMOR_CV[1]
    assert LivingGrip.draw(np.random.default_rng(3)) == LivingGrip.draw(np.random.default_rng(3))


def test_relaxation_decays_with_its_time_constant_and_restarts_with_a_movement():
    g = LivingGrip(trial_scale=1.0, relax_tau_s=4.0, drift_cv=0.02, tremor_cv=0.01)
    t = np.arange(0, 20, 0.004)
    moving = (t < 1.0) | ((t >= 12.0) & (t < 12.5))
    r = g.relaxation(t, moving)
    assert np.all(r[moving] == 1.0)
    i = np.searchsorted(t, 1.0 + 4.0)  # one time constant after the first movement ended
    floor = living.RELAX_FLOOR
    assert r[i] == pytest.approx(floor + (1 - floor) * np.exp(-(t[i] - t[np.searchsorted(t, 1.0) - 1]) / 4.0))
    assert r[np.searchsorted(t, 11.9)] < floor + 0.1 * (1 - floor)
    assert np.all(np.diff(r[(t > 1.0) & (t < 12.0)]) <= 0)


def test_modulation_has_the_drawn_spread_with_tremor_in_its_band():
    g = LivingGrip(trial_scale=1.0, relax_tau_s=4.0, drift_cv=0.0, tremor_cv=0.01)
    t = np.arange(0, 60, 0.004)
    m = g.modulation(t, np.random.default_rng(0))
    assert np.std(m) == pytest.approx(0.01, rel=0.02)
    f, p = signal.welch(m - 1, fs=250, nperseg=2048)
    band = (f >= 8) & (f <= 12)
    assert p[band].sum() / p.sum() > 0.8
    drift = LivingGrip(trial_scale=1.0, relax_tau_s=4.0, drift_cv=0.03, tremor_cv=0.0).modulation(t, np.random.default_rng(1))
    assert np.std(drift) == pytest.approx(0.03, rel=0.3)  # a 1 s process over 60 s: a loose estimate
    f, p = signal.welch(drift - 1, fs=250, nperseg=4096)
    assert p[f < 1].sum() / p.sum() > 0.8
    np.testing.assert_array_equal(m, g.modulation(t, np.random.default_rng(0)))
