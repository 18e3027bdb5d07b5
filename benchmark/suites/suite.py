"""A suite: a named, versioned set of scenarios with its protocol and default gates."""

from __future__ import annotations

from dataclasses import dataclass, field

from benchmark.world.scenario import Scenario


@dataclass(frozen=True)
class Gate:
    """A pass/fail rule on an aggregate of a suite.

    Attributes:
        metric: Per-episode metric name (see :mod:`benchmark.scores.episode`).
        op: ``"<="`` or ``">="``.
        limit: The threshold, in the metric's unit.
        statistic: ``"median"`` or ``"mean"`` over the suite's episodes.
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
        if self.statistic not in ("median", "mean"):
            raise ValueError(f"Gate.statistic must be 'median' or 'mean', got {self.statistic!r}")

    @property
    def name(self) -> str:
        return f"{self.statistic} {self.metric} {self.op} {self.limit:g}"

    def holds(self, value: float) -> bool:
        """Whether an aggregate value passes (NaN never does)."""
        if value != value:
            return False
        return value <= self.limit if self.op == "<=" else value >= self.limit


@dataclass(frozen=True)
class Suite:
    """A named, versioned set of scenarios.

    Attributes:
        name: Registry name.
        version: Bumped whenever a scenario, the protocol or a gate changes (cached episodes and
            scores carry it).
        scenarios: The episodes, in order.
        gates: Default gates on the aggregates.
        description: How the scenarios were drawn and what the suite is for.
    """

    name: str
    version: int
    scenarios: tuple[Scenario, ...]
    gates: tuple[Gate, ...] = field(default_factory=tuple)
    description: str = ""

    def __post_init__(self):
        if not self.scenarios:
            raise ValueError(f"suite {self.name!r} has no scenarios")
        if len(set(self.scenarios)) != len(self.scenarios):
            raise ValueError(f"suite {self.name!r} lists a scenario twice")
