"""Does the learned method gain from more people? ``python -m benchmark.commands.direct_curve``.

    python -m benchmark.commands.direct_curve --data DIR [--data DIR ...] --people 40,80,160 --suite dev
        --out DIR [--window W] [--hidden 128,128] [--workers N] [--cache DIR] [--quiet]

Trains the end-to-end force network (``--method direct``, :class:`fsv.method.DirectForces`) as the
shipped one is trained (``fsv-bench train-direct``'s defaults, :class:`fsv.learn.DirectConfig`, or
the ``--window`` and ``--hidden`` given: one curve per choice, to choose on ``dev``) on
the first N people of the training datasets (``fsv-bench generate --split train --design people
--rows all``; the people of several ``--data`` folders are taken in their order, folder after
folder) for each N of ``--people``, then scores each model on the suite (``dev``: people never
trained on, never scored by ``standard``) beside the reference method, every episode rendered and
tracked once. Writes ``direct_curve.json`` (per N: people, episodes, samples, the training's
epochs and seconds, every aggregate) and ``direct_curve.md``; the models go to ``DIR/models/``
(``direct-people-N.npz``).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import pathlib
import sys

from benchmark.atomic import OutputFolderError, check_out, staged_folder, write_text
from benchmark.commands.learning_curve import people_of
from benchmark.commands.parser import OneLineParser
from benchmark.errors import DatasetError
from benchmark.limits import integer
from benchmark.method import MethodSpec
from benchmark.paper import direct_training
from benchmark.paper.dataset.cli import parse_ints
from benchmark.paper.direct_training import check_all_rows, hidden_sizes
from benchmark.parallel import run_jobs
from benchmark.suites import get_suite
from benchmark.suites.evaluate import check_cache_args, evaluate_many, strict
from fsv.errors import InputError
from fsv.learn import DirectConfig
from fsv.learn.direct_inputs import MAX_WINDOW
from fsv.provenance import provenance

COLUMNS = (("force_mae_n", "mean", "per-contact MAE [N]"), ("force_rmse_n", "mean", "per-contact RMSE [N]"),
           ("force_normal_mae_n", "mean", "normal MAE [N]"), ("force_tangential_mae_n", "mean", "tangential MAE [N]"),
           ("peak_force_err_n", "mean", "peak-force MAE [N]"), ("net_force_err_n_rms", "median", "net force [N]"),
           ("net_force_err_n_rms", "p90", "net force, p90 [N]"), ("learned_rel_err_pct", "median", "learned [%]"))
"""The curve's cells: (metric, suite statistic, heading); the peers' per-contact and peak-force errors
first (the learned method's own targets), then the net force and the paper's learned error."""


def model_file(n: int) -> str:
    """The name of the N-people model in ``DIR/models/``."""
    return f"direct-people-{n}.npz"


def people_of_all(datasets: list) -> list:
    """The people of ``datasets`` in order, folder after folder.

    Raises:
        DatasetError: If a person is in two of them (naming the person and the folders).
    """
    everyone, where = [], {}
    for d in datasets:
        for u in people_of(d):
            if u in where:
                raise DatasetError(f"--data {d}: person {u} is in --data {where[u]} too; accepted: datasets of "
                                   "other people")
            where[u] = d
            everyone.append(u)
    return everyone


def train_models(datasets: list, everyone: list, counts: list, folder: pathlib.Path, workers: int = 1,
                 config: dict | None = None) -> dict:
    """Trains the N-people model for every N of ``counts`` into ``folder`` (:func:`model_file`), the
    largest first, on ``workers`` local processes (training is single-threaded; a model is the same
    whichever process trains it), with ``config`` (keyword arguments of :class:`fsv.learn.DirectConfig`;
    default: its defaults). Each model reads the datasets that hold some of its first N people (a
    later folder of other people is not opened; :func:`people_of_all`). Returns ``{n: training summary}``."""
    order = sorted(counts, reverse=True)
    holds = {str(d): set(people_of(d)) for d in datasets}
    jobs = []
    for n in order:
        chosen = everyone[:n]
        reads = [d for d, people in holds.items() if people.intersection(chosen)]
        jobs.append((reads, chosen, str(folder / model_file(n)), dict(config or {})))
    meta = {}
    for i, summary in run_jobs(direct_training.train_job, jobs, workers=workers):
        meta[order[i]] = summary
    return {n: meta[n] for n in counts}


def curve_markdown(suite, rows: list, reference: dict, config: DirectConfig = DirectConfig()) -> str:
    """The table of the curve: per number of people, each cell's statistic [95 % interval]; the
    reference method's row below for comparison; ``config``, the network's, named above."""
    lines = ["# Learning curve of the learned method (`--method direct`) against the number of training people",
             "", f"Scored on `{suite.name}` v{suite.version} ({len(suite.scenarios)} episodes, people never "
             "trained on), blind protocol; the network: hidden "
             f"{','.join(map(str, config.hidden))}, window {config.window}, at most {config.epochs} epochs. Each "
             "cell the suite statistic named in its heading over the episodes [95 % bootstrap interval]. The reference method (model-based, its shipped internal-force model) "
             "on the same episodes below.", "",
             "| training people | episodes | samples | " + " | ".join(f"{h} ({s})" for _, s, h in COLUMNS) + " |",
             "|---|---|---|" + "---|" * len(COLUMNS)]
    for r in rows:
        lines.append(f"| {r['people']} | {r['episodes']} | {r['samples']} | {_cells(r['aggregate'])} |")
    lines.append(f"| reference | | | {_cells(reference)} |")
    return "\n".join(lines) + "\n"


def _cells(aggregate: dict) -> str:
    cells = []
    for metric, statistic, _ in COLUMNS:
        agg = aggregate[metric][statistic]
        cells.append("-" if agg["value"] is None else f"{agg['value']:.3g} [{agg['ci_low']:.3g}, {agg['ci_high']:.3g}]")
    return " | ".join(cells)


def main(argv=None) -> int:
    p = OneLineParser(prog="python -m benchmark.commands.direct_curve", description=__doc__.split("\n\n")[0])
    p.add_argument("--data", action="append", required=True,
                   help="a training dataset of every frame (fsv-bench generate --split train --design people --rows "
                        "all); repeat for several, their people taken folder after folder")
    p.add_argument("--people", default="40,80,160", help="numbers of training people (default 40,80,160)")
    p.add_argument("--suite", default="dev", help="suite to score on (default dev)")
    p.add_argument("--window", type=integer(0, MAX_WINDOW), default=DirectConfig.window,
                   help=f"frames of kinematics on either side among the inputs, 0 to {MAX_WINDOW} (default "
                        f"{DirectConfig.window})")
    p.add_argument("--hidden", type=hidden_sizes, default=DirectConfig.hidden,
                   help=f"hidden layer sizes (default {','.join(map(str, DirectConfig.hidden))})")
    p.add_argument("--out", required=True, help="output folder")
    p.add_argument("--workers", type=int, default=1, help="local processes for training and scoring (default 1)")
    p.add_argument("--cache", default=None)
    p.add_argument("--quiet", action="store_true")
    args = p.parse_args(argv)
    out = pathlib.Path(args.out)
    try:
        suite = get_suite(args.suite)
        if args.workers < 1:
            raise InputError(f"--workers {args.workers}: accepted: 1 or more")
        for d in args.data:
            check_all_rows(d)
        everyone = people_of_all(args.data)
        counts = list(parse_ints(args.people, "--people"))
        if not counts or any(n > len(everyone) or n < 1 for n in counts):
            raise InputError(f"--people {args.people}: the datasets have {len(everyone)} people; accepted: 1 to "
                             f"{len(everyone)}")
        check_out(out)
        check_cache_args(argparse.Namespace(cache=args.cache, out=out))
    except (InputError, DatasetError, OutputFolderError, ValueError) as e:
        print(f"{p.prog}: error: {e}", file=sys.stderr)
        return 2
    with staged_folder(out) as tmp:
        (tmp / "models").mkdir(parents=True)
        config = {"window": args.window, "hidden": tuple(args.hidden)}
        meta = train_models(args.data, everyone, counts, tmp / "models", workers=args.workers, config=config)
        specs = [MethodSpec(method="direct", direct_model=str(tmp / "models" / model_file(n))) for n in counts]
        docs = evaluate_many(suite, specs + [MethodSpec()], cache=args.cache, progress=not args.quiet,
                             workers=args.workers)
        rows = [{"people": n, "users": everyone[:n], **meta[n], "aggregate": docs[i]["aggregate"]}
                for i, n in enumerate(counts)]
        doc = {"suite": {"name": suite.name, "version": suite.version, "n": len(suite.scenarios)},
               "config": dataclasses.asdict(DirectConfig(**config)), "rows": rows,
               "reference": docs[-1]["aggregate"], "provenance": provenance()}
        write_text(tmp / "direct_curve.json", json.dumps(strict(doc), indent=1, allow_nan=False) + "\n")
        table = curve_markdown(suite, rows, docs[-1]["aggregate"], DirectConfig(**config))
        write_text(tmp / "direct_curve.md", table)
    print(table)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
