"""Splits (benchmark.suites.splits): disjoint people, grasps and views for training, dev and test."""

import pytest

from benchmark.suites.registry import SUITES
from benchmark.suites.splits import SPLITS, split_of, split_scenarios
from benchmark.world.scenario import Scenario


def test_the_splits_do_not_overlap_and_the_cohort_is_in_none_of_the_others():
    ranges = [(s.start, s.stop if s.stop is not None else 10**9) for s in SPLITS.values()]
    for i, (a0, a1) in enumerate(ranges):
        for b0, b1 in ranges[i + 1:]:
            assert a1 <= b0 or b1 <= a0
    for index in (0, 4, 99, 100, 499, 500, 999, 1000, 10**6):
        assert sum(s.holds(index) for s in SPLITS.values()) <= 1


def test_a_scenario_is_in_a_split_only_when_its_person_grasp_and_view_all_are():
    assert split_of(Scenario(user=2, grasp=3)) == "cohort"
    assert split_of(Scenario(user=2, grasp=3, view=1)) is None
    assert split_of(Scenario(user=600, grasp=700, view=999)) == "test"
    assert split_of(Scenario(user=600, grasp=700, view=100)) is None  # a dev view
    assert split_of(Scenario(user=1000, grasp=5000, view=123456)) == "train"
    assert split_of(Scenario(user=17)) is None  # free indices: a user's own experiments


def test_split_scenarios_give_every_episode_its_own_person_grasp_and_view():
    scs = split_scenarios("test", ("lift", "rotate"), 3, seed=300, masses=6)
    assert [s.task for s in scs] == ["lift"] * 3 + ["rotate"] * 3
    assert [s.user for s in scs] == [500, 501, 502, 503, 504, 505]
    assert all(s.user == s.grasp == s.view and split_of(s) == "test" for s in scs)
    assert [s.seed for s in scs] == list(range(300, 306))
    assert scs == split_scenarios("test", ("lift", "rotate"), 3, seed=300, masses=6)
    with pytest.raises(ValueError, match="position 500 is not in split 'test' \\(size 500\\)"):
        split_scenarios("test", ("lift",), 1, first=500, seed=0, masses=6)
    with pytest.raises(ValueError, match="split 'cohort': accepted: dev, test, train"):
        split_scenarios("cohort", ("lift",), 1, seed=0, masses=6)


def test_no_registered_suite_scores_on_training_people():
    for suite in SUITES.values():
        assert all(split_of(s) != "train" for s in suite.scenarios), suite.name
