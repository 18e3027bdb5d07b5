"""The flat patch a pressed pulp makes grows with force as a fingertip's (benchmark.camera.pulp_patch)."""

from __future__ import annotations

import numpy as np
import pytest

from benchmark.camera.pulp_patch import patch_area_m2, pressed_fingertip
from benchmark.errors import BenchmarkError
from benchmark.world.assets import hand_model
from benchmark.world.scenario import Scenario
from benchmark.world.skin import pulp_indentation_m


@pytest.fixture(scope="module")
def hand():
    return hand_model(Scenario())


def test_the_patch_grows_with_force_and_saturates_like_a_fingertips(hand):
    forces = [0.25, 0.5, 1.0, 2.0, 5.0, 10.0]
    index = np.array([patch_area_m2(hand, 1, f) for f in forces]) * 1e6
    assert patch_area_m2(hand, 1, 0.0) == 0.0 and np.all(np.diff(index) > 0)
    # of the order of a square centimetre at a few newtons (measured 76 mm^2 at 1 N, 124 at 5 N)
    assert 50 < index[2] < 110 and 90 < index[4] < 170
    assert index[5] / index[4] < 1.3 < index[2] / index[0]  # stiffening: fast at first, then slowly
    # a truncated sphere: area about 2 pi r delta (the lateral factor widens it a little)
    r = hand.fingertip_radius[1]
    sphere = 2 * np.pi * r * pulp_indentation_m(1.0) * 1e6
    assert index[2] == pytest.approx(sphere, rel=0.35)


def test_the_flattened_pulp_lies_on_the_face_and_never_below_it(hand):
    verts, faces, face_z = pressed_fingertip(hand, 0, 5.0)
    assert verts[:, 2].min() == pytest.approx(face_z, abs=1e-15)
    assert np.sum(np.abs(verts[:, 2] - face_z) < 1e-12) > 10


@pytest.mark.parametrize("finger, force, needle", [(5, 1.0, "finger must be in 0..4"), (1, -1.0, "force_n"),
                                                   (1, float("nan"), "force_n")])
def test_bad_arguments_name_the_value(hand, finger, force, needle):
    with pytest.raises(BenchmarkError, match=needle):
        patch_area_m2(hand, finger, force)
