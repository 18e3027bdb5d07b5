"""Aggregates: statistics with deterministic 95 % bootstrap intervals; every episode counts, a missing
metric at its worst value."""

import numpy as np

from benchmark.scores.aggregate import aggregate, aggregate_all
from benchmark.scores.metrics import METRICS, WORST
from benchmark.scores.verdict import Gate, check_gates
from benchmark.suites.compare import HIGHER_IS_BETTER


def test_median_and_mean_with_intervals_that_bracket_them():
    x = [1.0, 2.0, 3.0, 10.0, 4.0, 2.5]
    med, mean = aggregate(x, "median"), aggregate(x, "mean")
    assert med["value"] == 2.75 and mean["value"] == np.mean(x)
    for a in (med, mean):
        assert min(x) <= a["ci_low"] <= a["value"] <= a["ci_high"] <= max(x) and a["n"] == 6
    assert aggregate(x, "median") == med  # seeded: the same interval every time
    assert mean["ci_high"] - mean["ci_low"] > 1.0  # a 10 among small values widens the mean's interval


def test_a_missing_value_counts_at_the_worst_and_degenerate_samples_have_no_width():
    inf = float("inf")
    assert aggregate([1.0, float("nan"), 3.0], "mean", inf) == {"value": inf, "ci_low": 1.0, "ci_high": inf, "n": 3,
                                                               "at_worst": 1}
    assert aggregate([2.0], "median") == {"value": 2.0, "ci_low": 2.0, "ci_high": 2.0, "n": 1, "at_worst": 0}
    assert aggregate([float("nan")], "median", inf)["value"] == inf
    assert aggregate([0.9, None], "median", 0.0)["value"] == 0.45  # a rate's worst is 0
    # without a worst value (a signed bias) the statistic is undefined: null, a gate on it fails
    assert aggregate([float("nan")], "median") == {"value": None, "ci_low": None, "ci_high": None, "n": 1,
                                                   "at_worst": 1}


def test_an_overflowing_episode_counts_and_the_gate_fails():
    """box/pos = 1e300 overflowed the episode's error to NaN: it was left out (n = 3 of 4, passing)."""
    rows = [{"box_pos_err_mm": v} for v in (3.0, 4.0, 5.0, float("nan"))]
    aggregates = aggregate_all(rows, ["box_pos_err_mm"])
    assert aggregates["box_pos_err_mm"]["median"]["n"] == 4 and aggregates["box_pos_err_mm"]["mean"]["n"] == 4
    (result,) = check_gates([Gate("box_pos_err_mm", "<=", 4.4)], aggregates)
    assert result.n == 4 and result.value == 4.5 and not result.passed  # 3 of 4 gave 4.0: a pass
    (result,) = check_gates([Gate("box_pos_err_mm", "<=", 8.0, statistic="mean")], aggregates)
    assert result.value == float("inf") and not result.passed


def test_an_episode_without_valid_kinematics_cannot_improve_the_median():
    """kinematics/valid all false in one episode made acc_err_rms NaN: dropped, the median improved
    from 0.387 to 0.361."""
    values = [0.30, 0.361, 0.387, 0.42, 0.45]
    honest = aggregate_all([{"acc_err_rms": v} for v in values], ["acc_err_rms"])["acc_err_rms"]["median"]
    hidden = aggregate_all([{"acc_err_rms": v} for v in values[:-1]] + [{"acc_err_rms": float("nan")}],
                           ["acc_err_rms"])["acc_err_rms"]["median"]
    assert honest["value"] == 0.387 and hidden["value"] >= honest["value"] and hidden["n"] == 5
    assert hidden["ci_high"] == float("inf") and hidden == aggregate_all(  # deterministic
        [{"acc_err_rms": v} for v in values[:-1]] + [{"acc_err_rms": None}], ["acc_err_rms"])["acc_err_rms"]["median"]


def test_every_metric_has_a_worst_value_of_its_direction():
    assert set(WORST) == set(METRICS)
    for m in METRICS:
        assert WORST[m] == (0.0 if m in HIGHER_IS_BETTER else None if m == "contact_err_mm_mean" else
                            1.0 if m == "least_violation_frac" else float("inf"))


def test_aggregate_all_groups_by_a_key():
    rows = [{"task": "lift", "m": 1.0}, {"task": "lift", "m": 3.0}, {"task": "rotate", "m": 10.0}]
    by = aggregate_all(rows, ["m"], by="task")
    assert by["lift"]["m"]["median"]["value"] == 2.0 and by["rotate"]["m"]["mean"]["value"] == 10.0
    assert aggregate_all(rows, ["m"])["m"]["median"]["value"] == 3.0


def test_the_tail_is_the_nearest_rank_90th_percentile_and_a_lost_episode_reaches_it():
    """p90 over n episodes is the ceil(0.9 n)-th smallest: of four the largest, of twenty the 18th;
    an episode at its infinite worst value makes the tail +inf, never NaN."""
    x = [0.1, 0.2, 0.3, 0.9]
    assert aggregate(x, "p90")["value"] == 0.9  # the median (0.25) hides the 0.9
    twenty = list(np.arange(1.0, 21.0))
    tail = aggregate(twenty, "p90")
    assert tail["value"] == 18.0 and tail["ci_low"] <= 18.0 <= tail["ci_high"] <= 20.0
    lost = aggregate([0.1, 0.2, 0.3, float("nan")], "p90", float("inf"))
    assert lost["value"] == float("inf") and lost["at_worst"] == 1
    one = aggregate_all([{"net_force_err_n_rms": v} for v in [0.2] * 9 + [1.1]], ["net_force_err_n_rms"])
    assert one["net_force_err_n_rms"]["p90"]["value"] == 0.2  # one episode in ten may miss
    rows = [{"net_force_err_n_rms": v} for v in [0.2] * 8 + [1.1, 1.2]]
    (median, tail) = check_gates([Gate("net_force_err_n_rms", "<=", 0.3),
                                  Gate("net_force_err_n_rms", "<=", 0.75, statistic="p90")],
                                 aggregate_all(rows, ["net_force_err_n_rms"]))
    assert median.passed and not tail.passed and tail.value == 1.1 and tail.name == "p90 net_force_err_n_rms <= 0.75"
    with np.testing.assert_raises(ValueError):
        aggregate(x, "max")
