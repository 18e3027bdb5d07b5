"""People (benchmark.world.people): the named cohort and the drawn population."""

import json

import numpy as np
import pytest

from benchmark.world.anatomy import Anatomy
from benchmark.world.assets import hand_model, users
from benchmark.world.grasp_plan import plan_grasp
from benchmark.world.people import BASELINE_GRIP_N, FINGER_SHARE_MEAN, SAFETY_MARGIN, named_count, person, person_record
from benchmark.world.scenario import Scenario


def test_the_named_cohort_is_users_yaml_with_hands_of_their_own_proportions_at_their_size():
    assert named_count() == len(users()) == 5
    for u in range(5):
        p = person(u)
        a, scale = p["anatomy"], users()[u]["hand_scale"]
        assert not p["drawn"] and p["name"] == users()[u]["name"]
        assert a.hand_length_m == pytest.approx(0.190 * scale, abs=1e-12)
        assert a.hand_breadth_m == pytest.approx(0.085 * scale, abs=1e-12)
        assert a != Anatomy.template(scale) and np.ptp(a.digit_radius) > 0.01  # not the template
    assert person(4)["anatomy"] == person(1)["anatomy"]  # users.yaml: u4 has u1's hand
    assert person(0)["anatomy"] != person(2)["anatomy"]


def test_a_drawn_person_is_the_same_for_every_scenario_and_differs_from_the_next():
    assert person(123) is person(123)
    assert person_record(123) == person_record(123)
    assert person(123)["anatomy"] != person(124)["anatomy"]
    a = hand_model(Scenario(user=123, task="lift", seed=1))
    b = hand_model(Scenario(user=123, task="rotate", seed=7))
    assert a is b
    json.dumps(person_record(123))  # summary.json can hold it


def test_the_drawn_population_spreads_as_stated():
    people = [person(u) for u in range(5, 405)]
    assert 0.4 < np.mean([p["sex"] == "female" for p in people]) < 0.6
    margins = np.array([p["safety_margin"] for p in people])
    assert np.median(margins) == pytest.approx(SAFETY_MARGIN[0], rel=0.1)
    assert margins.min() >= SAFETY_MARGIN[2][0] and margins.max() <= SAFETY_MARGIN[2][1] < 1.0  # (G - G_slip) / G
    # most within Johansson & Westling's 10-40 % of the grip force (measured 347 of 400)
    assert np.mean((margins >= 0.10) & (margins <= 0.40)) > 0.8
    base = np.array([p["baseline_grip_n"] for p in people])
    assert BASELINE_GRIP_N[0] <= base.min() and base.max() <= BASELINE_GRIP_N[1]
    shares = np.array([list(p["finger_share"].values()) for p in people])
    np.testing.assert_allclose(shares.sum(axis=1), 1.0)
    mean = np.array(list(FINGER_SHARE_MEAN.values()))
    np.testing.assert_allclose(shares.mean(axis=0), mean / mean.sum(), atol=0.01)
    # lengths: women's hands shorter than men's on average (Pheasant & Haslegrave: 174 vs 189 mm)
    L = {s: np.mean([p["anatomy"].hand_length_m for p in people if p["sex"] == s]) for s in ("female", "male")}
    assert 0.010 < L["male"] - L["female"] < 0.020


def test_a_drawn_persons_grasp_plan_is_solved_and_rounded():
    plan = plan_grasp(Scenario(user=17, grasp=1))
    assert plan.tip_error_m < 0.02
    q = plan.q_grasp
    np.testing.assert_array_equal(q, np.round(q, 9))
