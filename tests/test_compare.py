"""fsv-bench compare: paired differences with intervals, and which evaluation is better where."""

import json

import pytest

from benchmark.commands.cli import main
from benchmark.suites.compare import compare


def _scores(values, version=1, recall=0.9):
    eps = [{"episode": f"e{i}", "box_pos_err_mm": v, "contact_recall": recall + 0.01 * i} for i, v in enumerate(values)]
    return {"suite": {"name": "s", "version": version}, "method": "m", "metrics": ["box_pos_err_mm", "contact_recall"],
            "episodes": eps}


def test_a_uniformly_better_method_is_named_and_noise_is_not():
    a = _scores([1.0, 2.0, 3.0, 4.0, 5.0])
    b = _scores([0.5, 1.5, 2.5, 3.5, 4.5], recall=0.9)
    r = compare(a, b)
    assert r["metrics"]["box_pos_err_mm"]["mean_diff"] == pytest.approx(-0.5)
    assert r["metrics"]["box_pos_err_mm"]["better"] == "B"  # lower error, every episode
    assert r["metrics"]["contact_recall"]["better"] == "neither"  # identical recall
    c = _scores([1.5, 1.5, 3.5, 3.5, 5.0])  # differences of both signs
    assert compare(a, c)["metrics"]["box_pos_err_mm"]["better"] == "neither"
    worse_recall = _scores([1.0, 2.0, 3.0, 4.0, 5.0], recall=0.8)
    assert compare(a, worse_recall)["metrics"]["contact_recall"]["better"] == "A"


def test_other_suite_versions_are_refused():
    with pytest.raises(ValueError, match="same suite and version"):
        compare(_scores([1.0]), _scores([1.0], version=2))


def test_cli_prints_and_writes_and_refuses_a_folder_without_scores(tmp_path, capsys):
    for name, vals in (("a", [1.0, 2.0, 3.0]), ("b", [0.0, 1.0, 2.0])):
        (tmp_path / name).mkdir()
        (tmp_path / name / "scores.json").write_text(json.dumps(_scores(vals)))
    assert main(["compare", str(tmp_path / "a"), str(tmp_path / "b"), "--out", str(tmp_path / "c.json")]) == 0
    assert "box_pos_err_mm" in capsys.readouterr().out
    assert json.loads((tmp_path / "c.json").read_text())["metrics"]["box_pos_err_mm"]["better"] == "B"
    assert main(["compare", str(tmp_path / "a"), str(tmp_path / "nope")]) == 2
    assert "no readable scores.json" in capsys.readouterr().err
