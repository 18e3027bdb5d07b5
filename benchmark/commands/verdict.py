"""The verdict of ``fsv-bench``: the scenario as a suite of one, scored and gated like ``fsv-bench eval``.

The episode's metrics (:func:`benchmark.scores.episode.score_episode` on the method's estimate) are
checked against the smoke suite's gates (CI's gates for the reference method), or ``--gates FILE``.
``summary.json`` gets a ``verdict`` block (metrics, gates, pass/fail); the command exits 1 when a gate
fails, after writing every file.
"""

from __future__ import annotations

import argparse


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--gates", default=None,
                   help="JSON file of gates for the verdict (default: the smoke suite's; see fsv-bench eval)")


def run_stage(run) -> None:
    from dataclasses import asdict

    from benchmark.suites.evaluate import load_gates
    from benchmark.scores.aggregate import aggregate_all
    from benchmark.scores.episode import METRICS, score_episode
    from benchmark.scores.verdict import check_gates
    from benchmark.suites import get_suite

    gates = load_gates(run.args.gates) if run.args.gates else get_suite("smoke").gates
    metrics = score_episode(run.episode, run.estimate)
    results = check_gates(gates, aggregate_all([metrics], METRICS))
    failed = [r.name for r in results if not r.passed]
    run.summary["verdict"] = {
        "verdict": "fail" if failed else "pass",
        "gates_from": run.args.gates or "smoke suite",
        "method": run.estimate.labels,
        "metrics": metrics,
        "gates": [{k: v for k, v in asdict(r).items() if k != "ci"} for r in results],
    }
    run.lines.append(f"verdict: {'FAIL' if failed else 'pass'} ({len(results) - len(failed)} of {len(results)} gates "
                     f"of the {run.args.gates or 'smoke suite'} hold" + (f"; failed: {'; '.join(failed)})" if failed else ")"))
