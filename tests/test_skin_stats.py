"""The skin's depth against the primitives' (benchmark.camera.skin_stats)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from benchmark.camera.render import render
from benchmark.camera.skin_stats import collision_gap, hand_depth_difference
from benchmark.errors import BenchmarkError
from benchmark.world.scenario import Scenario
from benchmark.world.simulate import simulate


def test_the_statistics_of_a_known_difference():
    depth = np.full((1, 4, 4), 0.5)
    labels = np.full((1, 4, 4), 10, np.uint8)
    other = depth.copy()
    other[0, 0, :] += 0.004
    other_labels = labels.copy()
    other_labels[0, 3, 3] = 2  # one pixel is box in one render
    s = hand_depth_difference(other, other_labels, depth, labels)
    assert s["median_mm"] == pytest.approx(0.0) and s["p90_abs_mm"] == pytest.approx(4.0)
    assert s["silhouette_frac"] == pytest.approx(1 / 16)
    with pytest.raises(BenchmarkError, match="no pixel shows the hand"):
        hand_depth_difference(depth, labels * 0, depth, labels)


def test_the_skin_departs_from_the_primitives_by_millimetres_over_the_hand():
    sc = Scenario(task="lift", seed=3, duration_s=1.0, noise_m=0.0, sensor="ideal", hand_surface="capsules")
    prim = render(simulate(sc))
    skin = render(simulate(dataclasses.replace(sc, hand_surface="skin")))
    assert np.array_equal(skin.truth.box_pos, prim.truth.box_pos)  # the same simulation
    s = hand_depth_difference(skin.depth.depth_m, skin.labels, prim.depth.depth_m, prim.labels)
    # measured on four 3 s episodes: |median| 1.1-1.2 mm, 90th percentile 4.4-5.8 mm, silhouettes 3.7-4.7 %
    assert 0.6 < s["median_abs_mm"] < 2.0 and 3.0 < s["p90_abs_mm"] < 8.0 and 0.02 < s["silhouette_frac"] < 0.08


def test_the_skin_is_the_colliding_geometry_where_contacts_happen_and_departs_elsewhere():
    from benchmark.world.assets import hand_model

    gap = collision_gap(hand_model(Scenario()))
    assert gap["pulp_mm"][0] < 0.15 and gap["pulp_mm"][1] < 0.8  # measured 0.07 and 0.48 mm
    assert gap["palm_mm"][0] < 1.5  # measured 0.77 mm (the hypothenar eminence bulges to 6.9 mm)
    assert 0.25 < gap["skin_mm"][0] < 0.8 and 1.8 < gap["skin_mm"][1] < 3.5  # measured 0.45 and 2.65 mm
