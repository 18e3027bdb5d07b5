"""Simulated tactile sensors: one-axis normal-force readings per finger, like the paper's FSG020.

The paper measured each finger's normal force with a Honeywell FSG020WNPB piezoresistive sensor
(range 0-20 N). This model reads the truth's normal force n_k . F_k, adds Gaussian noise of
``noise_n`` (an assumed 0.5 % of the 20 N span; the datasheet's exact figure is not modelled) and
clips to the sensor's range [0, ``full_scale_n``]. A finger off the box reads NaN (no measurement),
which :func:`fsv.forces.decompose_forces` ignores.
"""

from __future__ import annotations

import numpy as np

from benchmark.errors import BenchmarkError
from benchmark.world.truth import Truth

FSG020_FULL_SCALE_N = 20.0
FSG020_NOISE_N = 0.1


def tactile_normal_forces(
    truth: Truth,
    rng: np.random.Generator | None = None,
    *,
    full_scale_n: float = FSG020_FULL_SCALE_N,
    noise_n: float = FSG020_NOISE_N,
) -> np.ndarray:
    """Normal-force readings per finger and frame.

    Args:
        truth: The episode's truth (contact forces and normals, object frame).
        rng: Source of the sensor noise (e.g. ``scenario.rng("tactile")``); None = noise-free.
        full_scale_n: Upper end of the sensor's range [N]; np.inf for an unbounded ideal sensor.
        noise_n: Standard deviation of the additive noise [N].

    Returns:
        Readings, shape (T, K), [N]; NaN where the finger does not touch the box.
    """
    if not (full_scale_n > 0) or not (np.isfinite(noise_n) and noise_n >= 0):
        raise BenchmarkError(f"tactile sensor needs full_scale_n > 0 and noise_n >= 0, got {full_scale_n!r}, {noise_n!r}")
    f = np.einsum("tki,tki->tk", np.asarray(truth.contact_force, float), np.asarray(truth.contact_normal, float))
    if rng is not None and noise_n > 0:
        f = f + rng.normal(0.0, noise_n, size=f.shape)
    return np.where(truth.contact_active, np.clip(f, 0.0, full_scale_n), np.nan)
