"""Every option of ``fsv-bench`` and of every sub-command, fed ``nan``, ``-1``, ``1e9`` and ``''``.

The options are enumerated from the parsers themselves (``parser._actions``). Each command's first
piece of work (the staging folder, the generation, the loading of a dataset, the evaluation) is
replaced by a function raising :class:`Worked`: a value either is refused with exit status 2 and
one line on stderr, in seconds, having written nothing, or reaches the work and must then be in
:data:`ACCEPTED`, each with its reason. A stale entry of :data:`ACCEPTED` fails too.
"""

from __future__ import annotations

import math
import os
import time

import pytest

from benchmark.commands import cli, entry

VALUES = ("nan", "-1", "1e9", "")


class Worked(Exception):
    """The command got past its validation to its work."""


def _work(*args, **kwargs):
    raise Worked()


COMMANDS = {
    # name: (a valid command line, the command's first work)
    "main": (["--out", "run"], "benchmark.commands.cli.staging_folder"),
    "generate": (["--out", "data"], "benchmark.paper.dataset.cli.generate"),
    "calibrate": (["--data", "data", "--out", "cal.json"], "benchmark.paper.dataset.files.read_header"),
    "train": (["--data", "data", "--out", "model.npz"], "benchmark.paper.training.load_dataset"),
    "train-direct": (["--data", "data", "--out", "model.npz"], "benchmark.paper.direct_training.check_all_rows"),
    "table2": (["--data", "data"], "benchmark.paper.table2.score"),
    "reproduce": (["--only", "smoke"], "benchmark.reproduce.make"),
    "eval": (["--suite", "smoke", "--out", "ev"], "benchmark.suites.evaluate.evaluate_many"),
    "compare": (["a", "b"], "benchmark.suites.compare.load_scores"),
    "export": (["--suite", "smoke", "--out", "ex"], "benchmark.exchange.export.export_suite"),
    "score": (["--suite", "smoke", "--out", "sc", "--estimates", "est"], "benchmark.exchange.score.estimate_paths"),
    "leaderboard": (["--suite", "smoke", "--out", "lb"], "benchmark.suites.leaderboard.evaluate_many"),
    "sweep": (["--suite", "smoke", "--axis", "noise", "--values", "0.005,0.01", "--out", "sw"],
              "benchmark.suites.evaluate.evaluate"),
    "check": (["est.npz"], "benchmark.exchange.check.check"),
}

_NAMES = ("nan", "-1", "1e9")
"""Values that are ordinary file or folder names."""

ACCEPTED = {
    **{(c, "--out", v): "a file or folder name" for c in ("main", "generate", "calibrate", "train", "train-direct",
                                                           "table2", "eval", "compare", "export", "score", "leaderboard",
                                                           "sweep")
       for v in _NAMES},
    **{(c, "--cache", v): "a folder name (the cache is made there)" for c in ("eval", "export", "score", "leaderboard",
                                                                              "sweep") for v in _NAMES},
    **{(c, "--data", v): "a folder name, read after this test's stand-in for the work"
       for c in ("calibrate", "train", "train-direct", "table2") for v in _NAMES},
    **{("reproduce", "--data", v): "a folder name (the datasets are generated there)" for v in _NAMES},
    **{("score", "--estimates", v): "a folder name, read after this test's stand-in for the work" for v in _NAMES},
    **{("check", "--inputs", v): "a file name, read after this test's stand-in for the work" for v in _NAMES},
    ("train", "--max-excess", "1e9"): "a tolerance of 1e9 N keeps every sample; no work grows with it",
    ("table2", "--max-excess", "1e9"): "a tolerance of 1e9 N keeps every sample; no work grows with it",
}
"""(command, option, value) accepted on purpose, with the reason."""


def _options(parser):
    """Every option of ``parser`` that takes a value."""
    return [a for a in parser._actions if a.option_strings and a.nargs != 0]


def _parser(name):
    return cli.build_parser() if name == "main" else entry.subcommand_parser(name)[1]


def _argv(name, base, option, value):
    if option in base:
        i = base.index(option)
        args = base[:i + 1] + [value] + base[i + 2:]
    else:
        args = base + [option, value]
    return args if name == "main" else [name] + args


def _tree(root):
    return sorted(os.path.join(d, f) for d, ds, fs in os.walk(root) for f in ds + fs)


def _outcome(name, argv, target, monkeypatch, capsys):
    """``("refused", stderr lines, seconds)`` or ``("accepted", ...)``."""
    monkeypatch.setattr(target, _work)
    capsys.readouterr()
    t0 = time.perf_counter()
    try:
        code = entry.run(argv)
    except Worked:
        return "accepted", [], time.perf_counter() - t0
    except SystemExit as e:
        code = e.code
    seconds = time.perf_counter() - t0
    err = capsys.readouterr().err.splitlines()
    return ("refused" if code == 2 else f"exit {code}"), err, seconds


@pytest.mark.parametrize("name", list(COMMANDS))
def test_every_option_refuses_nan_negative_huge_and_empty_values_before_any_work(name, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    base, target = COMMANDS[name]
    status, err, _ = _outcome(name, base if name == "main" else [name] + base, target, monkeypatch, capsys)
    assert status == "accepted", f"{name} {' '.join(base)}: the valid command line did not reach the work: {err}"
    accepted, problems = set(), []
    for action in _options(_parser(name)):
        option = max(action.option_strings, key=len)
        for value in VALUES:
            argv = _argv(name, base, option, value)
            before = _tree(tmp_path)
            status, err, seconds = _outcome(name, argv, target, monkeypatch, capsys)
            if status == "accepted":
                accepted.add((name, option, value))
                if (name, option, value) not in ACCEPTED:
                    problems.append(f"{option} {value!r}: accepted")
                continue
            if status != "refused" or len(err) != 1 or seconds > 5:
                problems.append(f"{option} {value!r}: {status}, {len(err)} lines, {seconds:.1f} s: {err[:2]}")
            if _tree(tmp_path) != before:
                problems.append(f"{option} {value!r}: wrote {sorted(set(_tree(tmp_path)) - set(before))}")
    assert not problems, f"fsv-bench {name}:\n" + "\n".join(problems)
    stale = {k for k in ACCEPTED if k[0] == name} - accepted
    assert not stale, f"fsv-bench {name}: listed as accepted but refused: {sorted(stale)}"


UNBOUNDED = {
    **{("main", o): "an index or a seed: it names what is simulated, no work grows with it"
       for o in ("--user", "--grasp", "--mass", "--seed", "--view")},
    ("main", "--noise"): "bounded by the scenario (0 to 0.1 m), as its help says",
    ("main", "--duration"): "bounded by the scenario (up to 120 s), as its help says",
    ("generate", "--noise"): "bounded by the scenario (0 to 0.1 m), as its help says",
    ("generate", "--duration"): "bounded by the scenario (up to 120 s), as its help says",
}
"""Number options without a ``benchmark.limits`` type, each with its reason."""


@pytest.mark.parametrize("name", list(COMMANDS))
def test_every_number_option_states_its_upper_bound_in_its_help(name):
    problems = []
    for action in _options(_parser(name)):
        option = max(action.option_strings, key=len)
        high = getattr(action.type, "high", None)
        if high is None:
            if action.type in (int, float) and (name, option) not in UNBOUNDED:
                problems.append(f"{option}: a number without a bound")
            continue
        if math.isfinite(high) and not any(f in (action.help or "") for f in (f"{high:,}", f"{high:g}", f"{high}")):
            problems.append(f"{option}: its help does not state its upper bound {high:,}")
    assert not problems, f"fsv-bench {name}:\n" + "\n".join(problems)


def test_every_sub_command_is_enumerated():
    assert set(COMMANDS) == {"main", *cli.ALL_SUBCOMMANDS}
