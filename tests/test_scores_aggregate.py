"""Aggregates: statistics with deterministic 95 % bootstrap intervals; NaN left out."""

import numpy as np

from benchmark.scores.aggregate import aggregate, aggregate_all


def test_median_and_mean_with_intervals_that_bracket_them():
    x = [1.0, 2.0, 3.0, 10.0, 4.0, 2.5]
    med, mean = aggregate(x, "median"), aggregate(x, "mean")
    assert med["value"] == 2.75 and mean["value"] == np.mean(x)
    for a in (med, mean):
        assert min(x) <= a["ci_low"] <= a["value"] <= a["ci_high"] <= max(x) and a["n"] == 6
    assert aggregate(x, "median") == med  # seeded: the same interval every time
    assert mean["ci_high"] - mean["ci_low"] > 1.0  # a 10 among small values widens the mean's interval


def test_nan_is_left_out_and_degenerate_samples_have_no_width():
    assert aggregate([1.0, float("nan"), 3.0], "mean")["n"] == 2
    assert aggregate([2.0], "median") == {"value": 2.0, "ci_low": 2.0, "ci_high": 2.0, "n": 1}
    assert aggregate([float("nan")], "median") == {"value": None, "ci_low": None, "ci_high": None, "n": 0}


def test_aggregate_all_groups_by_a_key():
    rows = [{"task": "lift", "m": 1.0}, {"task": "lift", "m": 3.0}, {"task": "rotate", "m": 10.0}]
    by = aggregate_all(rows, ["m"], by="task")
    assert by["lift"]["m"]["median"]["value"] == 2.0 and by["rotate"]["m"]["mean"]["value"] == 10.0
    assert aggregate_all(rows, ["m"])["m"]["median"]["value"] == 3.0
