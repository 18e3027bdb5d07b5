"""Depth previews: colour map, frame strip, PNG and GIF files."""

import numpy as np
import pytest
from matplotlib import colormaps
from PIL import Image

from benchmark.commands.pictures.depth_preview import COLOUR_BAR_HEIGHT, TURBO_SPAN, colorize, strip, write_preview
from benchmark.errors import BenchmarkError


def video(T=12, H=40, W=32):
    d = np.linspace(0.15, 1.0, W, dtype=np.float32)[None, None, :].repeat(H, 1).repeat(T, 0).copy()
    d[:, :4, :4] = 0.0  # no measurement
    return d


def test_colorize_maps_the_range_onto_turbo_and_missing_to_black():
    rgb = colorize(np.array([[0.0, 0.15, 1.0, 2.0, 0.575]]))
    turbo = colormaps["turbo"]
    lo, hi = TURBO_SPAN
    np.testing.assert_array_equal(rgb[0, 0], [0, 0, 0])
    np.testing.assert_array_equal(rgb[0, 1], np.round(np.array(turbo(lo)[:3]) * 255))
    np.testing.assert_array_equal(rgb[0, 2], np.round(np.array(turbo(hi)[:3]) * 255))
    np.testing.assert_array_equal(rgb[0, 3], rgb[0, 2])  # clipped beyond the far end
    np.testing.assert_allclose(rgb[0, 4], np.round(np.array(turbo((lo + hi) / 2)[:3]) * 255), atol=4)  # 256-entry table


def test_no_depth_is_drawn_near_the_black_of_no_measurement_and_the_saved_bar_keeps_its_colours(tmp_path):
    ramp = np.linspace(0.15, 1.0, 200)
    rgb = colorize(ramp[None]).astype(int)[0]
    assert rgb.max(axis=1).min() >= 120  # brightest channel at the map's darkest end (measured 203)
    d = np.tile(ramp[None, None, :], (2, 60, 1)).astype(np.float32)
    d[:, :5, :5] = 0.0
    path = write_preview(d, fps=30.0, out_dir=tmp_path, num=1, gif=False)[0]
    with Image.open(path) as png:
        saved = np.asarray(png.convert("RGB")).astype(int)
    # the frame and the colour bar as saved: every depth within a few levels of its colour, none black or grey
    np.testing.assert_allclose(saved[30, 10:], rgb[10:], atol=8)
    bar = saved[60 + 10, 50:150]
    expected = colorize(np.linspace(0.15, 1.0, 100)[None]).astype(int)[0]
    np.testing.assert_allclose(bar, expected, atol=8)
    assert (saved[30, 10:].max(axis=1) >= 120).all() and (saved[:5, :5] == 0).all()


def test_strip_holds_evenly_spaced_frames_with_gaps():
    d = video()
    d[-1] += 0.1  # the last frame differs, so it must be the strip's last panel
    s = strip(d, np.arange(12) / 30, num=4)
    assert s.shape == (40, 4 * 32 + 3 * 4, 3)
    np.testing.assert_array_equal(s[:, 32:36], 255)
    np.testing.assert_array_equal(s[20:, -32:], colorize(d[-1])[20:])  # below the time stamp
    assert strip(d[:2], np.arange(2) / 30, num=6).shape[1] == 2 * 32 + 4


def test_write_preview_writes_a_png_strip_and_a_gif(tmp_path):
    d = video(T=30) + 0.02 * np.arange(30, dtype=np.float32)[:, None, None]  # frames differ (GIF merges repeats)
    paths = write_preview(d, fps=30.0, out_dir=tmp_path / "new", num=3, gif_fps=15.0)
    assert [p.name for p in paths] == ["depth_preview.png", "depth.gif"]
    with Image.open(paths[0]) as png:
        assert png.size == (3 * 32 + 2 * 4, 40 + COLOUR_BAR_HEIGHT)  # frames above the colour bar
    with Image.open(paths[1]) as gif:
        assert gif.n_frames == 15  # every second frame of 30
        assert gif.info["duration"] == pytest.approx(1000 * 2 / 30, abs=10)  # GIF stores centiseconds
        first = np.asarray(gif.convert("RGB"))
    np.testing.assert_array_equal(first[0, 0], [0, 0, 0])  # no measurement
    np.testing.assert_allclose(first[10, :], colorize(d[0])[10, :], atol=6)  # the colour map at 255 levels
    assert not list((tmp_path / "new").glob("*.tmp"))


@pytest.mark.parametrize(
    "call, match",
    [
        (lambda: colorize(np.ones((2, 2)), near_m=1.0, far_m=0.5), "far_m > near_m"),
        (lambda: strip(np.ones((2, 2)), np.zeros(1)), r"shape \(T, H, W\)"),
        (lambda: strip(np.ones((1, 2, 2)), np.zeros(1), num=0), "num must be >= 1"),
        (lambda: write_preview(np.ones((1, 2, 2)), fps=0.0, out_dir="unused"), "frame rates must be > 0"),
    ],
)
def test_bad_input_is_rejected(call, match):
    with pytest.raises(BenchmarkError, match=match):
        call()
