"""Gates on aggregates, JUnit XML and the Markdown report."""

import xml.etree.ElementTree as ET

import pytest

from benchmark.scores.verdict import check_gates, junit_xml
from benchmark.suites import Gate

AGG = {"a": {"median": {"value": 1.0, "ci_low": 0.5, "ci_high": 1.5, "n": 4},
             "mean": {"value": 2.0, "ci_low": 1.0, "ci_high": 3.0, "n": 4}},
       "b": {"median": {"value": None, "ci_low": None, "ci_high": None, "n": 0},
             "mean": {"value": None, "ci_low": None, "ci_high": None, "n": 0}}}


def test_gates_hold_fail_and_fail_when_nothing_was_scored():
    r = check_gates([Gate("a", "<=", 1.0), Gate("a", "<=", 1.5, statistic="mean"), Gate("a", ">=", 0.9), Gate("b", "<=", 9)], AGG)
    assert [x.passed for x in r] == [True, False, True, False]
    assert r[1].name == "mean a <= 1.5" and r[1].value == 2.0 and r[1].ci == (1.0, 3.0) and r[3].ci is None
    with pytest.raises(ValueError, match="unknown metric 'c'"):
        check_gates([Gate("c", "<=", 1)], AGG)
    with pytest.raises(ValueError, match="Gate.op"):
        Gate("a", "<", 1)


def test_junit_has_one_case_per_gate_and_a_failure_naming_the_value():
    results = check_gates([Gate("a", "<=", 1.0), Gate("a", "<=", 1.5, statistic="mean")], AGG)
    root = ET.fromstring(junit_xml("smoke", results, 12.5))
    suite = root.find("testsuite")
    assert suite.get("tests") == "2" and suite.get("failures") == "1"
    cases = suite.findall("testcase")
    assert [c.get("name") for c in cases] == ["median a <= 1", "mean a <= 1.5"]
    assert cases[0].find("failure") is None
    assert "measured 2 (95 % CI [1, 3], n = 4 episodes, few episodes)" in cases[1].find("failure").get("message")


def test_the_report_gives_units_and_intervals_as_brackets():
    from types import SimpleNamespace

    from benchmark.scores.metrics import METRICS
    from benchmark.scores.units import UNITS, labelled
    from benchmark.scores.verdict import GateResult, report_markdown

    assert set(UNITS) == set(METRICS)  # every metric has its unit
    suite = SimpleNamespace(name="s", version=1, description="d")
    agg = {m: {s: {"value": -0.65, "ci_low": -0.6509, "ci_high": 0.6927} for s in ("median", "mean")} for m in METRICS}
    rows = [{"episode": "e", **{m: 1.0 for m in METRICS}}]
    text = report_markdown(suite, "m", rows, agg, {"lift": agg}, [GateResult("g", -0.65, (-0.6509, 0.6927), True, 1)],
                           METRICS)
    assert "| g | -0.65 | [-0.6509, 0.6927] | 1 | pass |" in text
    assert "n = 1 episodes: with so few, each 95 % interval is little more than the range" in text
    assert "| acc_err_rms [m/s²] | -0.65 | [-0.6509, 0.6927] | -0.65 |" in text
    assert "| contact_recall | -0.65 |" in text and labelled("learned_mae_n") == "learned_mae_n [N]"
    assert "-0.6509-0.6927" not in text
