"""The FSG020-like tactile sensor model."""

import numpy as np
import pytest
from forces_oracle import grasp_truth

from benchmark.errors import BenchmarkError
from benchmark.world.tactile import tactile_normal_forces


def test_readings_are_the_true_normal_forces_with_noise_range_and_gaps():
    truth, _ = grasp_truth(2, T=200, K=4)
    active = truth.contact_active.copy()
    active[::7, 1] = False
    truth = type(truth)(**{**truth.as_dict(), "contact_active": active})
    f = np.einsum("tki,tki->tk", truth.contact_force, truth.contact_normal)
    ideal = tactile_normal_forces(truth, full_scale_n=np.inf, noise_n=0.0)
    assert np.allclose(ideal[active], f[active]) and np.isnan(ideal[~active]).all()
    capped = tactile_normal_forces(truth, full_scale_n=3.0, noise_n=0.0)
    assert np.nanmax(capped) == 3.0 and np.allclose(capped[active], np.minimum(f[active], 3.0))
    noisy = tactile_normal_forces(truth, np.random.default_rng(0), full_scale_n=np.inf, noise_n=0.1)
    d = (noisy - ideal)[active]
    assert d.std() == pytest.approx(0.1, rel=0.1) and abs(d.mean()) < 0.02
    with pytest.raises(BenchmarkError, match="noise_n >= 0"):
        tactile_normal_forces(truth, noise_n=-0.1)
