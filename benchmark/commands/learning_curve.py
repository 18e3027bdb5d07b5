"""Does more generated training data help? ``python -m benchmark.commands.learning_curve``.

    python -m benchmark.commands.learning_curve --data DIR --people 5,20,40 --suite dev --out DIR
        [--grip FILE | --calibration DIR ...] [--workers N] [--cache DIR]

Trains the reference's two internal-force models, as the shipped ones are trained (relative
amount loss; one user-blind, one with the people's grip calibrations as inputs: the shipped file's,
another file's (``--grip``) or fitted from the people's calibration recordings, ``--calibration``),
on the first N people of a training dataset (``fsv-bench generate --split train --design people``) for each N of
``--people``, then scores them on the suite (``dev``: people never trained on, never scored by
``standard``) under their protocols (the user-blind model ``blind``, the other ``calibrated``),
beside the no-internal-force baseline. The episodes are rendered and tracked once for every model.
Writes ``learning_curve.json`` (per N: people, episodes, samples, every aggregate of both
protocols) and ``learning_curve.md``; the models go to ``DIR/models/`` (``people-N.npz`` with grip
inputs, ``people-N-blind.npz`` user-blind).
"""

from __future__ import annotations

import argparse
import contextlib
import importlib.resources
import io
import json
import pathlib
import sys

from benchmark.atomic import OutputFolderError, check_out, staged_folder, write_text
from benchmark.commands.parser import OneLineParser
from benchmark.errors import DatasetError
from benchmark.method import MethodSpec
from benchmark.method.grip_file import SHIPPED
from benchmark.method.protocol import PROTOCOLS
from benchmark.paper import calibration, training
from benchmark.paper.dataset.cli import parse_ints
from benchmark.paper.dataset.files import read_header
from benchmark.parallel import run_jobs
from benchmark.suites import get_suite
from benchmark.suites.evaluate import check_cache_args, evaluate_many, strict
from fsv.provenance import provenance

COLUMNS = (("learned_rel_err_pct", "learned [%]"), ("learned_mae_n", "MAE [N]"),
           ("learned_rel_err_pct_paper", "learned, paper's rule [%]"))
"""The curve's metrics (medians over the suite's episodes, with their intervals)."""


def people_of(data) -> list:
    """The dataset's people, in order (the first N train the N-people model)."""

    return list(read_header(data)["spec"]["users"])


def model_file(n: int, protocol: str) -> str:
    """The name of the N-people model of ``protocol`` in ``DIR/models/``."""
    return f"people-{n}{'-blind' if protocol == 'blind' else ''}.npz"


def train_model(data, users: list, grip, out: pathlib.Path) -> dict:
    """Trains one model on ``users``' episodes of ``data`` as ``fsv-bench train`` does with a shipped
    model's options, but no cross-validation: with the grip calibrations of ``grip`` (a file) as
    inputs, or user-blind if ``grip`` is None; its metadata."""

    parser = argparse.ArgumentParser()
    training.add_arguments(parser)
    args = parser.parse_args(["--data", str(data), "--out", str(out), "--users", ",".join(str(u) for u in users),
                              "--folds", "0", "--amount-loss", "relative", "--quiet"]
                             + ([] if grip is None else ["--grip", str(grip)]))
    return training.run(args).metadata


def fit_calibration(recordings: list, out: pathlib.Path, people: list, quiet: bool = False) -> None:
    """Fits the grip lines of ``recordings`` (calibration datasets) into the grip-calibration file
    ``out``, as ``fsv-bench calibrate`` does.

    Raises:
        DatasetError: If one of ``people`` has no line in the recordings (naming the first).
    """

    with contextlib.redirect_stdout(io.StringIO()) if quiet else contextlib.nullcontext():
        parser = argparse.ArgumentParser()
        calibration.add_arguments(parser)  # every option of `fsv-bench calibrate`, at its default
        args = parser.parse_args([a for r in recordings for a in ("--data", str(r))] + ["--out", str(out)])
        lines = calibration.run(args)
    missing = [u for u in people if u not in lines]
    if missing:
        raise DatasetError(f"--calibration {','.join(map(str, recordings))}: person {missing[0]} has no recording "
                           f"there ({len(missing)} of the {len(people)} training people lack one); accepted: "
                           "recordings of every training person")


def _train_job(job: tuple) -> dict:
    data, users, grip, out = job
    return train_model(data, users, grip, pathlib.Path(out))


def train_models(data, everyone: list, counts: list, grip, folder: pathlib.Path, workers: int = 1) -> dict:
    """Trains both protocols' models for every number of people in ``counts`` into ``folder``
    (:func:`model_file`), the largest first, on ``workers`` local processes (training is
    single-threaded; a model is the same whichever process trains it).

    Returns:
        ``{n: {protocol: metadata}}``.
    """
    from benchmark.commands.learning_curve import _train_job  # lazy: by its module's name, also as __main__

    keys = sorted(((n, pr) for n in counts for pr in PROTOCOLS), key=lambda k: -k[0])
    jobs = [(str(data), everyone[:n], None if pr == "blind" else str(grip), str(folder / model_file(n, pr)))
            for n, pr in keys]
    meta = {n: {} for n in counts}
    for i, metadata in run_jobs(_train_job, jobs, workers=workers):
        meta[keys[i][0]][keys[i][1]] = metadata
    return {n: {pr: meta[n][pr] for pr in PROTOCOLS} for n in counts}


def curve_markdown(suite, rows: list) -> str:
    """The table of the curve: per number of people and protocol, the medians [95 % intervals]."""
    lines = ["# Learning curve: the internal-force model against the number of training people",
             "", f"Scored on `{suite.name}` v{suite.version} ({len(suite.scenarios)} episodes, people never "
             "trained on); medians over the episodes [95 % bootstrap interval]. Per number of people, two models "
             "trained on the same samples: `blind`, the user-blind model; `calibrated`, the model with grip inputs, "
             "fed each person's calibration.", "",
             "| training people | episodes | samples | protocol | " + " | ".join(h for _, h in COLUMNS) + " |",
             "|---|---|---|---|" + "---|" * len(COLUMNS)]
    for r in rows:
        for protocol, agg in r["aggregate"].items():
            cells = " | ".join(_cell(agg[m]["median"]) for m, _ in COLUMNS)
            lines.append(f"| {r['people']} | {r['episodes']} | {r['samples']} | {protocol} | {cells} |")
    return "\n".join(lines) + "\n"


def _cell(agg: dict) -> str:
    if agg["value"] is None:
        return "-"
    return f"{agg['value']:.3g} [{agg['ci_low']:.3g}, {agg['ci_high']:.3g}]"


def main(argv=None) -> int:
    p = OneLineParser(prog="python -m benchmark.commands.learning_curve", description=__doc__.split("\n\n")[0])
    p.add_argument("--data", required=True, help="a training dataset (fsv-bench generate --split train --design people)")
    p.add_argument("--people", default="5,20,40", help="numbers of training people (default 5,20,40)")
    p.add_argument("--suite", default="dev", help="suite to score on (default dev)")
    p.add_argument("--grip", default=None, help="grip-calibration file of the training people (default: the shipped one)")
    p.add_argument("--calibration", action="append", default=None,
                   help="instead of --grip: the training people's calibration recordings (dataset folders, repeat for "
                        "several), fitted as `fsv-bench calibrate` does into models/grip_calibration.json")
    p.add_argument("--out", required=True, help="output folder")
    p.add_argument("--workers", type=int, default=1, help="local processes for training and scoring (default 1)")
    p.add_argument("--cache", default=None)
    p.add_argument("--quiet", action="store_true")
    args = p.parse_args(argv)
    suite = get_suite(args.suite)
    everyone = people_of(args.data)
    counts = list(parse_ints(args.people))
    if any(n > len(everyone) or n < 1 for n in counts):
        print(f"{p.prog}: error: --people {args.people}: the dataset has {len(everyone)} people; accepted: 1 to "
              f"{len(everyone)}", file=sys.stderr)
        return 2
    if args.workers < 1:
        print(f"{p.prog}: error: --workers {args.workers}: accepted: 1 or more", file=sys.stderr)
        return 2
    if args.grip is not None and args.calibration:
        print(f"{p.prog}: error: --grip {args.grip} and --calibration: accepted: one of them", file=sys.stderr)
        return 2
    grip = args.grip
    if grip is None and not args.calibration:
        grip = str(importlib.resources.files("sim_assets").joinpath(SHIPPED))
    out = pathlib.Path(args.out)
    try:
        check_out(out)
        check_cache_args(argparse.Namespace(cache=args.cache, out=out))
    except OutputFolderError as e:
        print(f"{p.prog}: error: {e}", file=sys.stderr)
        return 2
    try:
        with staged_folder(out) as tmp:
            (tmp / "models").mkdir(parents=True)
            if args.calibration:
                grip = tmp / "models" / "grip_calibration.json"
                fit_calibration(args.calibration, grip, everyone[:max(counts)], quiet=args.quiet)
            meta = train_models(args.data, everyone, counts, grip, tmp / "models", workers=args.workers)
            specs = [MethodSpec(internal_model=str(tmp / "models" / model_file(n, pr)), protocol=pr)
                     for n in counts for pr in PROTOCOLS]
            docs = evaluate_many(suite, specs + [MethodSpec(method="no-internal")], cache=args.cache,
                                 progress=not args.quiet, workers=args.workers)
            rows = []
            for i, n in enumerate(counts):
                first = meta[n][PROTOCOLS[0]]  # both models train on the same samples
                rows.append({"people": n, "users": everyone[:n], "episodes": first["episodes"], "samples": first["samples"],
                             "aggregate": {pr: docs[i * len(PROTOCOLS) + j]["aggregate"] for j, pr in enumerate(PROTOCOLS)}})
            doc = {"suite": {"name": suite.name, "version": suite.version, "n": len(suite.scenarios)}, "rows": rows,
                   "no_internal": docs[-1]["aggregate"], "provenance": provenance()}
            write_text(tmp / "learning_curve.json", json.dumps(strict(doc), indent=1, allow_nan=False) + "\n")
            table = curve_markdown(suite, rows)
            write_text(tmp / "learning_curve.md", table)
    except DatasetError as e:  # a recording without a training person: before any training
        print(f"{p.prog}: error: {e}", file=sys.stderr)
        return 2
    print(table)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
