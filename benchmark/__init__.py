"""The synthetic world of fsv-bench and its scorers (this package knows the truth)."""

import os

# Headless by design: MuJoCo and pyrender pick their GL platform when first imported, so the
# choice is made here, before any submodule imports them (a caller's own setting wins).
os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("PYOPENGL_PLATFORM", "egl")

# isort: off

from benchmark.errors import BenchmarkError, EpisodeFileError, RenderError, ScenarioError, SimulationError
from benchmark.world.scenario import Scenario
from benchmark.world.episode import Episode
from benchmark.world.simulate import simulate
from benchmark.world.tasks import TASKS
from benchmark.camera.episode_file import load_episode, save_episode
from benchmark.camera.render import render
from benchmark.camera.sensor import SensorModel
