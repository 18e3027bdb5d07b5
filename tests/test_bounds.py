"""Bounded inputs, checked before any work: grids, epochs and members, the initialisation's scale,
the plausibility rule, the cache (``benchmark.limits``)."""

import os
import subprocess
import sys
import time

import pytest

from benchmark.commands.cli import main
from benchmark.errors import DatasetError
from benchmark.limits import MAX_EPISODES, count_ints, parse_ints
from benchmark.paper.dataset.spec import DatasetSpec


class Worked(Exception):
    """The command got past its validation to its work."""


def _work(*args, **kwargs):
    raise Worked()


def _refused(argv, capsys, tmp_path) -> str:
    """Runs ``fsv-bench argv`` in ``tmp_path``; asserts exit 2, one line, under 5 s of this process's
    CPU (not wall time, which a loaded machine stretches), nothing written; returns the line."""
    before = sorted(tmp_path.rglob("*"))
    capsys.readouterr()
    t0 = time.process_time()
    try:
        code = main(argv)
    except SystemExit as e:  # argparse's own errors
        code = e.code
    seconds = time.process_time() - t0
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1, err
    assert seconds < 5
    assert sorted(tmp_path.rglob("*")) == before
    return err


def test_ranges_are_counted_without_being_built():
    t0 = time.process_time()  # CPU, not wall time: building the range would take seconds of it
    assert count_ints("0-100000000,5", "--seeds") == 100_000_002
    assert time.process_time() - t0 < 0.1
    assert parse_ints("0,2,5-7", "--seeds") == (0, 2, 5, 6, 7)
    with pytest.raises(ValueError, match=r"--seeds '0-100000000': 100,000,001 values, more than the 100,000 accepted"):
        parse_ints("0-100000000", "--seeds")
    for bad in ("7-5", "-1", "1-", "a", ""):
        with pytest.raises(ValueError, match="--users"):
            parse_ints(bad, "--users")


@pytest.mark.parametrize("grid, needle", [
    (["--seeds", "0-100000000"], "100,000,001 --seeds = 100,000,001 episodes, more than the 100,000 accepted"),
    (["--seeds", "0-199999"], "200,000 episodes"),
    (["--tasks", "lift,place", "--users", "0-9", "--grasps", "0,1", "--masses", "0-5", "--seeds", "0-999"],
     "2 --tasks x 10 --users x 2 --grasps x 1 --views x 6 --masses x 1,000 --seeds = 240,000 episodes"),
    (["--design", "people", "--users", "0-999", "--tasks", "lift,place", "--seeds", "0-99"],
     "2 --tasks x 1,000 --users x 100 --seeds = 200,000 episodes"),
], ids=["seeds-0-100000000", "seeds-0-199999", "product", "people"])
def test_generate_refuses_a_grid_above_the_bound_in_seconds_without_building_it(grid, needle, tmp_path, capsys,
                                                                                 monkeypatch):
    monkeypatch.setattr("benchmark.paper.dataset.cli.generate", _work)
    err = _refused(["generate", "--out", str(tmp_path / "data"), *grid], capsys, tmp_path)
    assert needle in err and "split the grid over several commands" in err


def test_a_dataset_spec_above_the_bound_is_refused():
    with pytest.raises(DatasetError, match="200,000 episodes, more than the 100,000 accepted"):
        DatasetSpec(seeds=tuple(range(2 * MAX_EPISODES)))


@pytest.mark.parametrize("argv, needle", [
    (["--epochs", "1e9"], "argument --epochs: expected an integer from 1 to 100,000, got '1e9'"),
    (["--epochs", "1000000000"], "argument --epochs: expected an integer from 1 to 100,000, got '1000000000'"),
    (["--epochs", "0"], "--epochs"),
    (["--members", "1000000"], "argument --members: expected an integer from 1 to 50"),
    (["--folds", "1"], "argument --folds: expected 0 (skip) or an integer from 2 to 100, got '1'"),
    (["--folds", "1000"], "--folds"),
    (["--seed", "-1"], "argument --seed: expected an integer from 0 to 4,294,967,295"),
    (["--max-excess", "nan"], "argument --max-excess: expected a number >= 0 N, or inf, got 'nan'"),
    (["--max-excess", "-1"], "--max-excess"),
    (["--max-excess=-inf"], "argument --max-excess: expected a number >= 0 N, or inf, got '-inf'"),
    (["--seeds", "0-100000000"], "--seeds '0-100000000': 100,000,001 values"),
])
def test_train_bounds_its_work_before_loading_anything(argv, needle, tmp_path, capsys, monkeypatch):
    monkeypatch.setattr("benchmark.paper.training.load_dataset", _work)
    err = _refused(["train", "--data", str(tmp_path), "--out", str(tmp_path / "m.npz"), *argv], capsys, tmp_path)
    assert needle in err


def test_max_excess_inf_turns_the_plausibility_rule_off_as_documented(tmp_path, monkeypatch):
    seen = {}

    def load(data, max_excess_n, **where):
        seen["rule"] = max_excess_n
        raise Worked()

    monkeypatch.setattr("benchmark.paper.training.load_dataset", load)
    with pytest.raises(Worked):
        main(["train", "--data", str(tmp_path), "--out", str(tmp_path / "m.npz"), "--max-excess", "inf"])
    assert seen["rule"] is None


@pytest.mark.parametrize("value", ["nan", "-1", "1e9", "10.5", "inf"])
def test_init_perturbation_is_refused_before_the_simulation(value, tmp_path, capsys, monkeypatch):
    monkeypatch.setattr("benchmark.commands.cli.staging_folder", _work)
    err = _refused(["--quiet", "--out", str(tmp_path / "run"), "--init-perturbation", value], capsys, tmp_path)
    assert f"argument --init-perturbation: expected a number from 0 to 10, got '{value}'" in err


@pytest.mark.parametrize("command", ["eval", "leaderboard", "export"])
def test_a_cache_that_is_a_file_is_refused_in_one_line(command, tmp_path, capsys, monkeypatch):
    monkeypatch.setattr("benchmark.suites.evaluate.evaluate_many", _work)
    monkeypatch.setattr("benchmark.suites.leaderboard.evaluate_many", _work)  # bound at its top
    monkeypatch.setattr("benchmark.exchange.export.export_suite", _work)
    cache = tmp_path / "cache.txt"
    cache.write_text("keep")
    err = _refused([command, "--suite", "smoke", "--out", str(tmp_path / "o"), "--cache", str(cache)], capsys, tmp_path)
    assert f"argument --cache: {cache}: exists and is not a folder" in err
    assert cache.read_text() == "keep"


@pytest.mark.parametrize("argv", [
    ["generate", "--out", "d", "--seeds", "0-100000000"],
    ["train", "--data", "d", "--out", "m.npz", "--epochs", "1e9"],
    ["--out", "r", "--init-perturbation", "nan"],
])
def test_the_console_script_refuses_in_seconds(argv, tmp_path):
    """One line, exit 2, nothing written, within 5 s of CPU (measured 1.7-2.0 s, the imports; CPU
    time, not wall time, which a loaded machine stretches: 3 s at load 6, 7.5 s at load 9)."""
    import resource

    def cpu_of_children():
        r = resource.getrusage(resource.RUSAGE_CHILDREN)
        return r.ru_utime + r.ru_stime

    before = cpu_of_children()
    out = subprocess.run([sys.executable, "-m", "benchmark.commands.entry", *argv], cwd=tmp_path, capture_output=True,
                         text=True, timeout=120, env={**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)})
    assert out.returncode == 2 and out.stderr.count("\n") == 1, out.stderr
    assert cpu_of_children() - before < 5
    assert not list(tmp_path.iterdir())
