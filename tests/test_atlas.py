"""The failure atlas: what lists an episode, what each cause needs, and the evidence measured."""

import dataclasses
import json

import numpy as np
import pytest
from tiny_suite import TINY

from benchmark.commands import atlas
from benchmark.suites import SUITES
from benchmark.suites.evaluate import cached_episode


def _row(**changes):
    row = {"net_force_err_n_rms": 0.1, "least_violation_frac": 0.0, "learned_rel_err_pct": 20.0,
           "contact_precision": 0.99, "box_pos_err_mm": 4.0, "no_contact_frames": 0, "phantom_finger_frames": 0,
           "phantom_digits": [], "least_violation_frames": 0, "table_lost_frames": 0}
    return {**row, **changes}


def test_the_criteria_list_an_episode_beyond_any_limit_or_without_a_value():
    net, lv, learned, precision = atlas.CRITERIA
    assert net.fails(0.51) and not net.fails(0.5) and lv.fails(0.021) and not lv.fails(0.02)
    assert learned.fails(60.1) and precision.fails(0.84) and not precision.fails(0.85)
    assert net.fails(float("nan")) and precision.fails(None)  # a metric that could not be computed fails


@pytest.mark.parametrize("lab, exact, expected", [
    (_row(net_force_err_n_rms=2.0, no_contact_frames=27), _row(), [("track: contacts", "contacts lost: 27 frames"),
                                                                   ("knowledge", "exact knowledge passes net_force")]),
    (_row(learned_rel_err_pct=90.0, phantom_finger_frames=12, phantom_digits=["little"]), _row(learned_rel_err_pct=90.0),
     [("track: contacts", "contacts invented: little (not in the grasp), 12 finger-frames")]),
    (_row(least_violation_frac=0.1, least_violation_frames=30), _row(least_violation_frac=0.1),
     [("forces", "no physical solution on 30 frames")]),
    (_row(learned_rel_err_pct=75.0), _row(learned_rel_err_pct=70.0), [("learn", "every stage before them passes")]),
    (_row(net_force_err_n_rms=1.9, table_lost_frames=27), _row(), [("forces: table", "table lost: 27 frames"),
                                                                   ("knowledge", "exact knowledge passes net_force")]),
    (_row(net_force_err_n_rms=0.8, box_pos_err_mm=12.0), _row(net_force_err_n_rms=0.8),
     [("track: box", "box 12.0 mm off")]),
    (_row(net_force_err_n_rms=0.8), _row(net_force_err_n_rms=0.9), [("?", "unexplained")]),
])
def test_each_cause_comes_from_its_evidence(lab, exact, expected):
    found = atlas.causes(lab, exact)
    assert [stage for stage, _ in found] == [stage for stage, _ in expected]
    for (_, text), (_, needle) in zip(found, expected):
        assert needle in text, (text, needle)


def test_lost_contacts_are_counted_where_the_truth_has_two_digits_or_more(monkeypatch, tiny_cache):
    """A tracker that finds no contact at all: every frame where the truth has two or more digits on
    the box is a lost-contact frame, and no digit is invented."""
    import benchmark.commands.atlas as module

    episode, _ = cached_episode(TINY, TINY.scenarios[0], tiny_cache)
    real = module.run_method

    def without_contacts(spec, ep, inputs=None):
        est = real(spec, ep, inputs=inputs)
        none = dataclasses.replace(est.contacts, active=np.zeros_like(est.contacts.active))
        return dataclasses.replace(est, contacts=none)

    monkeypatch.setattr(module, "run_method", without_contacts)
    found = atlas.diagnose(episode, "lab")
    two = int((np.asarray(episode.truth.contact_active).sum(axis=1) >= 2).sum())
    assert two > 10 and found["no_contact_frames"] == two and found["phantom_finger_frames"] == 0


def test_a_lost_table_is_counted_where_the_table_carries_the_box(monkeypatch, tiny_cache):
    """Nominal forces without any table force: every frame where the table pushes with more than half
    the box's weight (the box standing on it before the lift) has lost the table."""
    import benchmark.commands.atlas as module

    episode, _ = cached_episode(TINY, TINY.scenarios[0], tiny_cache)
    real = module.run_method

    def without_table(spec, ep, inputs=None):
        est = real(spec, ep, inputs=inputs)
        return dataclasses.replace(est, nominal=dataclasses.replace(est.nominal,
                                                                    env_wrench=np.zeros_like(est.nominal.env_wrench)))

    truth = episode.truth
    standing = int((np.linalg.norm(truth.env_force, axis=1) > 0.5 * truth.mass * 9.81).sum())
    assert standing > 10 and atlas.diagnose(episode, "exact")["table_lost_frames"] == 0  # told the true table
    monkeypatch.setattr(module, "run_method", without_table)
    assert atlas.diagnose(episode, "exact")["table_lost_frames"] == standing


def test_the_command_writes_the_atlas_of_a_suite(monkeypatch, tmp_path, tiny_cache, capsys):
    monkeypatch.setitem(SUITES, "tiny", TINY)
    assert atlas.main(["--suite", "tiny", "--out", str(tmp_path / "atlas"), "--cache", str(tiny_cache),
                       "--quiet"]) == 0
    doc = json.loads((tmp_path / "atlas" / "atlas.json").read_text())
    (episode,) = doc["episodes"]
    assert episode["episode"] == "lift-u0-g0-m0-s21" and set(doc["tail"]) == {"lab", "exact"}
    assert doc["tail"]["lab"]["episodes"] == 1 and doc["tail"]["lab"]["net_force_max_n"] == pytest.approx(
        episode["lab"]["net_force_err_n_rms"])
    assert episode["lab"]["box_pos_err_mm"] != episode["exact"]["box_pos_err_mm"]  # told different cameras
    assert bool(episode["failed"]) == bool(episode["causes"])
    text = (tmp_path / "atlas" / "atlas.md").read_text()
    assert "| lab | " in text and "| exact | " in text


def test_a_bad_suite_is_one_line_and_status_2_before_any_work(tmp_path, capsys):
    with pytest.raises(SystemExit) as refused:
        atlas.main(["--suite", "nope", "--out", str(tmp_path / "atlas")])
    err = capsys.readouterr().err
    assert refused.value.code == 2 and err.count("\n") == 1 and "nope" in err and not (tmp_path / "atlas").exists()


def test_run_as_a_script_its_episodes_go_to_worker_processes(tmp_path):
    """``python -m benchmark.commands.atlas --workers 2`` (as ``fsv-bench reproduce`` runs it): the
    job function is found by its module's name, not in ``__main__``, which a worker cannot unpickle."""
    import os
    import subprocess
    import sys

    code = ("import runpy, sys\n"
            "from benchmark.suites import SUITES\n"
            "from tiny_suite import TINY\n"
            "SUITES['tiny'] = TINY\n"
            f"sys.argv = ['atlas', '--suite', 'tiny', '--workers', '2', '--quiet', '--out', {str(tmp_path / 'a')!r}, "
            f"'--cache', {str(tmp_path / 'c')!r}]\n"
            "runpy.run_module('benchmark.commands.atlas', run_name='__main__')\n")
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300,
                         env={**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)})
    assert run.returncode == 0, run.stderr
    assert json.loads((tmp_path / "a" / "atlas.json").read_text())["tail"]["lab"]["episodes"] == 1
