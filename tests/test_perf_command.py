"""benchmark.perf.command: the main command's whole-process time; bad arguments are refused before any run."""

import pytest

from benchmark.perf import command


@pytest.mark.parametrize("argv, needle", [
    (["--trees", "9570bfc"], "--trees '9570bfc': not a source tree of fsv-bench"),
    (["--runs", "0"], "--runs 0: accepted: 1 or more"),
    (["--streams", "depth,sound"], "--streams 'depth,sound': stream 'sound': accepted: depth, colour"),
])
def test_bad_arguments_get_one_line_and_exit_2_before_any_run(argv, needle, monkeypatch, capsys):
    def never(*_):
        raise AssertionError("a run started")

    monkeypatch.setattr(command, "run_once", never)
    assert command.main(argv) == 2
    err = capsys.readouterr().err
    assert needle in err and err.count("\n") == 1, err
