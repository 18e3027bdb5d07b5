"""The synthetic world of fsv-bench and its scorers (this package knows the truth)."""

import os

# Headless by design: MuJoCo and pyrender pick their GL platform when first imported, so the
# choice is made here, before any submodule imports them (a caller's own setting wins).
os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("PYOPENGL_PLATFORM", "egl")

# isort: off

from benchmark.errors import BenchmarkError, EpisodeFileError, RenderError, ScenarioError, SimulationError
from benchmark.world.scenario import Scenario
from benchmark.episode import Episode, load_episode, save_episode
from benchmark.world.simulate import simulate
from benchmark.world.tasks import TASKS

# Depth rendering (issue 3)
from benchmark.camera.render import render  # noqa: E402
from benchmark.camera.sensor import SensorModel  # noqa: E402
