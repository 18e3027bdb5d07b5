"""``fsv-bench compare DIR_A DIR_B``: paired differences of two evaluations on the same episodes.

    fsv-bench compare DIR_A DIR_B [--out FILE.json]

Both folders hold a ``scores.json`` written by ``fsv-bench eval`` on the same suite and version.
For every metric, the per-episode differences B - A over the episodes both scored give a mean
difference with its 95 % bootstrap interval; a method is called better on a metric only when the
interval excludes zero (lower is better for errors, higher for recall and precision).
"""

from __future__ import annotations

import argparse
import json
import pathlib

from benchmark.scores.aggregate import aggregate

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
    for m in a["metrics"]:
        d = [eb[k][m] - ea[k][m] for k in common if ea[k][m] is not None and eb[k][m] is not None]
        agg = aggregate(d, "mean")
        better = "neither"
        if agg["value"] is not None and agg["n"] >= 2:
            lo, hi = agg["ci_low"], agg["ci_high"]
            b_better = (lo > 0) if m in HIGHER_IS_BETTER else (hi < 0)
            a_better = (hi < 0) if m in HIGHER_IS_BETTER else (lo > 0)
            better = "B" if b_better else "A" if a_better else "neither"
        out[m] = {"mean_diff": agg["value"], "ci_low": agg["ci_low"], "ci_high": agg["ci_high"], "n": agg["n"],
                  "better": better}
    return {"suite": sa, "a": a.get("method"), "b": b.get("method"), "episodes": common, "metrics": out}


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("a", help="evaluation folder A (scores.json)")
    p.add_argument("b", help="evaluation folder B (scores.json)")
    p.add_argument("--out", default=None, help="also write the comparison as JSON here")


def run(args: argparse.Namespace) -> dict:
    result = compare(load_scores(args.a), load_scores(args.b))
    print(f"{result['suite']['name']} v{result['suite']['version']}: B - A over {len(result['episodes'])} episodes "
          f"(A = {args.a}, B = {args.b}); better = interval excludes zero")
    print(f"{'metric':24s} {'mean B-A':>12s} {'95 % CI':>26s}  better")
    for m, r in result["metrics"].items():
        if r["mean_diff"] is None:
            print(f"{m:24s} {'-':>12s}")
            continue
        print(f"{m:24s} {r['mean_diff']:12.4g} [{r['ci_low']:11.4g}, {r['ci_high']:11.4g}]  {r['better']}")
    if args.out:
        from benchmark.atomic import write_text

        write_text(args.out, json.dumps(result, indent=1, allow_nan=False) + "\n")
    return result


