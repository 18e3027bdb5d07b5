"""Depth-sensor presets against their published curves: axial noise, lateral noise, artefacts."""

from dataclasses import replace

import numpy as np
import pytest
from scipy import optimize, stats

from benchmark.camera.sensor import PRESETS, SENSORS, SensorModel, sensor_preset
from benchmark.camera.sensor_kernels import _incidence_cos
from benchmark.errors import BenchmarkError

H, W = 240, 320
K = np.array([[212.0, 0.0, 159.5], [0.0, 216.0, 119.5], [0.0, 0.0, 1.0]])
CENTRE = (slice(90, 150), slice(130, 190))


def tilted_plane(z0: float, theta_deg: float) -> tuple[np.ndarray, np.ndarray]:
    """Exact depth (H, W) of a plane through (0, 0, z0) turned by theta about the camera's y axis,
    and the true incidence angle per pixel [rad]."""
    th = np.deg2rad(theta_deg)
    n = np.array([np.sin(th), 0.0, np.cos(th)])
    v, u = np.mgrid[0:H, 0:W]
    rays = np.stack([(u - K[0, 2]) / K[0, 0], (v - K[1, 2]) / K[1, 1], np.ones((H, W))], axis=-1)
    z = z0 * np.cos(th) / (rays @ n)
    incidence = np.arccos(np.abs(rays @ n) / np.linalg.norm(rays, axis=-1))
    return z.astype(np.float32), incidence


def measured_and_expected_std(sensor: SensorModel, z0: float, theta_deg: float, frames: int = 12):
    """RMS of measured - exact depth on the image centre over frames, and the RMS of the preset's
    published sigma_s(z, theta) over the same pixels."""
    z, inc = tilted_plane(z0, theta_deg)
    rng = np.random.default_rng(int(1000 * z0 + theta_deg))
    err, expected = [], []
    for _ in range(frames):
        out = sensor.measure(z, K, rng)[CENTRE]
        ok = out > 0
        err.append((out - z[CENTRE])[ok])
        expected.append(sensor.axial_sigma(z[CENTRE][ok], inc[CENTRE][ok]))
    err, expected = np.concatenate(err), np.concatenate(expected)
    assert len(err) > 0.25 * frames * 60 * 60  # steep planes leave the range on one side
    return float(np.sqrt(np.mean(err.astype(np.float64) ** 2))), float(np.sqrt(np.mean(expected**2)))


@pytest.mark.parametrize("z0", [0.2, 0.4, 0.6, 0.8, 0.95])
@pytest.mark.parametrize("theta", [5, 30, 60])
def test_ds325_axial_noise_follows_the_time_of_flight_curve_within_5_percent(z0, theta):
    got, want = measured_and_expected_std(sensor_preset("ds325"), z0, theta)
    assert got == pytest.approx(want, rel=0.05)


@pytest.mark.parametrize("z0", [0.5, 1.0, 1.5, 2.0, 2.6])
@pytest.mark.parametrize("theta", [10, 30, 60])
def test_kinect_axial_noise_follows_nguyen_2012_within_5_percent(z0, theta):
    got, want = measured_and_expected_std(sensor_preset("kinect-v1"), z0, theta)
    assert got == pytest.approx(want, rel=0.05)


def test_the_published_curves_themselves():
    ds, kin = PRESETS["ds325"], PRESETS["kinect-v1"]
    assert ds.axial_sigma(1.0) == pytest.approx(0.014)  # data sheet: < 1.4 cm at 1 m
    assert ds.axial_sigma(0.5, np.deg2rad(60)) == pytest.approx(0.014 * 0.25 * 2)
    assert kin.axial_sigma(0.4, 0.0) == pytest.approx(0.0012)
    assert kin.axial_sigma(2.4, 0.0) == pytest.approx(0.0012 + 0.0019 * 4)
    th = np.deg2rad(70)
    assert kin.axial_sigma(1.0, th) == pytest.approx(0.0012 + 0.0019 * 0.36 + 0.0001 * th**2 / (np.pi / 2 - th) ** 2)
    assert kin.lateral_sigma(np.deg2rad(45)) == pytest.approx(0.8 + 0.035)


def wrong_pixels_per_row(sigma: float) -> float:
    """Expected pixels per row on the wrong side of a vertical edge for jitter sigma [px] rounded
    to whole pixels: 2 sum_k P(N(0, sigma) > k + 1/2)."""
    k = np.arange(60)
    return float(2 * np.sum(stats.norm.sf((k + 0.5) / sigma)))


@pytest.mark.parametrize("theta", [10, 30, 60])
def test_kinect_lateral_noise_follows_nguyen_2012_within_5_percent(theta):
    """A vertical step edge: the jitter puts pixels on the wrong side of it; their count per row
    gives the jitter's standard deviation, compared with sigma_L(theta)."""
    fg, inc = tilted_plane(0.8, theta)
    bg, _ = tilted_plane(1.1, theta)
    edge = 160
    z = np.where(np.arange(W)[None, :] < edge, fg, bg).astype(np.float32)
    sensor = replace(PRESETS["kinect-v1"], axial="none", disparity_quantum_px=None, focal_baseline_px_m=0.0,
                     edge_jump_m=None, grazing_deg=None, min_range_m=0.0, max_range_m=np.inf)
    rng = np.random.default_rng(theta)
    rows = slice(20, 220)
    counts = []
    for _ in range(10):
        band = slice(edge - 20, edge + 20)  # where one pixel of jitter moves the depth far less than the step
        out = sensor.measure(z, K, rng)[rows, band]
        is_fg = np.abs(out - fg[rows, band]) < np.abs(out - bg[rows, band])
        counts.append(is_fg[:, 20:].sum(axis=1) + (~is_fg[:, :20]).sum(axis=1))
    mean = float(np.mean(counts))
    sigma = optimize.brentq(lambda s: wrong_pixels_per_row(s) - mean, 0.05, 20.0)
    want = sensor.lateral_sigma(inc[120, edge])
    assert sigma == pytest.approx(want, rel=0.05)


def test_lateral_jitter_leaves_a_continuous_surface_alone():
    z, _ = tilted_plane(0.6, 20)
    sensor = replace(SensorModel.ideal(), lateral="constant", lateral_px=1.0)
    np.testing.assert_array_equal(sensor.measure(z, K, np.random.default_rng(0)), z)


def test_multipath_reads_deeper_beside_a_closer_surface_only():
    z = np.full((H, W), 0.6, dtype=np.float32)
    z[100:140, 140:180] = 0.55  # a block 5 cm closer (a finger on a face)
    sensor = replace(SensorModel.ideal(), multipath_m=0.008, multipath_window_px=5, multipath_depth_m=0.03)
    bias = sensor.measure(z, K, np.random.default_rng(0)) - z
    assert np.all(bias >= 0)
    assert bias[120, 181] > 0.002 and bias[120, 139] > 0.002  # the face just beside the block
    assert bias[120, 181] <= 0.008 + 1e-7
    assert np.all(bias[100:140, 140:180] == 0)  # the closer block itself
    assert np.all(bias[:, :130] == 0) and np.all(bias[:, 190:] == 0)  # farther than the window


def test_flying_pixels_survive_at_edges_with_mixed_depth():
    z = np.full((H, W), 0.6, dtype=np.float32)
    z[:, 160:] = 0.7
    sensor = replace(SensorModel.ideal(), edge_jump_m=0.02, flying_frac=0.3)
    out = sensor.measure(z, K, np.random.default_rng(1))
    edge = out[:, 159:161]
    kept = edge > 0
    assert kept.mean() == pytest.approx(0.3, abs=0.05)
    assert np.all((edge[kept] >= 0.6 - 1e-6) & (edge[kept] <= 0.7 + 1e-6))
    assert np.all(out[:, 159][kept[:, 0]] > 0.6)  # the near side mixed toward the far one
    np.testing.assert_array_equal(out[:, :159], z[:, :159])


def test_kinect_depth_is_quantised_in_disparity():
    z, _ = tilted_plane(1.5, 30)
    sensor = replace(PRESETS["kinect-v1"], axial="none", lateral="none")
    out = sensor.measure(z, K, np.random.default_rng(0))
    mm = out[out > 0].astype(np.float64) * 1000
    np.testing.assert_allclose(mm, np.rint(mm), atol=1e-3)  # whole millimetres
    raw = replace(sensor, quantum_m=None).measure(z, K, np.random.default_rng(0))
    d = 580.0 * 0.075 / raw[raw > 0].astype(np.float64) / 0.125
    np.testing.assert_allclose(d, np.rint(d), atol=1e-3)  # before: whole eighths of a pixel of disparity
    step = np.diff(np.unique(out[out > 0]))
    assert 0.5 * 1.5**2 * 0.125 / 43.5 < np.median(step) < 2 * 1.5**2 * 0.125 / 43.5  # ~6 mm at 1.5 m


def test_presets_by_name_and_bad_names():
    assert SENSORS == ("ds325", "kinect-v1", "ideal")
    assert sensor_preset("ideal", 0.01).noise_m == 0.01
    assert sensor_preset("ds325").min_range_m == 0.15 and sensor_preset("kinect-v1").min_range_m == 0.4
    with pytest.raises(BenchmarkError, match="sensor must be one of ds325, kinect-v1, ideal; got 'kinect'"):
        sensor_preset("kinect")
    with pytest.raises(BenchmarkError, match="SensorModel.axial must be one of"):
        SensorModel(axial="sonar")
    with pytest.raises(BenchmarkError, match="SensorModel.focal_baseline_px_m must be > 0 with a disparity quantum"):
        SensorModel(disparity_quantum_px=0.125)


def test_white_noise_adds_to_the_sensors_own_in_variance():
    z, inc = tilted_plane(0.8, 30)
    s = sensor_preset("ds325", 0.01)
    sig = s.sigma(z[120, 160], inc[120, 160])
    own = s.axial_sigma(z[120, 160], inc[120, 160])
    assert sig == pytest.approx(np.sqrt(0.01**2 + own**2 - 0.001**2 / 12))


def test_incidence_of_a_tilted_plane():
    z, inc = tilted_plane(0.7, 45)
    c = _incidence_cos(z, K)
    np.testing.assert_allclose(c[CENTRE], np.cos(inc[CENTRE]), atol=1e-4)
