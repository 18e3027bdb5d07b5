"""The synthetic world of fsv-bench and its scorers (this package knows the truth).

Its parts are imported from where they live, so that importing a small part of the package
(``benchmark.errors``, ``benchmark.interrupt``) loads neither MuJoCo nor the renderer:
``benchmark.world.scenario.Scenario``, ``benchmark.world.simulate.simulate``,
``benchmark.camera.render.render``, ``benchmark.camera.episode_file.load_episode`` and
``save_episode``, ``benchmark.world.episode.Episode``, ``benchmark.world.tasks.TASKS``.

Importing the package first pins NumPy's vector loops to its baseline instructions
(:mod:`benchmark.simd`), before NumPy is imported.
"""

from benchmark.simd import pin_numpy_baseline as _pin_numpy_baseline

_pin_numpy_baseline()
