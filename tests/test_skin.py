"""The skin: closed pieces, fitted to the colliding primitives where contacts happen, per person,
skinned consistently, and the pulp's force-compression law (benchmark.world.skin)."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from benchmark.world import skin as S
from benchmark.world.anatomy import draw_anatomy
from benchmark.world.assets import hand_model
from benchmark.world.hand import hand_model as hand_of_anatomy
from benchmark.world.scenario import Scenario


@pytest.fixture(scope="module")
def hand():
    return hand_model(Scenario())


@pytest.fixture(scope="module")
def skin(hand):
    return S.skin_of(hand)


def test_every_piece_is_closed_outward_and_labelled_by_its_digit(hand, skin):
    mesh = trimesh.Trimesh(skin.bind_pose(hand), skin.faces, process=False)
    parts = mesh.split(only_watertight=False)
    assert len(parts) == 17  # the palm's slab and thenar eminence, three pieces per digit
    assert all(p.is_watertight and p.is_winding_consistent and p.volume > 0 for p in parts)
    assert set(np.unique(skin.face_label)) == {9, 10, 11, 12, 13, 14}
    # a face's label is its vertices' finger's
    finger = skin.finger[skin.faces[:, 0]]
    assert np.array_equal(skin.face_label, np.where(finger < 0, 9, 10 + finger))


def test_the_pulp_reaches_the_pad_sphere_below_its_centre(hand, skin):
    for k, seg in enumerate(hand.fingertip_segment):  # the lowest skin point under the pad's centre
        v = skin.local[skin.segment == seg]
        centre, r = np.asarray(hand.fingertip_offset[k]), hand.fingertip_radius[k]
        below = v[np.argmin(v[:, 2])]
        assert below[2] == pytest.approx(centre[2] - r, abs=1e-9)


def test_a_digit_is_wider_than_deep_and_its_nail_flattens_its_back(hand, skin):
    seg = hand.fingertip_segment[1]  # the index's distal phalanx
    v = skin.local[skin.segment == seg]
    r = hand.fingertip_radius[1]
    ring = v[np.abs(v[:, 1] - hand.fingertip_offset[1][1] * 0.9) < 0.1 * r]
    width, dorsal, palmar = np.ptp(ring[:, 0]) / 2, ring[:, 2].max(), -ring[:, 2].min()
    assert width > 1.03 * palmar and dorsal < 0.8 * palmar  # elliptic, the nail's side flat


def test_each_person_has_their_own_skin(hand, skin):
    other = hand_of_anatomy(draw_anatomy(np.random.default_rng(7), "female"))
    theirs = S.skin_of(other)
    assert theirs.local.shape == skin.local.shape  # the same mesh layout on another anatomy
    ratio = np.ptp(theirs.bind_pose(other)[:, 1]) / np.ptp(skin.bind_pose(hand)[:, 1])
    assert ratio != pytest.approx(1.0, abs=1e-3)


def test_the_parent_coordinates_are_the_same_point_at_the_bind_pose(hand, skin):
    R, t = S._bind_frames(hand)
    own = np.einsum("vij,vj->vi", R[skin.segment], skin.local) + t[skin.segment]
    par = np.einsum("vij,vj->vi", R[skin.parent], skin.parent_local) + t[skin.parent]
    assert np.max(np.abs(own - par)) < 1e-15
    assert skin.parent_weight.max() == S.BLEND_AT_JOINT and skin.parent_weight[skin.segment == 0].max() == 0


def test_pulp_compression_follows_serinas_law():
    f = np.array([0.0, 0.5, 1.0, 5.0, 20.0])
    d = S.pulp_indentation_m(f) * 1e3
    assert d[0] == 0 and np.all(np.diff(d) > 0)
    assert d[2] == pytest.approx(1.348, abs=1e-3) and d[3] == pytest.approx(2.405, abs=1e-3)
    b, m = S.PULP_STIFFNESS_N_PER_MM, S.PULP_EXPONENT_PER_MM
    assert np.allclose(b / m * np.expm1(m * d), f, rtol=1e-12, atol=1e-15)  # the law inverted
    # its stiffness dF/dd = b exp(m d), by finite differences of the inverse
    h = 1e-6
    slope = 2 * h / ((S.pulp_indentation_m(1.0 + h) - S.pulp_indentation_m(1.0 - h)) * 1e3)
    assert slope == pytest.approx(b * np.exp(m * d[2]), rel=1e-6)
    assert S.pulp_indentation_m(-3.0) == 0
