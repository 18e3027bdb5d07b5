"""Sensor model: noise statistics, quantisation, range limits, edges, grazing angles, seeding."""

import numpy as np
import pytest

from benchmark.camera.sensor import SensorModel, dequantise, quantise
from benchmark.camera.sensor_kernels import _incidence_cos
from benchmark.errors import BenchmarkError

H, W = 240, 320
K = np.array([[212.0, 0.0, 159.5], [0.0, 216.0, 119.5], [0.0, 0.0, 1.0]])


def plane_depth(normal, offset):
    """Exact depth of the plane n . X = offset seen by the camera K, (H, W); 0 where behind."""
    v, u = np.mgrid[0:H, 0:W]
    rays = np.stack([(u - K[0, 2]) / K[0, 0], (v - K[1, 2]) / K[1, 1], np.ones((H, W))], axis=-1)
    z = offset / (rays @ normal)
    return np.where(z > 0, z, 0).astype(np.float32), rays


def test_gaussian_noise_has_the_requested_std_on_valid_pixels():
    z, _ = plane_depth(np.array([0.0, 0.3, 1.0]), 0.6)
    for sigma in (0.002, 0.01):
        sensor = SensorModel(noise_m=sigma)
        out = np.stack([sensor.measure(z, K, np.random.default_rng(1)) for _ in range(1)])[0]
        valid = out > 0
        assert valid.mean() > 0.9
        err = out[valid] - z[valid]
        assert np.std(err) == pytest.approx(sigma, rel=0.05)
        assert abs(np.mean(err)) < 0.05 * sigma


def test_same_seed_same_frames_other_seed_other_frames():
    z, _ = plane_depth(np.array([0.1, 0.3, 1.0]), 0.5)
    sensor = SensorModel(noise_m=0.01, dropout=0.1)

    def video(seed):
        rng = np.random.default_rng(seed)
        return np.stack([sensor.measure(z, K, rng) for _ in range(3)])

    a, b, c = video(7), video(7), video(8)
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a, c)
    assert not np.array_equal(a[0], a[1])  # fresh noise every frame


def test_quantisation_to_whole_millimetres_and_exact_round_trip():
    z, _ = plane_depth(np.array([0.0, 0.2, 1.0]), 0.5)
    out = SensorModel(noise_m=0.003).measure(z, K, np.random.default_rng(3))
    counts = np.rint(out.astype(np.float64) / 0.001).astype(np.int64)
    np.testing.assert_array_equal(dequantise(counts, 0.001), out)  # bit-identical
    assert np.max(np.abs(out - counts * 0.001)) < 1e-7
    x = np.array([0.12345, 0.5, 0.9996], dtype=np.float32)
    np.testing.assert_allclose(quantise(x, 0.001), [0.123, 0.5, 1.0], atol=1e-7)


def test_range_limits_drop_near_and_far_pixels():
    z, _ = plane_depth(np.array([0.0, 1.59, 1.0]), 0.19)  # depth 0.1 .. 1.6 m over the image
    assert z[z > 0].min() < 0.15 and z.max() > 1.0
    out = SensorModel(edge_jump_m=None, grazing_deg=None).measure(z, K, np.random.default_rng(0))
    inside = (z >= 0.15) & (z <= 1.0)
    np.testing.assert_array_equal(out > 0, inside)
    unlimited = SensorModel.ideal().measure(z, K, np.random.default_rng(0))
    np.testing.assert_array_equal(unlimited, z)  # the ideal sensor changes nothing


def test_pixels_on_both_sides_of_a_depth_jump_are_dropped():
    z = np.full((H, W), 0.6, dtype=np.float32)
    z[:, 100:] = 0.7  # 10 cm step between columns 99 and 100
    z[50:60, 200:210] = 0.71  # 1 cm bump: below the 2 cm threshold
    z[:, 300:] = 0.0  # nothing in view: its border is an edge too
    out = SensorModel(grazing_deg=None).measure(z, K, np.random.default_rng(0))
    missing = out == 0
    np.testing.assert_array_equal(np.flatnonzero(missing.all(axis=0)), [99, 100, 299, *range(300, 320)])
    assert not missing[:, :99].any() and not missing[:, 101:299].any()


def test_incidence_angle_of_a_plane_matches_geometry_and_grazing_pixels_are_dropped():
    n = np.array([0.0, -1.0, 0.0])  # a floor 0.3 m below a level camera: edge-on at the horizon
    z, rays = plane_depth(n, -0.3)
    c_true = np.abs(rays @ n) / np.linalg.norm(rays, axis=-1)
    c = _incidence_cos(z, K)
    seen = z > 0
    np.testing.assert_allclose(c[seen], c_true[seen], atol=1e-5)
    sensor = SensorModel(quantum_m=None, min_range_m=0.0, max_range_m=np.inf, edge_jump_m=None, grazing_deg=80.0)
    ok = sensor.measurable(z, K)
    grazing = c_true < np.cos(np.deg2rad(80.0))
    assert 0.2 < grazing[seen].mean() < 0.5
    agree = ok[seen] == ~grazing[seen]
    assert agree.mean() > 0.995  # disagreement only within float error of the 80 degree line


def test_random_dropout_removes_the_requested_fraction():
    z = np.full((H, W), 0.5, dtype=np.float32)
    out = SensorModel(dropout=0.25).measure(z, K, np.random.default_rng(4))
    assert (out == 0).mean() == pytest.approx(0.25, abs=0.01)


@pytest.mark.parametrize(
    "kwargs, field",
    [
        (dict(noise_m=-0.01), "noise_m"),
        (dict(quantum_m=0.0), "quantum_m"),
        (dict(min_range_m=0.5, max_range_m=0.4), "max_range_m"),
        (dict(edge_jump_m=-1.0), "edge_jump_m"),
        (dict(grazing_deg=95.0), "grazing_deg"),
        (dict(dropout=1.0), "dropout"),
    ],
)
def test_bad_settings_are_rejected_naming_the_field(kwargs, field):
    with pytest.raises(BenchmarkError, match=f"SensorModel.{field} must be"):
        SensorModel(**kwargs)


def test_measure_rejects_a_video():
    with pytest.raises(BenchmarkError, match=r"shape \(H, W\)"):
        SensorModel().measure(np.zeros((2, H, W)), K, np.random.default_rng(0))


def test_noise_is_normally_distributed_also_on_images_with_an_odd_pixel_count():
    from scipy import stats

    sensor = SensorModel(noise_m=0.01, quantum_m=None, edge_jump_m=None, grazing_deg=None)
    for shape in ((H, W), (239, 319)):
        z = np.full(shape, 0.5, dtype=np.float32)
        err = (sensor.measure(z, K, np.random.default_rng(5)) - z).ravel().astype(np.float64) / 0.01
        assert stats.kstest(err, "norm").pvalue > 0.01
        assert np.mean(np.abs(err) > 2) == pytest.approx(2 * stats.norm.sf(2), abs=0.003)
        assert np.mean(np.abs(err) > 3) == pytest.approx(2 * stats.norm.sf(3), abs=0.001)
        assert abs(np.corrcoef(err[:-1], err[1:])[0, 1]) < 0.02  # neighbouring pixels independent


def test_measurement_is_depth_plus_sigma_times_one_float32_normal_per_pixel_then_rounded():
    """The documented draw: rng.standard_normal((H, W), float32) once per frame, scaled by sigma
    (another draw or order would be off by about sigma, far more than half a quantum)."""
    z, _ = plane_depth(np.array([0.1, 0.3, 1.0]), 0.5)
    sensor = SensorModel(noise_m=0.01)
    rng = np.random.default_rng(11)
    out = np.stack([sensor.measure(z, K, rng) for _ in range(2)])
    normals = np.random.default_rng(11).standard_normal((2, H, W), dtype=np.float32)
    kept = out > 0
    assert kept.mean() > 0.9
    noisy = np.broadcast_to(z, out.shape) + np.float32(0.01) * normals
    assert np.abs(out - noisy)[kept].max() <= 0.0005 + 1e-6
    np.testing.assert_array_equal(kept, sensor.measurable(z, K) & (noisy > 0.0005))
