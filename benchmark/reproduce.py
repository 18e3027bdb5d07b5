"""``fsv-bench reproduce``: regenerate every committed result and check it against the committed values.

    fsv-bench reproduce [--only NAMES] [--write] [--data DIR] [--workers N] [--list]

Each committed result (the reference run of the main command, Table 1 against the ideal and a
lab's AHRS, Table 2 and its variants, the shipped internal-force model) is a :class:`Result`: the
documented commands that make it, the datasets it needs (generated once into ``--data``, default ``data/``, and resumed), and a
comparison with tolerances. Without ``--write`` the results are made in a temporary folder and
compared with the committed ones; every value that moved beyond its tolerance is printed and the
command exits 1. With ``--write`` the committed files are replaced (each folder swapped in whole
once complete) and ``results/reproduce.json`` records, per result, the code fingerprint and the
machine (:func:`fsv.provenance.provenance`) that made it.

Tolerances. On one machine every stage is deterministic; across OpenBLAS kernels the world, the
tracker and the kinematics are bit-identical (fixed-order arithmetic, :mod:`fsv.linalg`) and the
cone solver differs in the tenth digit. Numbers are therefore compared to a relative 1e-6
(``REL_TOL``) and an absolute 1e-9; a machine whose NumPy dispatches other SIMD code (for example
AVX-512 transcendental functions) may move tracked results further, and the comparison says where.

Staleness without regenerating: :func:`benchmark.fingerprint.results_fingerprint` hashes the source that produces the
results (``fsv/``, ``sim_assets/`` and the world and scoring modules of ``benchmark/``) with
comments and docstrings stripped; a test compares it with the fingerprint recorded at the last
``--write``, so a change to the world, the tracker or the learning that forgets to regenerate
fails the test suite.
"""

from __future__ import annotations

import argparse
import json
import math
import pathlib
import runpy
import shutil
import sys
import tempfile
import time
from dataclasses import dataclass
from typing import Callable

import numpy as np

from benchmark.atomic import atomic_path, staging_folder, swap_folder, write_bytes, write_text
from benchmark.commands.digests import STAGES, first_difference
from benchmark.errors import BenchmarkError
from benchmark.fingerprint import results_fingerprint
from benchmark.limits import MAX_WORKERS, integer

INTERRUPTED = "each committed result is as it was or wholly replaced"
"""What Ctrl-C leaves, as the interrupted command says it (`fsv-bench <sub-command>: interrupted; ...`)."""

ROOT = pathlib.Path(__file__).resolve().parent.parent
RECORD = "results/reproduce.json"
REL_TOL = 1e-6
ABS_TOL = 1e-9

_UNCOMPARED = frozenset({"timing_s", "provenance", "rendered", "seconds", "train_seconds", "frames_per_s",
                         "frames_per_s_after_first", "first_frame_s", "compile_s", "steps_per_s", "stage_ms_per_frame",
                         "overlay", "plot", "fig6", "command", "episode", "summary", "path", "digests"})
"""Keys whose values measure this run's speed or name where it ran or what it wrote: never compared
(``digests`` are compared as a whole, :func:`_compare_run`)."""

class ReproduceError(BenchmarkError):
    """A committed result differs from its regeneration, or a regeneration failed."""


_TABLE2_GRID = ["--tasks", "lift", "--grasps", "0,1", "--masses", "1,4", "--seeds", "0-5"]
_ALL_TASKS = ",".join(("lift", "place", "release", "rotate", "shake", "free", "excite-tx", "excite-ty", "excite-tz",
                       "excite-rx", "excite-ry", "excite-rz"))
TRAIN_PEOPLE = 40
"""People of the shipped model's training set (training split, 1000-1039): each through every task once."""
CURVE_PEOPLE = 80
"""People of the learning curve's training set (training split, 1000-1079; the first 40 are the
shipped model's), each with a calibration recording."""
SUITE_PEOPLE = 48
"""People of each split's suite (``standard``: test 500-547; ``dev``: 100-147), each calibrated."""
_RECORDING = ["--design", "people", "--tasks", "lift", "--masses", "0,2", "--seeds", "900,901", "--duration", "6"]
"""A person's calibration recording: two 6 s lifts with their own grasp, the 0.30 and the 0.60 kg box."""

def _training_set(people: int, first: int = 0) -> list:
    """The training split's ``people`` people from position ``first``, each with their own grasp and
    view through every task once, the six masses rotating, seed 100."""
    return ["--split", "train", "--design", "people", "--tasks", _ALL_TASKS, "--users",
            f"{first}-{first + people - 1}", "--masses", "0-5", "--seeds", "100"]


DATASETS = {
    "table2": _TABLE2_GRID + ["--users", "0,4"],
    "table2-users-0-1": _TABLE2_GRID + ["--users", "0,1"],
    "table2-error-model": _TABLE2_GRID + ["--users", "0,4", "--contacts", "error-model"],
    "table2-oracle-contacts": _TABLE2_GRID + ["--users", "0,4", "--contacts", "oracle"],
    "train": _training_set(TRAIN_PEOPLE) + ["--rows", "all"],
    "train-curve": _training_set(CURVE_PEOPLE) + ["--rows", "all"],
    "train-curve-more": _training_set(CURVE_PEOPLE, first=CURVE_PEOPLE) + ["--rows", "all"],
    "calibration": ["--tasks", "lift", "--users", "0-4", "--grasps", "0-3", "--masses", "0,2", "--seeds", "900"],
    "calibration-train": ["--split", "train", "--users", f"0-{TRAIN_PEOPLE - 1}"] + _RECORDING,
    "calibration-train-curve": ["--split", "train", "--users", f"0-{CURVE_PEOPLE - 1}"] + _RECORDING,
    "calibration-dev": ["--split", "dev", "--users", f"0-{SUITE_PEOPLE - 1}"] + _RECORDING,
    "calibration-test": ["--split", "test", "--users", f"0-{SUITE_PEOPLE - 1}"] + _RECORDING,
}
"""``fsv-bench generate`` arguments of every dataset a committed result is made from: the Table 2
cohort's, the shipped models' training set (training people only, :data:`TRAIN_PEOPLE`; every frame, for the
end-to-end network, of which the paper's networks read the paper's rows), the learning curve's (:data:`CURVE_PEOPLE`, with their recordings),
the learned method's curve's next :data:`CURVE_PEOPLE` training people (1080-1159, whose drawn grasps
are solved at run time, not stored), and the calibration recordings (the named users' eight 10 s lifts each; every other person's
:data:`_RECORDING`, never scored)."""


@dataclass(frozen=True)
class Result:
    """One committed result.

    Attributes:
        name: Name used by ``--only``.
        path: The committed file or folder, relative to the repository.
        datasets: Names in :data:`DATASETS` it is made from.
        commands: Its ``fsv-bench`` (or ``python -m``) commands, ``{data}``/``{out}`` to be filled in.
        compare: ``(new, committed) -> [difference, ...]`` on the two paths.
        docs_pictures: ``(file in the result, path under docs/)`` pairs: pictures the docs show,
            copied there whenever the result is written, so the docs never show an older run.
        omitted: Files its commands write that the committed result leaves out (removed after them).
    """

    name: str
    path: str
    datasets: tuple
    commands: tuple
    compare: Callable
    docs_pictures: tuple = ()
    omitted: tuple = ()


def _leaves(obj, prefix=""):
    if isinstance(obj, dict):
        for k, v in obj.items():
            yield from _leaves(v, f"{prefix}/{k}")
    elif isinstance(obj, list):
        for i, v in enumerate(obj):
            yield from _leaves(v, f"{prefix}[{i}]")
    else:
        yield prefix, obj


def compare_values(new, old, where: str = "") -> list[str]:
    """Differences between two JSON-like values beyond the tolerances (uncompared keys skipped).

    Args:
        new: The regenerated value (nested dicts and lists of numbers, strings, booleans, None).
        old: The committed value.
        where: Label prefixed to every difference.

    Returns:
        One line per differing leaf: ``where/key: committed -> regenerated``.
    """
    a, b = dict(_leaves(new)), dict(_leaves(old))
    out = []
    for key in sorted(set(a) | set(b)):
        if any(seg.split("[")[0] in _UNCOMPARED for seg in key.split("/")):
            continue
        x, y = a.get(key, "<missing>"), b.get(key, "<missing>")
        if isinstance(x, (int, float)) and isinstance(y, (int, float)) and not isinstance(x, bool):
            if (math.isnan(x) and math.isnan(y)) or math.isclose(x, y, rel_tol=REL_TOL, abs_tol=ABS_TOL):
                continue
        elif x == y:
            continue
        out.append(f"{where}{key}: {y!r} -> {x!r}")
    return out


def _compare_json(name: str):
    def compare(new: pathlib.Path, old: pathlib.Path) -> list[str]:
        if not (old / name).exists():
            return [f"{old / name}: not committed"]
        return compare_values(json.loads((new / name).read_text()), json.loads((old / name).read_text()),
                              f"{old.name}/{name}")
    return compare


def _compare_csv(name: str):
    def compare(new: pathlib.Path, old: pathlib.Path) -> list[str]:
        import pandas as pd  # lazy: pandas (0.3 s) off `fsv-bench reproduce --list`

        if not (old / name).exists():
            return [f"{old / name}: not committed"]
        a, b = pd.read_csv(new / name), pd.read_csv(old / name)
        return compare_values(a.to_dict("list"), b.to_dict("list"), f"{old.name}/{name}")
    return compare


def _compare_run(new: pathlib.Path, old: pathlib.Path) -> list[str]:
    """The main command's run: first the first stage whose output differs (from the runs'
    ``digests``), then every value that moved and Table 1's table."""

    diffs = _compare_json("summary.json")(new, old) + _compare_csv("table1.csv")(new, old)
    if not (old / "summary.json").exists():
        return diffs
    a = json.loads((new / "summary.json").read_text()).get("digests")
    b = json.loads((old / "summary.json").read_text()).get("digests")
    stage = first_difference(a, b)
    if stage is None:
        return diffs
    if stage == "digests":
        return [f"{old.name}/summary.json: no stage digests to compare (regenerate with --write)"] + diffs
    same = STAGES[:STAGES.index(stage)]
    return [f"{old.name}/summary.json: the first stage whose output differs is {stage}"
            + (f" ({', '.join(same)} identical)" if same else "")] + diffs


def _compare_model(new: pathlib.Path, old: pathlib.Path) -> list[str]:
    from fsv.learn import load  # lazy: scipy, numba, clarabel (0.65 s) off `fsv-bench reproduce --list`

    a, b = load(new), load(old)
    diffs = compare_values(a.metadata.get("cross_validation"), b.metadata.get("cross_validation"), "cross_validation")
    sa, sb = a.state(), b.state()
    for key in ("net_l2", "net_decomp"):
        for i, (x, y) in enumerate(zip(sa[key], sb[key])):
            for j, (u, v) in enumerate(zip(x, y)):
                for p in ("weight", "bias"):
                    d = float(np.max(np.abs(u[p] - v[p]))) if u[p].shape == v[p].shape else float("inf")
                    if d > REL_TOL:
                        diffs.append(f"{key}[{i}][{j}].{p}: weights differ by up to {d:.2e}")
    return diffs


def _compare_direct_model(new: pathlib.Path, old: pathlib.Path) -> list[str]:
    from fsv.learn import load_direct  # lazy: scipy, numba, clarabel (0.65 s) off `fsv-bench reproduce --list`

    a, b = load_direct(new), load_direct(old)
    keys = ("samples", "held_out_samples", "best_epoch", "val_loss")
    diffs = compare_values({k: a.metadata.get(k) for k in keys}, {k: b.metadata.get(k) for k in keys}, "metadata")
    if len(a.layers) != len(b.layers):
        return diffs + [f"layers: {len(b.layers)} -> {len(a.layers)}"]
    for i, ((Wa, ba), (Wb, bb)) in enumerate(zip(a.layers, b.layers)):
        for p, u, v in (("weight", Wa, Wb), ("bias", ba, bb)):
            d = float(np.max(np.abs(u - v))) if u.shape == v.shape else float("inf")
            if d > REL_TOL:
                diffs.append(f"layers[{i}].{p}: weights differ by up to {d:.2e}")
    return diffs


def _table2(out_sub: str, data: str, extra: tuple = ()) -> Result:
    path = "results/table2" + (f"/{out_sub}" if out_sub else "")
    return Result(name="table2" + (f"-{out_sub}" if out_sub else ""), path=path, datasets=(data,),
                  commands=(("fsv-bench", "table2", "--data", f"{{data}}/{data}", "--out", "{out}") + extra,),
                  compare=_compare_json("table2.json"))


def _compare_calibration(new: pathlib.Path, old: pathlib.Path) -> list[str]:
    return compare_values(json.loads(new.read_text())["users"], json.loads(old.read_text())["users"], "users")


RESULTS = (
    Result(name="grip-calibration", path="sim_assets/calibration/grip_calibration.json",
           datasets=("calibration", "calibration-train", "calibration-dev", "calibration-test"),
           commands=(("fsv-bench", "calibrate", "--data", "{data}/calibration", "--data", "{data}/calibration-train",
                      "--data", "{data}/calibration-dev", "--data", "{data}/calibration-test", "--out", "{out}"),),
           compare=_compare_calibration),
    Result(name="shipped-model", path="fsv/data/internal_forces.npz", datasets=("train",),
           commands=(("fsv-bench", "train", "--data", "{data}/train", "--out", "{out}", "--folds", "3",
                      "--amount-loss", "relative", "--grip", "{root}/sim_assets/calibration/grip_calibration.json"),),
           compare=_compare_model),
    Result(name="shipped-model-blind", path="fsv/data/internal_forces_blind.npz", datasets=("train",),
           commands=(("fsv-bench", "train", "--data", "{data}/train", "--out", "{out}", "--folds", "3",
                      "--amount-loss", "relative"),),
           compare=_compare_model),
    Result(name="direct-model", path="fsv/data/direct_forces.npz", datasets=("train",),
           commands=(("fsv-bench", "train-direct", "--data", "{data}/train", "--out", "{out}", "--quiet"),),
           compare=_compare_direct_model),
    Result(name="learning-curve", path="results/learning_curve", datasets=("train-curve", "calibration-train-curve"),
           commands=(("python", "-m", "benchmark.commands.learning_curve", "--data", "{data}/train-curve", "--people",
                      f"5,20,40,{CURVE_PEOPLE}", "--calibration", "{data}/calibration-train-curve", "--suite", "dev",
                      "--workers", "2", "--quiet", "--out", "{out}"),),
           compare=_compare_json("learning_curve.json")),
    Result(name="direct-curve", path="results/direct_curve", datasets=("train-curve", "train-curve-more"),
           commands=(("python", "-m", "benchmark.commands.direct_curve", "--data", "{data}/train-curve", "--data",
                      "{data}/train-curve-more", "--people", f"{TRAIN_PEOPLE},{CURVE_PEOPLE},{2 * CURVE_PEOPLE}",
                      "--suite", "dev", "--workers", "2", "--quiet", "--out", "{out}"),),
           compare=_compare_json("direct_curve.json")),
    Result(name="reference-run", path="results/lift-u0-g0-m0-s0", datasets=(),
           commands=(("fsv-bench", "--task", "lift", "--noise", "0.01", "--no-gif", "--out", "{out}"),),
           compare=_compare_run, omitted=("episode.npz",),  # the reference's episode is not committed
           docs_pictures=(("depth_preview.png", "depth_preview.png"),
                          ("tracking_overlay.png", "pictures/lift-u0-g0-s0-tracking_overlay.png"),
                          ("forces_fig5.png", "pictures/lift-u0-g0-s0-forces_fig5.png"))),
    Result(name="walkthrough-rotate", path="results/rotate-u2-g3-m0-s17", datasets=(),
           commands=(("fsv-bench", "--task", "rotate", "--user", "2", "--grasp", "3", "--seed", "17", "--noise", "0.01",
                      "--no-gif", "--out", "{out}"),),
           compare=_compare_run,
           docs_pictures=(("tracking_overlay.png", "pictures/rotate-u2-g3-s17-tracking_overlay.png"),
                          ("forces_fig5.png", "pictures/rotate-u2-g3-s17-forces_fig5.png"))),
    Result(name="world", path="results/world", datasets=(),
           commands=(("python", "-m", "benchmark.commands.humanness", "--suite", "standard", "--quiet", "--out", "{out}"),),
           compare=_compare_json("humanness.json")),
    Result(name="world-whole-hand", path="results/world_whole_hand", datasets=(),
           commands=(("python", "-m", "benchmark.commands.humanness", "--suite", "standard", "--grip-control", "whole-hand",
                      "--quiet", "--out", "{out}"),),
           compare=_compare_json("humanness.json")),
    Result(name="table1", path="results/table1", datasets=(),
           commands=(("python", "-m", "benchmark.commands.table1", "--score", "--seeds", "0,1,2", "--out", "{out}"),),
           compare=_compare_csv("table1.csv")),
    Result(name="table1-ahrs", path="results/table1_ahrs", datasets=(),
           commands=(("python", "-m", "benchmark.commands.table1", "--score", "--seeds", "0,1,2", "--imu", "mti-300",
                      "--out", "{out}"),),
           compare=lambda new, old: _compare_csv("table1.csv")(new, old) + _compare_json("ahrs.json")(new, old)),
    Result(name="standard", path="results/standard", datasets=(),
           commands=(("fsv-bench", "leaderboard", "--suite", "standard", "--quiet", "--workers", "2", "--out",
                      "{out}"),),
           compare=lambda new, old: _compare_json("reference/scores.json")(new, old)),
    Result(name="knowledge-ablation", path="results/knowledge_ablation", datasets=(),
           commands=(("fsv-bench", "sweep", "--suite", "dev", "--axis", "knowledge", "--values",
                      "exact,lab-hand:0,lab-hand,lab-box,lab-camera,lab,lab:2", "--workers", "2", "--quiet", "--out", "{out}"),),
           compare=_compare_json("sweep.json")),
    Result(name="skin-ablation", path="results/skin_ablation", datasets=(),
           commands=(("fsv-bench", "sweep", "--suite", "dev", "--axis", "hand_surface", "--values",
                      "capsules,skin-rigid,skin", "--workers", "2", "--quiet", "--out", "{out}"),),
           compare=_compare_json("sweep.json")),
    Result(name="failure-atlas", path="results/failure_atlas", datasets=(),
           commands=(("python", "-m", "benchmark.commands.atlas", "--suite", "dev", "--workers", "2", "--quiet",
                      "--out", "{out}"),),
           compare=_compare_json("atlas.json")),
    Result(name="colour-ablation", path="results/colour_ablation", datasets=(),
           commands=(("python", "-m", "benchmark.commands.colour_ablation", "--suite", "dev", "--workers", "2",
                      "--quiet", "--out", "{out}"),),
           compare=_compare_json("colour_ablation.json")),
    Result(name="smoke", path="results/smoke", datasets=(),
           commands=(("fsv-bench", "eval", "--suite", "smoke", "--quiet", "--out", "{out}"),),
           compare=lambda new, old: _compare_json("scores.json")(new, old)),
    Result(name="smoke-savgol", path="results/smoke_savgol", datasets=(),
           commands=(("fsv-bench", "eval", "--suite", "smoke", "--differentiator", "examples.savgol:SavitzkyGolay",
                      "--quiet", "--out", "{out}"),),
           compare=lambda new, old: _compare_json("scores.json")(new, old)),
    _table2("", "table2"),
    _table2("paper-rule-only", "table2", ("--max-excess", "inf")),
    _table2("users-0-1", "table2-users-0-1", ("--users", "0,1")),
    _table2("error-model", "table2-error-model"),
    _table2("oracle-contacts", "table2-oracle-contacts"),
)
"""Every committed result, in the order they are made (the shipped model uses the users' grip
calibration, the reference run the shipped model)."""


def recorded() -> dict:
    """The record of the last ``--write`` (``results/reproduce.json``), or {} if none."""
    path = ROOT / RECORD
    return json.loads(path.read_text()) if path.exists() else {}


def _run(command: tuple, data: pathlib.Path, out: pathlib.Path, documented_out: str, log) -> None:
    argv = [c.format(data=data, out=out, root=ROOT) for c in command]
    print("$ " + " ".join(argv), file=log, flush=True)
    if argv[0] == "fsv-bench":
        from benchmark.commands.cli import main  # lazy: MuJoCo (0.25 s) off `fsv-bench reproduce --list`

        saved = sys.argv  # what a model records as its command: the documented one
        sys.argv = [c.format(data="data", out=documented_out, root=".") for c in command]
        try:
            code = main(argv[1:])
        finally:
            sys.argv = saved
    else:
        module = argv[2]
        saved = sys.argv
        sys.argv = [module] + argv[3:]
        try:
            runpy.run_module(module, run_name="__main__")
            code = 0
        except SystemExit as e:
            code = e.code or 0
        finally:
            sys.argv = saved
    main_command = argv[0] == "fsv-bench" and argv[1].startswith("--")  # the main command: its verdict is a result
    if code != 0 and not (code == 1 and (argv[1:2] in (["eval"], ["leaderboard"]) or main_command)):  # a failed gate too
        raise ReproduceError(f"{' '.join(argv)} exited with status {code}")


def _generate(name: str, data: pathlib.Path, workers: int | None, log) -> None:
    from benchmark.commands.cli import main  # lazy: MuJoCo (0.25 s) off `fsv-bench reproduce --list`

    argv = ["generate", "--out", str(data / name), *DATASETS[name], "--no-progress"]
    if workers:
        argv += ["--workers", str(workers)]
    print("$ fsv-bench " + " ".join(argv), file=log, flush=True)
    if main(argv) != 0:
        raise ReproduceError(f"fsv-bench {' '.join(argv)} failed")


def make(result: Result, data: pathlib.Path, out: pathlib.Path, *, workers: int | None = None, log=sys.stdout) -> None:
    """Makes one result into ``out`` (a file path for a model, a folder otherwise), datasets first."""
    for name in result.datasets:
        _generate(name, data, workers, log)
    for command in result.commands:
        _run(command, data, out, result.path, log)
    for name in result.omitted:
        (out / name).unlink(missing_ok=True)


def _select(only: str | None) -> list[Result]:
    if not only:
        return list(RESULTS)
    names = [n.strip() for n in only.split(",") if n.strip()]
    known = {r.name: r for r in RESULTS}
    bad = [n for n in names if n not in known]
    if bad:
        raise ValueError(f"--only {','.join(bad)}: no such result; accepted: {', '.join(known)}")
    return [known[n] for n in names]


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--only", default=None, help="comma-separated result names (default: all; see --list)")
    p.add_argument("--write", action="store_true", help="replace the committed results (default: only compare)")
    p.add_argument("--data", default="data", help="folder of the datasets, generated or resumed (default: data)")
    p.add_argument("--workers", type=integer(1, MAX_WORKERS), default=None,
                   help=f"local worker processes for the datasets, 1 to {MAX_WORKERS} (default: all cores)")
    p.add_argument("--list", action="store_true", help="list the results and their commands, then exit")


def run(args: argparse.Namespace) -> list[str]:
    """Runs ``fsv-bench reproduce``; returns the differences (raises ReproduceError if any)."""
    results = _select(args.only)
    if args.workers is not None and args.workers < 1:
        raise ValueError(f"--workers must be >= 1, got {args.workers}")
    if args.list:
        for r in results:
            print(f"{r.name}: {r.path}\n  datasets: " + (", ".join(
                f"{d} ({' '.join(DATASETS[d])})" for d in r.datasets) or "none"))
            for c in r.commands:
                print("  " + " ".join(c))
        return []
    from fsv.provenance import provenance  # lazy: scipy, numba, clarabel (0.65 s) off `fsv-bench reproduce --list`

    data = pathlib.Path(args.data).resolve()
    data.mkdir(parents=True, exist_ok=True)
    differences = []
    with tempfile.TemporaryDirectory(prefix="fsv-reproduce-") as tmp:
        for r in results:
            t0 = time.perf_counter()
            committed = ROOT / r.path
            new = pathlib.Path(tmp) / (r.name + committed.suffix)
            make(r, data, new, workers=args.workers)
            diffs = r.compare(new, committed) if committed.exists() else [f"{r.path}: not committed yet"]
            differences += [f"{r.name}: {d}" for d in diffs]
            status = "unchanged" if not diffs else f"{len(diffs)} values moved"
            if args.write:
                _replace(new, committed)
                for picture, shown in r.docs_pictures:
                    write_bytes(ROOT / "docs" / shown, (committed / picture).read_bytes())
                record = recorded()  # read again: another reproduce of other results may have written since
                record.setdefault("results", {})[r.name] = {"path": r.path, "commands": [" ".join(c) for c in r.commands],
                                             "datasets": {d: DATASETS[d] for d in r.datasets},
                                             "seconds": time.perf_counter() - t0}
                record["code_fingerprint"] = results_fingerprint()
                record["provenance"] = provenance()
                write_text(ROOT / RECORD, json.dumps(record, indent=1) + "\n")
                status += ", written"
            print(f"reproduce {r.name}: {status} ({time.perf_counter() - t0:.0f} s)", flush=True)
    for d in differences:
        print("  " + d)
    if differences and not args.write:
        raise ReproduceError(f"{len(differences)} committed values differ from their regeneration (listed above); "
                             f"`fsv-bench reproduce --write` replaces them")
    return differences


def _replace(new: pathlib.Path, committed: pathlib.Path) -> None:
    """Swaps ``new`` in for ``committed`` (a file, or a folder whose sub-folders of other results are kept)."""
    committed.parent.mkdir(parents=True, exist_ok=True)
    if new.is_file():
        with atomic_path(committed) as tmp:
            shutil.copyfile(new, tmp)
        return
    staging = staging_folder(committed)
    try:
        shutil.copytree(new, staging, dirs_exist_ok=True)
        if committed.exists():  # keep nested results (results/table2/<variant>/) that are made separately
            for child in committed.iterdir():
                if child.is_dir() and not (staging / child.name).exists():
                    shutil.copytree(child, staging / child.name)
        swap_folder(staging, committed, replace_any=True)  # the committed results are replaced on purpose
    except BaseException:
        shutil.rmtree(staging, ignore_errors=True)
        raise

