"""benchmark.world.butterworth: scipy.signal's Butterworth band-pass design and sosfilt, bit for bit."""

import numpy as np
import pytest
from scipy import signal

from benchmark.errors import BenchmarkError
from benchmark.world.butterworth import bandpass_sos, sosfilt
from benchmark.world.living import TREMOR_BAND_HZ


def _bands():
    """The tremor band at control rates from 25 Hz to 2 kHz (the world's use), and a sweep of others."""
    lo, hi = TREMOR_BAND_HZ
    rates = np.concatenate([[25.0, 30.0, 60.0, 100.0, 240.0, 500.0, 1000.0, 2000.0],
                            np.random.default_rng(7).uniform(25.0, 2000.0, 40)])
    for fs in rates:
        dt = (np.arange(3) / fs)[1] - (np.arange(3) / fs)[0]
        nyquist = 0.5 / dt
        if hi < nyquist:
            yield 4, lo / nyquist, hi / nyquist
    for low, high in np.random.default_rng(8).uniform(0.01, 0.99, (60, 2)):
        if abs(high - low) > 1e-3:
            yield 4, min(low, high), max(low, high)
    for order in (1, 2, 3, 5, 6):
        yield order, 0.1, 0.4


@pytest.mark.parametrize("order, low, high", list(_bands()))
def test_the_sections_are_scipys_bit_for_bit(order, low, high):
    ours = bandpass_sos(order, low, high)
    theirs = signal.butter(order, [low, high], btype="bandpass", output="sos")
    assert ours.dtype == theirs.dtype and ours.shape == theirs.shape == (order, 6)
    assert ours.tobytes() == theirs.tobytes()


def test_the_filter_is_scipys_bit_for_bit_and_passes_the_band():
    rng = np.random.default_rng(3)
    for order, low, high in [(4, 0.008, 0.024), (4, 0.3, 0.6), (2, 0.05, 0.9)]:
        sos = bandpass_sos(order, low, high)
        x = rng.standard_normal(12000)
        assert sosfilt(sos, x).tobytes() == signal.sosfilt(sos, x).tobytes()
    sos = bandpass_sos(4, 0.2, 0.3)
    t = np.arange(4000)
    inside, outside = np.sin(np.pi * 0.25 * t), np.sin(np.pi * 0.05 * t)
    assert np.std(sosfilt(sos, inside)[2000:]) > 0.69 and np.std(sosfilt(sos, outside)[2000:]) < 0.01


def test_bad_bands_and_sections_are_refused():
    with pytest.raises(BenchmarkError, match="0 < low < high < 1"):
        bandpass_sos(4, 0.5, 0.4)
    with pytest.raises(BenchmarkError, match="order"):
        bandpass_sos(0, 0.1, 0.2)
    with pytest.raises(BenchmarkError, match="a0 = 1"):
        sosfilt(np.ones((2, 6)) * 2, np.zeros(5))
