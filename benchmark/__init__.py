"""The synthetic world of fsv-bench and its scorers (this package knows the truth).

The names below are loaded on first use (``benchmark.Scenario``, ``from benchmark import simulate``),
so that importing a small part of the package (``benchmark.errors``, ``benchmark.interrupt``) does
not load MuJoCo and the renderer.
"""

import importlib

_EXPORTS = {
    "BenchmarkError": "benchmark.errors", "EpisodeFileError": "benchmark.errors", "RenderError": "benchmark.errors",
    "ScenarioError": "benchmark.errors", "SimulationError": "benchmark.errors",
    "Scenario": "benchmark.world.scenario", "Episode": "benchmark.world.episode",
    "simulate": "benchmark.world.simulate", "TASKS": "benchmark.world.tasks",
    "load_episode": "benchmark.camera.episode_file", "save_episode": "benchmark.camera.episode_file",
    "render": "benchmark.camera.render", "SensorModel": "benchmark.camera.sensor",
}
__all__ = sorted(_EXPORTS)


def __getattr__(name: str):
    if name in _EXPORTS:
        value = getattr(importlib.import_module(_EXPORTS[name]), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'benchmark' has no attribute {name!r}")
