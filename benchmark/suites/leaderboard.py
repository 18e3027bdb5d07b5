"""``fsv-bench leaderboard``: the reference method and its variants on one suite, in one pass.

    fsv-bench leaderboard --suite standard --out DIR [--workers N] [--cache DIR] [--quiet]

The variants (:data:`VARIANTS`) replace one stage of the reference (another differentiator, or a
stage's trivial baseline), feed it truth (oracle contacts, oracle kinematics: ablations that show
what each stage costs) or tell it the simulation's own hand, box and camera (``exact-knowledge``,
an ablation beside the default ``lab`` knowledge, :mod:`benchmark.method.knowledge`); the
reference is also run under the ``calibrated`` protocol beside the ``blind`` one
(:mod:`benchmark.method.protocol`). They share every episode's rendering and tracking. The table gives each
method's skill against the best baseline per metric. ``DIR/<variant>/`` gets the files of ``fsv-bench eval``
(``scores.json``, ``report.md``, ``junit.xml``); ``DIR/leaderboard.md`` the table with intervals.
The exit status is 0 when the reference passes the suite's gates, 1 when not.
"""

from __future__ import annotations

import argparse
import pathlib

from benchmark.atomic import OUT_AS_IT_WAS_EPISODES_CACHED, check_out, staged_folder
from benchmark.method import MethodSpec
from benchmark.method.knowledge import DEFAULT_KNOWLEDGE, KNOWLEDGE
from benchmark.scores.leaderboard import leaderboard_markdown
from benchmark.suites.evaluate import GateFailure, baselines_block, check_cache_args, evaluate_many, write_outputs
from benchmark.suites.options import add_suite_arguments, suite_of
from fsv.method.baselines import BASELINE_STAGE, BASELINES

INTERRUPTED = OUT_AS_IT_WAS_EPISODES_CACHED
"""What Ctrl-C leaves, as the interrupted command says it (`fsv-bench <sub-command>: interrupted; ...`)."""

BASELINE_NAMES = tuple(BASELINES)
OTHER_KNOWLEDGE = next(k for k in KNOWLEDGE if k != DEFAULT_KNOWLEDGE)

VARIANTS = {
    "reference": MethodSpec(),
    "calibrated": MethodSpec(protocol="calibrated"),
    "central": MethodSpec(differentiator="central"),
    "gaussian": MethodSpec(differentiator="gaussian"),
    "oracle-contacts": MethodSpec(oracle=("contacts",)),
    "oracle-kinematics": MethodSpec(oracle=("kinematics",)),
    "oracle-contacts-kinematics": MethodSpec(oracle=("contacts", "kinematics")),
    f"{OTHER_KNOWLEDGE}-knowledge": MethodSpec(knowledge=OTHER_KNOWLEDGE),
    "direct": MethodSpec(method="direct"),
    "direct-oracle-contacts-kinematics": MethodSpec(method="direct", oracle=("contacts", "kinematics")),
    **{f"baseline-{name}": MethodSpec(method=name, protocol="calibrated" if name == "grip-line" else "blind")
       for name in BASELINE_NAMES},
}
"""The leaderboard's rows: the reference (algebraic differentiation, lab knowledge, the ``blind`` protocol), the
same under the ``calibrated`` protocol (:mod:`benchmark.method.protocol`), its variants, the
end-to-end network of the learned family (``direct``, :class:`fsv.method.DirectForces`; blind: it is told
nothing of the person) on the reference's tracking and on the truth's contacts and kinematics, and the
trivial baseline of each stage (``fsv.method.baselines``) every method must beat (the grip line is
a calibration, so it is run calibrated)."""


def add_arguments(p: argparse.ArgumentParser) -> None:
    add_suite_arguments(p, out_help="output folder (leaderboard.md, <variant>/)")


def run(args: argparse.Namespace) -> list:
    suite = suite_of(args)
    if args.workers < 1:
        raise ValueError(f"--workers {args.workers}: need at least 1 worker process")
    check_out(args.out)
    check_cache_args(args)
    results = evaluate_many(suite, list(VARIANTS.values()), cache=args.cache, progress=not args.quiet,
                            workers=args.workers)
    entries = list(zip(VARIANTS, results))
    names = [n for n in VARIANTS if n.startswith("baseline-")]
    block = baselines_block([n[9:] for n in names], [dict(entries)[n] for n in names])
    for name, scores in entries:
        if not name.startswith("baseline-"):
            scores["baselines"] = block
    out = pathlib.Path(args.out)
    with staged_folder(out) as tmp:
        for name, scores in entries:
            write_outputs(scores, suite, tmp / name)
        table = leaderboard_markdown(suite, entries, BASELINE_STAGE)
        (tmp / "leaderboard.md").write_text(table)
    print(table)
    print(f"written to {out}/ (leaderboard.md, {', '.join(VARIANTS)})")
    if results[0]["verdict"] != "pass":
        failed = [g["name"] for g in results[0]["gates"] if not g["passed"]]
        raise GateFailure(f"the reference fails {len(failed)} gate(s) of {suite.name}: {'; '.join(failed)}")
    return entries
