"""benchmark.perf.throughput: the arithmetic of its figures (the timings themselves are not tested)."""

import pytest

from benchmark.perf.throughput import TPAMI_MANIPULATION_S, extrapolate, per_core_minute


def test_episodes_per_core_minute():
    assert per_core_minute(4, 120.0, 1) == 2.0 and per_core_minute(4, 60.0, 2) == 2.0


def test_the_extrapolation_scales_the_one_worker_cost():
    # 20 s of manipulation cost 60 s on one worker: 3 core-seconds per second of manipulation
    x = extrapolate(60.0, 20.0, efficiency=0.9, cores=64)
    assert x["core_hours"] == pytest.approx(3 * TPAMI_MANIPULATION_S / 3600)  # 9.6 core-hours
    assert x["wall_hours"] == pytest.approx(9.6 / (64 * 0.9))
