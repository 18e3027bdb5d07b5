"""``fsv-bench compare DIR_A DIR_B``: paired differences of two evaluations on the same episodes.

    fsv-bench compare DIR_A DIR_B [--out FILE.json]

Both folders hold a ``scores.json`` written by ``fsv-bench eval`` on the same suite and version.
For every metric, the per-episode differences B - A over the episodes both hold give a mean
difference with its 95 % bootstrap interval (labelled "few episodes" below
:data:`benchmark.scores.aggregate.FEW_EPISODES`) and Wilcoxon's signed-rank test. A method is
called better on a metric only when the test's two-sided p is below 0.05 (lower is better for
errors, higher for recall and precision); with fewer than
:data:`benchmark.scores.aggregate.MIN_PAIRED_EPISODES` differing pairs no p below 0.05 is possible,
and the verdict is "too few episodes". Every episode counts: a metric missing on one side counts at
its worst value (:data:`benchmark.scores.episode.WORST`; two worst values tie), as in ``scores.json``'s
aggregates.
"""

from __future__ import annotations

import argparse
import json
import pathlib

from benchmark.atomic import OUT_AS_IT_WAS, check_file_out, write_text
from benchmark.scores.aggregate import FEW_EPISODES, aggregate, paired_test
from benchmark.scores.metrics import WORST
from benchmark.scores.units import labelled
from benchmark.suites.evaluate import strict

INTERRUPTED = OUT_AS_IT_WAS
"""What Ctrl-C leaves, as the interrupted command says it (`fsv-bench <sub-command>: interrupted; ...`)."""

ALPHA = 0.05
"""The paired test's level: a method is better where p < ALPHA."""

HIGHER_IS_BETTER = ("contact_recall", "contact_precision")


def load_scores(folder) -> dict:
    """``scores.json`` of an evaluation folder; ValueError naming the folder if it has none."""
    path = pathlib.Path(folder) / "scores.json"
    try:
        return json.loads(path.read_text())
    except (OSError, ValueError) as e:
        raise ValueError(f"{folder}: no readable scores.json from `fsv-bench eval` ({e})") from e


def compare(a: dict, b: dict) -> dict:
    """Paired differences B - A per metric over the episodes both evaluations scored.

    Raises:
        ValueError: If the two were made on different suites or suite versions, or share no episode.
    """
    sa, sb = a["suite"], b["suite"]
    if (sa["name"], sa["version"]) != (sb["name"], sb["version"]):
        raise ValueError(f"cannot pair {sa['name']} v{sa['version']} with {sb['name']} v{sb['version']}: "
                         "compare evaluations of the same suite and version")
    ea = {e["episode"]: e for e in a["episodes"]}
    eb = {e["episode"]: e for e in b["episodes"]}
    common = [k for k in ea if k in eb]
    if not common:
        raise ValueError("the two evaluations share no episode")
    out = {}
    for m in (m for m in a["metrics"] if m in b["metrics"]):  # an older scores.json may lack the newer metrics
        d = [paired_difference(ea[k][m], eb[k][m], WORST.get(m)) for k in common]
        agg = aggregate(d, "mean")
        test = paired_test(d)
        if agg["value"] is None:
            better = "nothing scored"
        elif test["n"] == 0:
            better = "neither"  # the same value on every episode
        elif test["p"] is None:
            better = "too few episodes"
        elif test["p"] >= ALPHA:
            better = "neither"
        else:
            lower = test["median_diff"] < 0
            better = ("A" if lower else "B") if m in HIGHER_IS_BETTER else ("B" if lower else "A")
        out[m] = {"mean_diff": agg["value"], "ci_low": agg["ci_low"], "ci_high": agg["ci_high"], "n": agg["n"],
                  "interval": "few episodes" if agg["n"] < FEW_EPISODES else "bootstrap",
                  "median_diff": test["median_diff"], "pairs": test["n"], "p": test["p"], "better": better}
    return {"suite": sa, "a": a.get("method"), "b": b.get("method"), "episodes": common, "metrics": out}


def paired_difference(a, b, worst):
    """B - A on one episode, a missing value (None: NaN or infinite in ``scores.json``) at the metric's
    ``worst``: two worst values tie (0), one gives an infinite difference; None where a value is
    missing and the metric has no worst value (then no mean is defined)."""
    a, b = (worst if v is None else v for v in (a, b))
    if a is None or b is None:
        return None
    return 0.0 if a == b else b - a


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("a", help="evaluation folder A (scores.json)")
    p.add_argument("b", help="evaluation folder B (scores.json)")
    p.add_argument("--out", default=None, help="also write the comparison as JSON here; an existing file needs --force")
    p.add_argument("--force", action="store_true", help="replace --out if it exists (without it an existing file is refused)")


def run(args: argparse.Namespace) -> dict:
    if args.out:
        check_file_out(args.out, force=args.force)
    result = compare(load_scores(args.a), load_scores(args.b))
    n = len(result["episodes"])
    print(f"{result['suite']['name']} v{result['suite']['version']}: B - A over n = {n} episodes (A = {args.a}, "
          f"B = {args.b}); better: Wilcoxon signed-rank p < {ALPHA:g}" + (
              f"; 95 % intervals over {n} episodes are little more than their range" if n < FEW_EPISODES else ""))
    print(f"{'metric':28s} {'mean B-A':>10s} {'95 % CI':>24s} {'pairs':>5s} {'p':>8s}  better")
    for m, r in result["metrics"].items():
        if r["mean_diff"] is None:
            print(f"{labelled(m):28s} {'-':>10s}")
            continue
        p = "-" if r["p"] is None else f"{r['p']:.3g}"
        print(f"{labelled(m):28s} {r['mean_diff']:10.4g} [{r['ci_low']:10.4g}, {r['ci_high']:10.4g}] {r['pairs']:5d} "
              f"{p:>8s}  {r['better']}")
    if args.out:
        write_text(args.out, json.dumps(strict(result), indent=1, allow_nan=False) + "\n")
    return result


