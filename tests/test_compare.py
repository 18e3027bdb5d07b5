"""fsv-bench compare: paired differences with intervals, and which evaluation is better where."""

import json

import pytest

from benchmark.commands.cli import main
from benchmark.suites.compare import compare


def _scores(values, version=1, recall=0.9):
    eps = [{"episode": f"e{i}", "box_pos_err_mm": v, "contact_recall": recall + 0.01 * i} for i, v in enumerate(values)]
    return {"suite": {"name": "s", "version": version}, "method": "m", "metrics": ["box_pos_err_mm", "contact_recall"],
            "episodes": eps}


def test_four_episodes_are_too_few_for_a_verdict_however_alike_their_signs():
    a = _scores([1.0, 2.0, 3.0, 4.0])
    b = _scores([0.5, 1.5, 2.5, 3.5])  # lower on all four: a sign test's p = 0.125
    r = compare(a, b)["metrics"]["box_pos_err_mm"]
    assert r["mean_diff"] == pytest.approx(-0.5) and r["pairs"] == 4 and r["p"] is None
    assert r["better"] == "too few episodes" and r["interval"] == "few episodes"


def test_a_uniformly_better_method_is_named_with_its_p_value_and_noise_is_not():
    a = _scores([1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0])
    b = _scores([0.5, 1.4, 2.3, 3.6, 4.5, 5.2, 6.6], recall=0.9)  # lower on all seven
    r = compare(a, b)
    m = r["metrics"]["box_pos_err_mm"]
    assert m["better"] == "B" and m["p"] == pytest.approx(2 / 2**7)  # exact Wilcoxon: the smallest two-sided p
    assert r["metrics"]["contact_recall"]["better"] == "neither"  # the same recall on every episode
    c = _scores([1.5, 1.5, 3.5, 3.5, 5.5, 5.5, 7.5])  # differences of both signs
    assert compare(a, c)["metrics"]["box_pos_err_mm"]["better"] == "neither"
    worse_recall = _scores([1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0], recall=0.8)
    assert compare(a, worse_recall)["metrics"]["contact_recall"]["better"] == "A"


def test_hiding_the_worst_episode_cannot_make_a_method_better():
    """B is lower than A on seven episodes and has no value (null: NaN or overflowed) on the eighth:
    left out, that gave B better at p = 2/2^7; at its worst value it ranks above every difference."""
    a = _scores([1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0])
    b = _scores([0.5, 1.5, 2.5, 3.5, 4.5, 5.5, 6.5, None])
    m = compare(a, b)["metrics"]["box_pos_err_mm"]
    assert m["n"] == 8 and m["pairs"] == 8 and m["mean_diff"] == float("inf") and m["better"] == "neither"
    both = compare(_scores([None, 1.0]), _scores([None, 1.0]))["metrics"]["box_pos_err_mm"]
    assert both["mean_diff"] == 0.0 and both["better"] == "neither"  # two worst values tie
    recall = _scores([1.0] * 8)
    for e in recall["episodes"][:7]:
        e["contact_recall"] = None  # a rate's worst is 0
    assert compare(_scores([1.0] * 8), recall)["metrics"]["contact_recall"]["better"] == "A"


def test_an_older_scores_file_without_the_newer_metrics_is_compared_on_the_metrics_both_have():
    a = _scores([1.0, 2.0, 3.0, 4.0])
    a["metrics"].append("force_mae_n")
    for e in a["episodes"]:
        e["force_mae_n"] = 2.0
    r = compare(a, _scores([0.5, 1.5, 2.5, 3.5]))["metrics"]
    assert set(r) == {"box_pos_err_mm", "contact_recall"} and r["box_pos_err_mm"]["mean_diff"] == pytest.approx(-0.5)


def test_other_suite_versions_are_refused():
    with pytest.raises(ValueError, match="same suite and version"):
        compare(_scores([1.0]), _scores([1.0], version=2))


def test_cli_prints_and_writes_and_refuses_a_folder_without_scores(tmp_path, capsys):
    for name, vals in (("a", [1.0, 2.0, 3.0, 4.0, 5.0, 6.0]), ("b", [0.0, 1.0, 2.0, 3.0, 4.0, 5.0])):
        (tmp_path / name).mkdir()
        (tmp_path / name / "scores.json").write_text(json.dumps(_scores(vals)))
    assert main(["compare", str(tmp_path / "a"), str(tmp_path / "b"), "--out", str(tmp_path / "c.json")]) == 0
    printed = capsys.readouterr().out
    assert "over n = 6 episodes" in printed and "box_pos_err_mm [mm]" in printed and "0.0312" in printed
    assert json.loads((tmp_path / "c.json").read_text())["metrics"]["box_pos_err_mm"]["better"] == "B"
    assert main(["compare", str(tmp_path / "a"), str(tmp_path / "nope")]) == 2
    assert "no readable scores.json" in capsys.readouterr().err
