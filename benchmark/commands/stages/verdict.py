"""The verdict stage: the scenario as a suite of one, scored and gated like ``fsv-bench eval``.

The episode's metrics (:func:`benchmark.scores.episode.score_episode` on the method's estimate, its
learned forces' errors taken from the learn stage's scores) are checked against the smoke suite's gates (CI's gates for the reference method), or ``--gates FILE``.
``summary.json`` gets a ``verdict`` block (metrics, gates, pass/fail); the command exits 1 when a gate
fails, after writing every file.
"""

from __future__ import annotations

from benchmark.commands.stage import Run, Stage, StageResult
from benchmark.scores.aggregate import aggregate_all
from benchmark.scores.episode import score_episode
from benchmark.scores.metrics import METRICS
from benchmark.scores.units import UNITS
from benchmark.scores.verdict import Gate, GateResult, check_gates, gate_rows
from benchmark.suites import get_suite
from benchmark.suites.evaluate import load_gates


def add_arguments(parser) -> None:
    parser.add_argument("--gates", default=None,
                        help="JSON file of gates for the verdict (default: the smoke suite's; see fsv-bench eval)")


def run(record: Run, options) -> StageResult:
    """The episode's metrics against the gates; the ``verdict`` block and line."""
    gates_file = options["gates"]
    gates = load_gates(gates_file) if gates_file else get_suite("smoke").gates
    metrics = score_episode(record.episode, record.estimate,
                            record.knowledge.world_from_method if record.knowledge else None, learned=record.learned)
    results = check_gates(gates, aggregate_all([metrics], METRICS))
    failed = [r.name for r in results if not r.passed]
    block = {
        "verdict": "fail" if failed else "pass",
        "gates_from": gates_file or "smoke suite",
        "method": record.estimate.labels,
        "metrics": metrics,
        "gates": gate_rows(results),
    }
    line = (f"verdict: {'FAIL' if failed else 'pass'} ({len(results) - len(failed)} of {len(results)} gates "
            f"of the {gates_file or 'smoke suite'} hold" + (f"; failed: {'; '.join(failed)})" if failed else ")"))
    return StageResult(blocks=(("verdict", block),), lines=(line, *(gate_line(g, r) for g, r in zip(gates, results))))


ON_A_SUITE = {"median": "", "mean": ", a suite's mean", "p90": ", a suite's 90th percentile"}
"""What a gate's limit bounds over a suite's episodes, as the verdict's line says it (of one episode,
every statistic is the episode's own value: two gates on one metric differ only in this)."""


def gate_line(gate: Gate, result: GateResult) -> str:
    """One gate of the verdict as the command prints it: the episode's value beside the limit, in the
    metric's unit, e.g. ``  pass  acc_err_rms 0.367 m/s² (limit <= 0.5 m/s²)`` or ``  pass
    net_force_err_n_rms 0.0591 N (limit <= 0.5 N, a suite's 90th percentile)``."""
    unit = UNITS.get(gate.metric, "")
    value = "not scored" if result.value is None else f"{result.value:.3g}{' ' + unit if unit else ''}"
    limit = f"{gate.limit:g}{' ' + unit if unit else ''}{ON_A_SUITE[gate.statistic]}"
    return f"  {'pass' if result.passed else 'FAIL'}  {gate.metric} {value} (limit {gate.op} {limit})"


STAGE = Stage(name="verdict", run=run, options=("gates",), add_arguments=add_arguments)
