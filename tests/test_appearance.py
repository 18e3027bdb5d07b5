"""Appearance: the person's Monk skin tone, the box's print, the table, the wall and the lights."""

import numpy as np
import pytest

from benchmark.camera import appearance as A
from benchmark.errors import BenchmarkError
from benchmark.world.scenario import Scenario


def test_monk_scale_has_ten_swatches_decoded_by_the_srgb_curve():
    assert len(A.MONK_SRGB) == 10
    # MST1 f6ede4: 0xf6 = 246 -> ((246/255 + 0.055) / 1.055)^2.4
    np.testing.assert_allclose(A.hex_to_linear("f6ede4")[0], ((246 / 255 + 0.055) / 1.055) ** 2.4, rtol=1e-15)
    assert A.srgb_to_linear(0.04) == pytest.approx(0.04 / 12.92)
    lum = [A.hex_to_linear(h) @ [0.2126, 0.7152, 0.0722] for h in A.MONK_SRGB]
    assert np.all(np.diff(lum[:2] + lum[3:]) < 0)  # lighter to darker (MST3 is yellower than MST2, not darker)
    assert lum[0] > 0.8 and lum[-1] < 0.02


def test_skin_tone_is_drawn_per_person_not_per_scenario():
    a, b = A.appearance_of(Scenario(user=3, seed=0)), A.appearance_of(Scenario(user=3, seed=9))
    assert a.skin_tone == b.skin_tone and np.array_equal(a.skin_albedo, b.skin_albedo)
    assert not np.array_equal(a.box_ink, b.box_ink)  # the scene is drawn per scenario
    assert A.appearance_of(Scenario(user=3, seed=0)) .skin_tone == a.skin_tone  # deterministic
    np.testing.assert_array_equal(A.appearance_of(Scenario(user=3, seed=0)).table_par, a.table_par)


def test_tones_are_uniform_over_the_ten_and_the_jitter_is_small():
    tones, ratios = [], []
    for user in range(400):
        tone, albedo = A.skin_of(user)
        tones.append(tone)
        ratios.append(albedo / (A.hex_to_linear(A.MONK_SRGB[tone - 1]) * A.SKIN_REFLECTANCE_SCALE))
    counts = np.bincount(tones, minlength=11)[1:]
    assert counts.min() >= 20 and counts.max() <= 62  # 40 expected each (binomial sd 6)
    ratios = np.asarray(ratios)
    common = ratios.mean(axis=1)
    assert np.std(common) == pytest.approx(A.SKIN_LIGHTNESS_JITTER, rel=0.2)
    assert np.abs(ratios - 1).max() < 0.2  # the tone stays recognisable


def test_kelvin_to_rgb_has_unit_luminance_and_warm_lights_are_red():
    for T in (3000.0, 4500.0, 6500.0):
        rgb = A.kelvin_to_rgb(T)
        assert rgb @ [0.2126729, 0.7151522, 0.0721750] == pytest.approx(1.0, abs=1e-4)
    warm, cold = A.kelvin_to_rgb(3000.0), A.kelvin_to_rgb(6500.0)
    assert warm[0] > warm[1] > warm[2] and warm[0] / warm[2] > 2.0
    assert np.ptp(cold) / cold.mean() < 0.1  # near the D65 white
    with pytest.raises(BenchmarkError, match="1667"):
        A.kelvin_to_rgb(1000.0)


def test_drawn_lights_and_textures_lie_in_the_stated_ranges():
    for seed in range(30):
        a = A.appearance_of(Scenario(seed=seed))
        light = a.lighting
        assert len(light.kelvin) in (1, 2)
        assert np.all((light.kelvin >= A.KELVIN[0]) & (light.kelvin <= A.KELVIN[1]))
        elevation = np.degrees(np.arcsin(-light.direction[:, 2]))
        np.testing.assert_allclose(np.linalg.norm(light.direction, axis=1), 1.0)
        assert A.KEY_ELEVATION_DEG[0] - 1e-9 <= elevation[0] <= A.KEY_ELEVATION_DEG[1] + 1e-9
        if len(elevation) == 2:
            assert A.FILL_ELEVATION_DEG[0] - 1e-9 <= elevation[1] <= A.FILL_ELEVATION_DEG[1] + 1e-9
        assert np.all((a.box_par[:, 0] >= A.BOX_CELL_M[0]) & (a.box_par[:, 0] <= A.BOX_CELL_M[1]))
        assert np.all(a.box_ink < a.box_base)  # ink darker than the board
        assert np.all(a.table_grain < a.table_base)
        assert np.linalg.norm(a.table_par[:2]) == pytest.approx(1.0)
        assert np.all((a.background > 0.1) & (a.background < 0.5))


def test_ablations_switch_each_source_off_alone():
    a = A.appearance_of(Scenario(user=7, seed=2))
    fixed = a.ablated(skin_tone=9)
    assert fixed.skin_tone == 9 and np.array_equal(fixed.skin_albedo, A.hex_to_linear(A.MONK_SRGB[8]))
    assert fixed.box_print and fixed.table_texture and fixed.lighting is a.lighting
    assert not a.ablated(box_print=False).box_print and a.ablated(box_print=False).table_texture
    assert not a.ablated(table_texture=False).table_texture
    assert a.ablated(fixed_lighting=True).lighting is A.FIXED_LIGHTING
    plain = a.plain()
    assert not plain.box_print and not plain.table_texture
    np.testing.assert_array_equal(plain.box_albedo, a.box_base[0])
    for bad in (0, 11, True, 2.5):
        with pytest.raises(BenchmarkError, match="Monk"):
            a.ablated(skin_tone=bad)


def test_people_of_each_tone_can_be_picked():
    for tone in (1, 5, 10):
        users = A.people_with_tone(tone, 3, start=5)
        assert len(users) == 3 and min(users) >= 5 and users == sorted(users)
        assert all(A.appearance_of(Scenario(user=u)).skin_tone == tone for u in users)
    with pytest.raises(BenchmarkError, match="Monk"):
        A.people_with_tone(0)


def test_the_lightest_skin_reflects_about_six_tenths_in_the_red_and_less_than_a_white_board():
    red = [A.hex_to_linear(h)[0] * A.SKIN_REFLECTANCE_SCALE for h in A.MONK_SRGB]
    assert red[0] == pytest.approx(0.6, abs=0.002) and red[-1] == pytest.approx(0.016, abs=0.002)
    assert np.all(np.diff(red) <= 0.025)  # MST3 is redder than MST2 by 0.022; otherwise lighter tones first
    white_board = A.hex_to_linear("e9e4da")
    assert np.all(A.hex_to_linear(A.MONK_SRGB[0]) * A.SKIN_REFLECTANCE_SCALE < white_board)
