"""fsv-bench reproduce: the committed results are those of this code, and the comparison catches moves."""

import argparse

import pytest

from benchmark import reproduce
from benchmark.commands.entry import run
from benchmark.fingerprint import results_fingerprint


def test_compare_values_tolerates_rounding_and_names_what_moved():
    old = {"a": 1.0, "b": {"c": [2.0, 3.0]}, "timing_s": {"total": 5.0}, "name": "x"}
    assert reproduce.compare_values({"a": 1.0 + 1e-9, "b": {"c": [2.0, 3.0]}, "timing_s": {"total": 9.0}, "name": "x"}, old) == []
    diffs = reproduce.compare_values({"a": 1.01, "b": {"c": [2.0]}, "timing_s": {"total": 5.0}, "name": "y"}, old, "s")
    assert diffs == ["s/a: 1.0 -> 1.01", "s/b/c[1]: 3.0 -> '<missing>'", "s/name: 'x' -> 'y'"]


def test_a_moved_run_names_the_first_stage_whose_output_differs(tmp_path):
    import json
    import shutil

    result = {r.name: r for r in reproduce.RESULTS}["reference-run"]
    committed = reproduce.ROOT / result.path
    summary = json.loads((committed / "summary.json").read_text())
    assert list(summary["digests"]) == ["truth", "depth", "tracking", "kinematics", "nominal_forces", "final_forces"]
    new = tmp_path / "run"
    shutil.copytree(committed, new)
    assert result.compare(new, committed) == []
    moved = json.loads(json.dumps(summary))
    for stage in ("depth", "kinematics", "final_forces"):  # a depth of other bits moves everything after it
        moved["digests"][stage] = "0" * 16
    moved["forces"]["net_force_err_n_rms"] *= 1.01
    (new / "summary.json").write_text(json.dumps(moved))
    diffs = result.compare(new, committed)
    assert diffs[0] == f"{committed.name}/summary.json: the first stage whose output differs is depth (truth identical)"
    assert len(diffs) == 2 and "net_force_err_n_rms" in diffs[1]


def test_committed_results_were_made_by_this_code():
    """Fails when the world, the method or the learning changed after the last
    `fsv-bench reproduce --write`: regenerate the committed results in the same change."""
    record = reproduce.recorded()
    assert record, "results/reproduce.json is missing: run `fsv-bench reproduce --write`"
    assert set(record["results"]) == {r.name for r in reproduce.RESULTS}
    assert record["code_fingerprint"] == results_fingerprint(), (
        "the committed results are stale: run `fsv-bench reproduce --write`")


@pytest.mark.accuracy
def test_the_reference_run_regenerates_to_its_committed_values(tmp_path):
    """The main command on the default lift, compared with results/lift-u0-g0-m0-s0 (every value but
    timings and provenance, to a relative 1e-6; measured: identical)."""
    result = {r.name: r for r in reproduce.RESULTS}["reference-run"]
    reproduce.make(result, tmp_path / "data", tmp_path / "run", log=open(tmp_path / "log", "w"))
    assert not (tmp_path / "run" / "episode.npz").exists()
    diffs = result.compare(tmp_path / "run", reproduce.ROOT / result.path)
    assert diffs == []


def test_bad_result_names_exit_2_before_any_work(tmp_path, capsys):
    assert run(["reproduce", "--only", "table3", "--data", str(tmp_path / "d")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "table3" in err and "accepted: grip-calibration, shipped-model" in err
    assert not (tmp_path / "d").exists()


def test_list_names_every_result_and_its_commands(capsys):
    reproduce.run(argparse.Namespace(only=None, write=False, data="unused", workers=None, list=True))
    text = capsys.readouterr().out
    for r in reproduce.RESULTS:
        assert f"{r.name}: {r.path}" in text
    assert "fsv-bench train --data {data}/train" in text


def test_writing_results_keeps_nested_results_and_touches_no_folder_of_the_users(tmp_path):
    committed, new = tmp_path / "results" / "table2", tmp_path / "new"
    (committed / "users-0-1").mkdir(parents=True)
    (committed / "users-0-1" / "table2.md").write_text("a variant, made separately")
    (committed / "table2.md").write_text("old")
    new.mkdir()
    (new / "table2.md").write_text("new")
    mine = tmp_path / "results" / ".table2.new"  # a folder of the user's, named like the old staging folder
    mine.mkdir()
    (mine / "notes.txt").write_text("mine")
    reproduce._replace(new, committed)
    assert (committed / "table2.md").read_text() == "new"
    assert (committed / "users-0-1" / "table2.md").read_text() == "a variant, made separately"
    assert (mine / "notes.txt").read_text() == "mine"
    assert sorted(p.name for p in (tmp_path / "results").iterdir()) == [".table2.new", "table2"]
    (new / "model.npz").write_bytes(b"model")
    (tmp_path / "results" / ".model.npz.new").write_text("mine too")
    reproduce._replace(new / "model.npz", tmp_path / "results" / "model.npz")
    assert (tmp_path / "results" / "model.npz").read_bytes() == b"model"
    assert (tmp_path / "results" / ".model.npz.new").read_text() == "mine too"
