"""benchmark.world.grasp_plan: the trials a drawn grasp must pass, and the targeted re-check of the stored choices."""

import json

import numpy as np
import pytest

from benchmark.errors import ScenarioError, SimulationError
from benchmark.reproduce import DATASETS
from benchmark.world import grasp_plan, physics
from benchmark.world.grasp_plan import (
    TRIAL_PALM_CLEARANCE_M,
    TRIALS,
    Recheck,
    Trial,
    _PlanProblem,
    palm_clearance,
    plan_grasp,
    recheck_stored,
)
from benchmark.world.scenario import Scenario


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


# Person 1020's drawn choice as stored before the re-check (scipy's plan of the tripod d1020-width-tripod).
_OLD_1020 = {
    "spec": {"name": "d1020-width-tripod", "family": "width-tripod", "palm_x": -0.001286765985235373,
             "spots": {"thumb": {"face": "-y", "point": [-0.001286765985235373, -0.0555, -0.0035929785491718687]},
                       "index": {"face": "+y", "point": [-0.01118158190583296, 0.0555, 0.0012581535156305796]},
                       "middle": {"face": "+y", "point": [0.008608049935362214, 0.0555, -0.008444110613974317]}}},
    "x": [-0.012821743, 0.077663087, -0.335606589, 0.545795333, 0.089400818, 0.55744335, 0.536264682, -0.34906585,
          0.15825858, 1.047364746, 0.521463779, -0.34906585, 0.174604196, 1.21824794, 0.309181628, -0.0, 0.174255381,
          0.300000354, 0.15, 0.0, 0.12614319, 0.281013717, 0.150000686],
}


def test_the_light_box_trial_catches_a_grip_too_light_to_stop_the_box_turning_between_the_pads():
    """The old tripod of person 1020 let the 0.30 kg box turn about the grip axis until it touched the
    palm while it turned the 0.66 kg box back each stroke: only a trial with the lightest box sees it."""
    plan = _PlanProblem(1020, _OLD_1020["spec"]).plan(np.array(_OLD_1020["x"]))
    physics.run(Trial("excite-ry", 5).scenario(1020, 1020), plan)  # the heaviest box: held
    with pytest.raises(SimulationError, match="palm touched the box"):
        physics.run(Trial("excite-ry", 0).scenario(1020, 1020), plan)


def test_the_shipped_training_sets_failed_episodes_simulate_with_the_re_checked_grasps():
    """The three episodes of the shipped model's training set (people 1000-1039, seed 100, the masses
    rotating) that dropped the box or touched it with the palm before the re-check."""
    assert DATASETS["train"][DATASETS["train"].index("--seeds") + 1] == "100"
    for task, user, mass in (("excite-ry", 1020, 0), ("free", 1002, 1), ("free", 1020, 1)):
        sc = Scenario(task=task, user=user, grasp=user, mass=mass, seed=100, view=user)
        truth = physics.run(sc, plan_grasp(sc))[0].truth
        assert truth.held.any() and truth.contact_active[truth.held].any(axis=1).all()


# Person 1034's grasp as the six trials alone drew it again (bounded_lsq's plan of its next candidate).
_SIX_TRIALS_1034 = {
    "spec": {"name": "d1034-width-five", "family": "width-five", "palm_x": -0.002593762281617119,
             "spots": {"thumb": {"face": "-y", "point": [-0.002593762281617119, -0.0555, -0.00223224217855715]},
                       "index": {"face": "+y", "point": [-0.029711675650319704, 0.0555, -0.0013304807241580566]},
                       "middle": {"face": "+y", "point": [-0.011781908576448565, 0.0555, -0.005739544359359875]},
                       "ring": {"face": "+y", "point": [0.0075213109124213275, 0.0555, 0.0017060766823437865]},
                       "little": {"face": "+y", "point": [0.023597224187878466, 0.0555, -0.003565020313054455]}}},
    "x": [0.006700246, 0.060484243, -0.14885819, 0.497250683, -0.698131701, 0.953679318, 0.820779223, -0.022767521,
          0.500396502, 1.455442644, 0.340928462, 0.058072874, 0.506098822, 1.499944416, 0.514583341, 0.056863755,
          0.359336424, 1.554645409, 0.553538434, 0.078906365, 0.512961854, 1.029569527, 0.278384606],
}


def test_a_trial_passed_with_the_palm_a_hair_from_the_box_is_failed():
    """1034's grasp shook the heaviest box at seed 0 without a palm contact, its palm 0.1 mm from the
    box (it touched it at other seeds); the stored grasp of person 1000 keeps its palm 15 mm clear."""
    shake = Trial("shake", 5).scenario(1034, 1034)
    plan = _PlanProblem(1034, _SIX_TRIALS_1034["spec"]).plan(np.array(_SIX_TRIALS_1034["x"]))
    close = palm_clearance(shake, physics.run(shake, plan)[0].truth)
    assert 0.0 < close < 0.0005 < TRIAL_PALM_CLEARANCE_M
    shake = Trial("shake", 5).scenario(1000, 1000)
    assert palm_clearance(shake, physics.run(shake, plan_grasp(shake))[0].truth) > 0.010
