"""benchmark.world.grasp_plan: the trials a drawn grasp must pass, and the targeted re-check of the stored choices."""

import json

import pytest

from benchmark.errors import ScenarioError
from benchmark.world import grasp_plan
from benchmark.world.grasp_plan import TRIALS, Recheck, Trial, recheck_stored


def test_the_trials_hold_the_heaviest_box_in_five_tasks_and_turn_the_lightest_about_the_grip_axis():
    assert TRIALS[:5] == tuple(Trial(t, 5) for t in ("lift", "rotate", "free", "release", "shake"))
    assert TRIALS[5:] == (Trial("excite-ry", 0),)
    sc = Trial("excite-ry", 0).scenario(1020, 1020)
    assert (sc.task, sc.user, sc.grasp, sc.mass, sc.seed, sc.duration_s) == ("excite-ry", 1020, 1020, 0, 0, None)


def test_recheck_writes_only_the_entries_drawn_again_and_keeps_every_other_byte(tmp_path, monkeypatch):
    shipped = grasp_plan.importlib.resources.files("sim_assets") / grasp_plan.PLANS_FILE
    path = tmp_path / "plans.json"
    path.write_text(shipped.read_text())
    new = {"fingerprint": "f" * 64, "spec": {"name": "d101-width-four"}, "x": [0.5]}

    def fake(pair):  # no simulation: person 101's choice "fails", 100's and 102's hold
        return Recheck(f"drawn/{pair[0]}/{pair[1]}", "free@5" if pair[0] == 101 else "", "",
                       new if pair[0] == 101 else None, 0.0)

    monkeypatch.setattr(grasp_plan, "recheck_pair", fake)
    lines = []
    out = recheck_stored(users=[102, 100, 101], report=lines.append, path=path)
    assert [r.key for r in out] == ["drawn/100/100", "drawn/101/101", "drawn/102/102"]  # STORED_DRAWN's order
    assert lines[1] == "drawn/101/101: failed free@5, drawn again: d101-width-four (0 s)"
    before, after = json.loads(shipped.read_text()), json.loads(path.read_text())
    assert after["plans"].pop("drawn/101/101") == new and before["plans"].pop("drawn/101/101") != new
    assert after == before
    old_lines, new_lines = shipped.read_text().splitlines(), path.read_text().splitlines()
    changed = [i for i, (a, b) in enumerate(zip(old_lines, new_lines)) if a != b]
    first = old_lines.index('  "drawn/101/101": {')
    assert changed and changed[0] > first and path.read_text().endswith("}\n")
    tail = len(old_lines) - old_lines.index('  "drawn/102/102": {')  # everything after the entry: the same bytes
    assert old_lines[-tail:] == new_lines[-tail:]


def test_recheck_refuses_people_without_a_stored_choice_and_bad_workers():
    with pytest.raises(ScenarioError, match=r"users \[17\] have no stored drawn grasp"):
        recheck_stored(users=[100, 17])
    with pytest.raises(ScenarioError, match="workers must be a positive integer"):
        recheck_stored(users=[100], workers=0)
    with pytest.raises(ScenarioError, match="not a stored drawn choice"):
        grasp_plan.recheck_pair((17, 17))
    assert grasp_plan._people("1000-1002,100") == [1000, 1001, 1002, 100]
    with pytest.raises(ScenarioError, match="indices and ranges"):
        grasp_plan._people("a-b")
