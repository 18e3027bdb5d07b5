"""The synthetic world of fsv-bench and its scorers (this package knows the truth)."""

from benchmark.errors import BenchmarkError, EpisodeFileError, RenderError, ScenarioError, SimulationError
from benchmark.scenario import Scenario
from benchmark.episode import Episode, load_episode, save_episode
from benchmark.simulate import simulate
from benchmark.tasks import TASKS

# Depth rendering (issue 3)
from benchmark.render import render  # noqa: E402
from benchmark.sensor import SensorModel  # noqa: E402
