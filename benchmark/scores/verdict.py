"""The one gate system: gates on aggregates of episodes' metrics (a suite's, or one episode's),
the verdict as a report and as JUnit XML for CI systems."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass

from benchmark.scores.aggregate import FEW_EPISODES, STATISTICS, aggregate_all
from benchmark.scores.leaderboard import skill_table
from benchmark.scores.units import labelled


@dataclass(frozen=True)
class Gate:
    """A pass/fail rule on an aggregate of per-episode metrics (over a suite, or of one episode).

    Attributes:
        metric: Per-episode metric name (see :mod:`benchmark.scores.episode`).
        op: ``"<="`` or ``">="``.
        limit: The threshold, in the metric's unit.
        statistic: ``"median"``, ``"mean"`` or ``"p90"`` (the 90th percentile: the tail) over the
            suite's episodes (:data:`benchmark.scores.aggregate.STATISTICS`).
        measured: What the reference method measured when the gate was set (documentation).
    """

    metric: str
    op: str
    limit: float
    statistic: str = "median"
    measured: str = ""

    def __post_init__(self):
        if self.op not in ("<=", ">="):
            raise ValueError(f"Gate.op must be '<=' or '>=', got {self.op!r}")
        if self.statistic not in STATISTICS:
            raise ValueError(f"Gate.statistic must be one of {', '.join(map(repr, STATISTICS))}, got {self.statistic!r}")

    @property
    def name(self) -> str:
        return f"{self.statistic} {self.metric} {self.op} {self.limit:g}"

    def holds(self, value: float) -> bool:
        """Whether an aggregate value passes (NaN never does)."""
        if value != value:
            return False
        return value <= self.limit if self.op == "<=" else value >= self.limit


@dataclass(frozen=True)
class GateResult:
    """A gate and the aggregate it was checked on.

    Attributes:
        name: ``"<statistic> <metric> <op> <limit>"``.
        value: The aggregate (None when nothing was scored: the gate fails).
        ci: The aggregate's 95 % interval, ``(low, high)`` or None.
        passed: Whether the gate holds.
        n: The episodes the aggregate is over (below ``FEW_EPISODES`` its interval is labelled
            "few episodes").
    """

    name: str
    value: float | None
    ci: tuple | None
    passed: bool
    n: int = 0


def check_gates(gates, aggregates: dict) -> list[GateResult]:
    """Checks every gate on ``aggregates`` (``{metric: {statistic: {"value", "ci_low", "ci_high"}}}``).

    Raises:
        ValueError: If a gate names a metric that was not scored.
    """
    out = []
    for g in gates:
        if g.metric not in aggregates:
            raise ValueError(f"gate {g.name!r} names the unknown metric {g.metric!r}; accepted: {', '.join(aggregates)}")
        a = aggregates[g.metric][g.statistic]
        value = a["value"]
        out.append(GateResult(name=g.name, value=value, ci=None if value is None else (a["ci_low"], a["ci_high"]),
                              passed=value is not None and g.holds(value), n=int(a.get("n", 0))))
    return out


def junit_xml(suite_name: str, results: list[GateResult], elapsed_s: float) -> bytes:
    """One JUnit test case per gate (a failure names the value and its interval)."""
    failures = sum(not r.passed for r in results)
    root = ET.Element("testsuites")
    ts = ET.SubElement(root, "testsuite", name=f"fsv-bench.{suite_name}", tests=str(len(results)),
                       failures=str(failures), errors="0", time=f"{elapsed_s:.3f}")
    for r in results:
        case = ET.SubElement(ts, "testcase", classname=f"fsv-bench.{suite_name}", name=r.name, time="0")
        if not r.passed:
            f = ET.SubElement(case, "failure", message=f"{r.name}: measured {_fmt(r.value)} {_fmt_ci(r.ci, r.n)}")
            f.text = f"{r.name} does not hold: measured {_fmt(r.value)} {_fmt_ci(r.ci, r.n)}"
    return ET.tostring(root, encoding="utf-8", xml_declaration=True)


def _fmt(v) -> str:
    return "nothing scored" if v is None else f"{v:.4g}"


def _interval(ci) -> str:
    return "" if ci is None else f"[{ci[0]:.4g}, {ci[1]:.4g}]"


def _fmt_ci(ci, n: int | None = None) -> str:
    if ci is None:
        return ""
    if n is None:
        return f"(95 % CI {_interval(ci)})"
    return f"(95 % CI {_interval(ci)}, n = {n} episodes{', few episodes' if n < FEW_EPISODES else ''})"


def report_markdown(suite, method: str, rows: list[dict], aggregates: dict, per_task: dict, results: list,
                    metrics, baselines: dict | None = None) -> str:
    """``report.md``: the verdict, the gates, the skill against the baselines (with ``baselines``, the
    ``baselines`` entry of ``scores.json``), the aggregates with intervals, per task and per episode."""
    ok = all(r.passed for r in results)
    lines = [f"# {suite.name} (version {suite.version}): {method}", "",
             f"**Verdict: {'every gate holds' if ok else 'FAILED: ' + ', '.join(r.name for r in results if not r.passed)}**",
             "", suite.description, "", f"n = {len(rows)} episodes" + (
                 ": with so few, each 95 % interval is little more than the range of the values (few episodes)"
                 if len(rows) < FEW_EPISODES else ""),
             "", "## Gates", "", "| gate | measured | 95 % CI | n | |", "|---|---|---|---|---|"]
    for r in results:
        lines.append(f"| {r.name} | {_fmt(r.value)} | {_interval(r.ci)} | {r.n} | "
                     f"{'pass' if r.passed else '**FAIL**'} |")
    if baselines:
        entries = [("this method", {"aggregate": aggregates})]
        entries += [(f"baseline-{name}", {"aggregate": b["aggregate"]}) for name, b in baselines.items()]
        table = skill_table(entries, {name: b["stage"] for name, b in baselines.items()})
        lines += ["", "## Skill against the trivial baselines", "",
                  "The baselines (`fsv.method.baselines`) ran on the same episodes."] + table
    lines += ["", f"## Aggregates over {len(rows)} episodes (median [95 % CI], mean, 90th percentile: the tail)", "",
              "| metric | median | 95 % CI | mean | 90th percentile |", "|---|---|---|---|---|"]
    for m in metrics:
        med, mean = aggregates[m]["median"], aggregates[m]["mean"]
        ci = (med["ci_low"], med["ci_high"]) if med["value"] is not None else None
        tail = aggregates[m].get("p90", {}).get("value")
        lines.append(f"| {labelled(m)} | {_fmt(med['value'])} | {_interval(ci)} | {_fmt(mean['value'])} | {_fmt(tail)} |")
    lines += ["", "## Per task (median)", "", "| task | " + " | ".join(labelled(m) for m in metrics) + " |",
              "|---|" + "---|" * len(metrics)]
    for task, agg in per_task.items():
        lines.append(f"| {task} | " + " | ".join(_fmt(agg[m]["median"]["value"]) for m in metrics) + " |")
    lines += ["", "## Per episode", "", "| episode | " + " | ".join(labelled(m) for m in metrics) + " |",
              "|---|" + "---|" * len(metrics)]
    for r in rows:
        lines.append(f"| {r['episode']} | " + " | ".join(_fmt(r[m] if r[m] == r[m] else None) for m in metrics) + " |")
    return "\n".join(lines) + "\n"


def check_values(gates, values: dict) -> list[GateResult]:
    """Checks gates on one episode's values (``{metric: value}``): its median and mean are the value."""
    return check_gates(gates, aggregate_all([values], sorted({g.metric for g in gates})))


def gate_rows(results: list[GateResult]) -> list[dict]:
    """The results as JSON rows ``{"name", "value", "passed"}`` (no interval: one episode has none)."""
    return [{"name": r.name, "value": r.value, "passed": r.passed} for r in results]
