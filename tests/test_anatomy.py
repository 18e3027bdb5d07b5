"""Hand anatomies (benchmark.world.anatomy): the template at a scale, the generic hand, drawn hands."""

import numpy as np
import pytest

from benchmark.errors import ScenarioError
from benchmark.world.anatomy import (
    DIGIT_LENGTH_SD,
    HAND_SIZE,
    TEMPLATE_HAND_BREADTH_M,
    TEMPLATE_HAND_LENGTH_M,
    Anatomy,
    draw_anatomy,
)
from benchmark.world.hand import hand_model
from fsv.hand import fingertip_centres, forward_kinematics_qpos

FLAT = np.concatenate([[0, 0, 0, 1, 0, 0, 0], np.zeros(20)])


def _measured_length(hand) -> float:
    """The palm capsules' wrist-side end points to the tip of the middle finger's pad, hand flat, [m]."""
    tip = fingertip_centres(hand, forward_kinematics_qpos(hand, FLAT))[2]
    return tip[1] + hand.fingertip_radius[2] - np.min(hand.geom_fromto[hand.geom_segment == 0][:, [1, 4]])


def test_a_template_anatomy_is_the_uniformly_scaled_hand_bit_for_bit():
    a, b = hand_model(Anatomy.template(0.92)), hand_model(0.92)
    assert a is b  # the same cached model
    assert Anatomy.template(1.08).hand_length_m == TEMPLATE_HAND_LENGTH_M * 1.08
    assert Anatomy.template(1.08).hand_breadth_m == TEMPLATE_HAND_BREADTH_M * 1.08


def test_length_and_breadth_scales_act_along_and_across_the_hand():
    ref, long_ = hand_model(Anatomy.template(1.0)), hand_model(Anatomy(length_scale=1.1, breadth_scale=1.0))
    broad = hand_model(Anatomy(length_scale=1.0, breadth_scale=1.1))
    np.testing.assert_allclose(long_.geom_radius, ref.geom_radius)
    np.testing.assert_allclose(broad.geom_radius, 1.1 * ref.geom_radius)
    # the index finger's base moves along y with the length, along x with the breadth
    b = ref.segment_names.index("index_prox")
    np.testing.assert_allclose(long_.offset_pos[b], ref.offset_pos[b] * [1.0, 1.1, 1.0])
    np.testing.assert_allclose(broad.offset_pos[b], ref.offset_pos[b] * [1.1, 1.0, 1.1])
    assert _measured_length(long_) == pytest.approx(1.1 * _measured_length(ref), rel=0.01)


def test_digit_and_phalanx_factors_change_only_their_segments():
    phal = [[1.0] * 3 for _ in range(5)]
    phal[1][2] = 1.1  # the index's distal phalanx
    a = Anatomy(length_scale=1.0, breadth_scale=1.0, digit_length=(1.0, 1.0, 1.0, 0.95, 1.0),
                phalanx_length=tuple(map(tuple, phal)), digit_radius=(1.0, 1.0, 1.0, 1.0, 1.05))
    ref, h = hand_model(1.0), hand_model(a)
    seg = ref.segment_names
    ring_mid, ring_dist = seg.index("ring_mid"), seg.index("ring_dist")  # offset of a child = parent's length
    assert h.offset_pos[ring_mid][1] == pytest.approx(0.95 * ref.offset_pos[ring_mid][1])
    assert h.offset_pos[ring_dist][1] == pytest.approx(0.95 * ref.offset_pos[ring_dist][1])
    index_pad, middle_pad = 1, 2
    assert h.fingertip_offset[index_pad][1] > ref.fingertip_offset[index_pad][1]
    np.testing.assert_array_equal(h.fingertip_offset[middle_pad], ref.fingertip_offset[middle_pad])
    little = np.isin(h.geom_segment, [seg.index(f"little_{s}") for s in ("prox", "mid", "dist")])
    np.testing.assert_allclose(h.geom_radius[little], 1.05 * ref.geom_radius[little])
    np.testing.assert_array_equal(h.geom_radius[~little], ref.geom_radius[~little])


def test_a_drawn_hand_has_the_drawn_length_and_the_model_measures_it():
    for seed in range(6):
        a = draw_anatomy(np.random.default_rng(seed), "female")
        # the property counts the middle digit's factors; the model's flat hand measures the same
        extra = a.hand_length_m / a.length_scale - TEMPLATE_HAND_LENGTH_M  # the middle digit's, at scale 1
        assert _measured_length(hand_model(a)) == pytest.approx(
            a.length_scale * (_measured_length(hand_model(1.0)) + extra), rel=1e-12)
        assert abs(extra) > 1e-4  # the factors did change the digit


def test_drawn_hands_follow_the_cited_distributions():
    rng = np.random.default_rng(0)
    for sex in ("male", "female"):
        hands = [draw_anatomy(rng, sex) for _ in range(1500)]
        L = np.array([h.hand_length_m for h in hands])
        B = np.array([h.hand_breadth_m for h in hands])
        (ml, sl), (mb, sb) = HAND_SIZE[sex]["length_m"], HAND_SIZE[sex]["breadth_m"]
        assert L.mean() == pytest.approx(ml, abs=0.001) and L.std() == pytest.approx(sl, rel=0.1)
        assert B.mean() == pytest.approx(mb, abs=0.0005) and B.std() == pytest.approx(sb, rel=0.1)
        assert np.corrcoef(L, B)[0, 1] == pytest.approx(0.6, abs=0.06)
        # 2D:4D, the index's over the ring's length, spreads like Manning et al.'s 0.03-0.04
        ratio = [h.digit_length[1] / h.digit_length[3] for h in hands]
        assert np.std(ratio) == pytest.approx(np.sqrt(2) * DIGIT_LENGTH_SD, rel=0.1)


def test_bad_anatomies_name_the_value():
    with pytest.raises(ScenarioError, match="length_scale"):
        Anatomy(length_scale=3.0, breadth_scale=1.0)
    with pytest.raises(ScenarioError, match="digit_radius"):
        Anatomy(length_scale=1.0, breadth_scale=1.0, digit_radius=(1.0, 1.0, 1.5, 1.0, 1.0))
    with pytest.raises(ScenarioError, match="sex 'x'"):
        draw_anatomy(np.random.default_rng(0), "x")
    with pytest.raises(ScenarioError, match="anatomy"):
        hand_model("big")
