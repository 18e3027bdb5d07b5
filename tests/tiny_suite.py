"""The ``tiny`` suite of the tests: one 1.5 s lift (its episode is made once per test process by the
``tiny_cache`` fixture, tests/conftest.py)."""

from __future__ import annotations

from benchmark.suites import Gate, Suite
from benchmark.world.scenario import Scenario

TINY = Suite(name="tiny", version=1, scenarios=(Scenario(task="lift", seed=21, duration_s=1.5),),
             gates=(Gate("box_pos_err_mm", "<=", 8.0), Gate("learned_rel_err_pct", "<=", 60.0)),
             description="one short lift, for the tests")
