"""A suite: a named, versioned set of scenarios with its protocol and default gates."""

from __future__ import annotations

from dataclasses import dataclass, field

from benchmark.scores.verdict import Gate  # noqa: F401 (a suite's gates; the one gate system is the scores')
from benchmark.world.scenario import Scenario


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
