"""Named, versioned sets of scenarios with their default gates."""

from benchmark.suites.registry import SUITES, get_suite
from benchmark.suites.suite import Gate, Suite

__all__ = ["Gate", "SUITES", "Suite", "get_suite"]
