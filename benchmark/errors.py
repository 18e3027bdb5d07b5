"""Errors raised by the benchmark (the synthetic world and its scorers).

Every error derives from :class:`BenchmarkError`; the CLI turns them into a one-line message and
exit status 2.
"""


class BenchmarkError(Exception):
    """Base class of every error raised by `benchmark`."""


class ScenarioError(BenchmarkError, ValueError):
    """A scenario parameter is out of range; the message names the value and the accepted ones."""


class EpisodeFileError(BenchmarkError):
    """An episode file is missing, truncated, of another format or of an unsupported version."""


class RenderError(BenchmarkError):
    """The depth could not be rendered; the message says why and how to fix it. The CPU rasteriser
    needs no system library and does not raise it; it stays in the API for code that catches it."""


class SimulationError(BenchmarkError):
    """The simulation diverged or the task failed (e.g. the box was dropped)."""


class DatasetError(BenchmarkError, ValueError):
    """A dataset folder or specification is invalid (e.g. resuming with other arguments)."""


class DatasetFileError(DatasetError):
    """A dataset file is truncated, corrupt, renamed from another episode or without a digest; the
    message names the file."""
