"""The colour sensor: presets, the colour camera beside the depth camera, noise, white balance, sRGB."""

import dataclasses
import hashlib
import math

import numpy as np
import pytest

from benchmark.camera import colour_sensor as CS
from benchmark.camera.appearance import Lighting, kelvin_to_rgb
from benchmark.camera.camera import load_camera
from benchmark.errors import BenchmarkError
from benchmark.world.scenario import SENSORS

SRGB_TABLE_SHA256 = "02387f3d0fb18f89bd923d54abccebc15685f8587ac91b4f4e2ddd8b3e953b83"
NORMAL_TABLE_SHA256 = "4c2f5f42f122b6bd035838527b999a2a71644434978501f302767ff79fd4dada"


def test_lookup_tables_are_pinned_and_right():
    s, n = CS.srgb_table(), CS.normal_table()
    assert hashlib.sha256(s.tobytes()).hexdigest() == SRGB_TABLE_SHA256
    assert hashlib.sha256(n.tobytes()).hexdigest() == NORMAL_TABLE_SHA256
    assert s[0] == 0 and s[-1] == 255 and s[32767] == 188  # sRGB(0.5) = 0.7354 -> 187.5 -> 188
    assert s[int(0.0031308 * 65535 + 0.5)] == 10  # the linear segment's end: 0.04045 * 255 = 10.3
    assert n.mean() == pytest.approx(0.0, abs=1e-12) and n.std() == pytest.approx(1.0, abs=2e-5)
    assert n[0] == pytest.approx(-4.3249, abs=1e-4) and np.all(np.diff(n) > 0)
    assert not s.flags.writeable and not n.flags.writeable


def test_presets_have_the_stated_cameras():
    assert tuple(CS.PRESETS) == SENSORS
    ds = CS.colour_preset("ds325")
    assert (ds.width, ds.height, ds.hfov_deg, ds.vfov_deg) == (640, 480, 63.2, 49.3)
    kin = CS.colour_preset("kinect-v1")
    assert (kin.hfov_deg, kin.vfov_deg, kin.offset_m) == (62.0, 48.6, (0.025, 0.0, 0.0))
    ideal = CS.colour_preset("ideal")
    assert not ideal.noise and ideal.exposure_s == 0 and ideal.offset_m == (0.0, 0.0, 0.0)
    with pytest.raises(BenchmarkError, match="ds325, kinect-v1, ideal"):
        CS.colour_preset("nope")


def test_colour_camera_sits_beside_the_depth_camera_with_its_field_of_view():
    depth = load_camera()
    cam = CS.colour_camera(depth, CS.colour_preset("ds325"))
    assert (cam.width, cam.height) == (640, 480)
    assert cam.K[0, 0] == pytest.approx(320 / math.tan(math.radians(31.6)))
    assert cam.K[1, 1] == pytest.approx(240 / math.tan(math.radians(24.65)))
    assert abs(cam.K[0, 0] / cam.K[1, 1] - 1) < 0.01  # the 63.2 x 49.3 degree field is 4:3: square pixels
    assert (cam.K[0, 2], cam.K[1, 2]) == (319.5, 239.5)
    np.testing.assert_array_equal(cam.T_world_cam[:3, :3], depth.T_world_cam[:3, :3])
    # 2.5 cm along the depth camera's x axis
    np.testing.assert_allclose(cam.T_world_cam[:3, 3] - depth.T_world_cam[:3, 3], 0.025 * depth.T_world_cam[:3, 0],
                               atol=1e-15)
    ideal = CS.colour_camera(depth, CS.ColourSensor.ideal())
    np.testing.assert_array_equal(ideal.T_world_cam, depth.T_world_cam)
    np.testing.assert_allclose(ideal.K[:2, :2], 2 * depth.K[:2, :2])  # the depth camera's field, twice the pixels


def test_ideal_sensor_is_the_encoded_radiance_and_draws_nothing():
    rad = np.random.default_rng(0).random((20, 30, 3), dtype=np.float32) * 1.2
    rng = np.random.default_rng(1)
    state = rng.bit_generator.state
    out = CS.ColourSensor.ideal().measure(rad, rng)
    assert rng.bit_generator.state == state
    table = CS.srgb_table()
    expected = table[np.floor(np.clip(rad.astype(np.float64), 0, 1) * 65535 + 0.5).astype(int)]
    np.testing.assert_array_equal(out, expected)
    np.testing.assert_array_equal(CS.encode(rad), expected)


def _white(kelvin):
    rgb = kelvin_to_rgb(kelvin)
    return Lighting(ambient=0.2 * rgb, direction=np.array([[0.0, 0.0, -1.0]]), rgb=0.6 * rgb[None], kelvin=np.array([kelvin]))


def test_noise_has_the_shot_and_read_noise_std():
    """A flat patch's code spread equals the model's sigma through the sRGB curve's slope, plus
    the uint8 step's 1/12 (within 4 % over 120 000 values), at two levels; the mean is the
    noise-free code."""
    sensor = dataclasses.replace(CS.colour_preset("ds325"), white_balance="daylight")
    rng = np.random.default_rng(5)
    for L in (0.4, 0.08):
        rad = np.full((200, 200, 3), L, dtype=np.float32)
        codes = sensor.measure(rad, rng).astype(np.float64)
        e = float(np.float32(L)) * sensor.full_well_e / sensor.saturation_radiance
        x = e / sensor.full_well_e
        sigma_x = math.sqrt(e + sensor.read_noise_e**2) / sensor.full_well_e
        slope = 255 * 1.055 / 2.4 * x ** (1 / 2.4 - 1)  # d code / d x
        expected = math.sqrt((sigma_x * slope) ** 2 + 1 / 12)
        assert codes.std() == pytest.approx(expected, rel=0.04), L
        assert codes.mean() == pytest.approx(255 * (1.055 * x ** (1 / 2.4) - 0.055), abs=0.1)
    clean = dataclasses.replace(sensor, noise=False).measure(np.full((4, 4, 3), 0.4, np.float32), None)
    assert np.ptp(clean) == 0


def test_draws_one_raw_word_per_four_values_in_c_order():
    sensor = CS.colour_preset("ds325")
    rad = np.full((3, 5, 3), 0.3, dtype=np.float32)
    a, b = np.random.default_rng(2), np.random.default_rng(2)
    one = sensor.measure(rad, a, _white(5000.0))
    b.bit_generator.random_raw(12)  # ceil(45 / 4)
    assert a.bit_generator.state == b.bit_generator.state
    np.testing.assert_array_equal(one, sensor.measure(rad, np.random.default_rng(2), _white(5000.0)))


def test_auto_white_balance_neutralises_the_light_and_daylight_keeps_its_cast():
    warm = _white(3000.0)
    rad = (0.5 * warm.white()).astype(np.float32) * np.ones((2, 2, 3), np.float32)  # a grey card
    auto = dataclasses.replace(CS.colour_preset("ds325"), noise=False)
    day = dataclasses.replace(auto, white_balance="daylight")
    g = auto.gains(warm)
    assert g[1] == 1.0 and g[0] < 1.0 < g[2]
    a, d = auto.measure(rad, None, warm)[0, 0].astype(int), day.measure(rad, None, warm)[0, 0].astype(int)
    assert np.ptp(a) <= 1  # neutral
    assert d[0] - d[2] > 60  # a warm cast
    with pytest.raises(BenchmarkError, match="lighting"):
        auto.measure(rad, None)


def test_settings_are_validated():
    for kwargs, match in (({"max_samples": 4}, "odd"), ({"white_balance": "tungsten"}, "daylight, auto"),
                          ({"hfov_deg": None}, "vfov_deg"), ({"exposure_s": -1.0}, "exposure_s"),
                          ({"width": 0}, "width"), ({"offset_m": (0, 0)}, "offset_m")):
        with pytest.raises(BenchmarkError, match=match):
            CS.ColourSensor(**kwargs)
    with pytest.raises(BenchmarkError, match="generator"):
        CS.colour_preset("ds325").measure(np.zeros((2, 2, 3), np.float32), None, _white(4000.0))
