"""eval --pictures: each chosen episode's overlay and Fig. 5 in DIR/pictures/; which episodes are the worst."""

import json

from benchmark.commands.cli import main
from benchmark.commands.pictures.episodes import worst_episodes
from benchmark.suites import SUITES, Gate, Suite
from benchmark.world.scenario import Scenario


def test_the_worst_episodes_are_those_worst_on_some_gates_metric():
    scores = {"episodes": [{"episode": "a", "box_pos_err_mm": 1.0, "contact_recall": 0.5},
                           {"episode": "b", "box_pos_err_mm": 3.0, "contact_recall": 0.9},
                           {"episode": "c", "box_pos_err_mm": 2.0, "contact_recall": None}]}
    gates = [Gate("box_pos_err_mm", "<=", 2.0), Gate("contact_recall", ">=", 0.8)]
    assert worst_episodes(scores, gates) == ["b", "c"]  # c scored no recall: worst of all
    assert worst_episodes(scores, gates[:1] * 2) == ["b"]  # each once
    assert worst_episodes(scores, []) == []


def test_eval_writes_the_pictures_of_the_worst_or_of_all_episodes(tmp_path, monkeypatch, capsys):
    # the baselines, scored beside the method, are left out: no picture is drawn of them (without
    # --pictures none is drawn: tests/test_evaluate.py)
    pair = Suite(name="pair", version=1, scenarios=tuple(Scenario(task="lift", seed=s, duration_s=1.5) for s in (41, 42)),
                 gates=(Gate("box_pos_err_mm", "<=", 5.0),), description="two short lifts")
    monkeypatch.setitem(SUITES, "pair", pair)
    cache = str(tmp_path / "c")
    assert main(["eval", "--suite", "pair", "--out", str(tmp_path / "all"), "--cache", cache, "--quiet",
                 "--no-baselines", "--pictures", "all"]) == 0
    names = sorted(p.name for p in (tmp_path / "all" / "pictures").iterdir())
    assert names == ["lift-u0-g0-m0-s41-forces.png", "lift-u0-g0-m0-s41-overlay.png",
                     "lift-u0-g0-m0-s42-forces.png", "lift-u0-g0-m0-s42-overlay.png"]
    assert main(["eval", "--suite", "pair", "--out", str(tmp_path / "worst"), "--cache", cache, "--quiet",
                 "--no-baselines", "--pictures", "worst"]) == 0
    rows = json.loads((tmp_path / "worst" / "scores.json").read_text())["episodes"]
    worst = max(rows, key=lambda r: r["box_pos_err_mm"])["episode"]
    assert sorted(p.name for p in (tmp_path / "worst" / "pictures").iterdir()) == [f"{worst}-forces.png",
                                                                                   f"{worst}-overlay.png"]
