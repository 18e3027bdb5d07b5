"""The synthetic world of fsv-bench and its scorers (this package knows the truth).

Its parts are imported from where they live, so that importing a small part of the package
(``benchmark.errors``, ``benchmark.interrupt``) loads neither MuJoCo nor the renderer:
``benchmark.world.scenario.Scenario``, ``benchmark.world.simulate.simulate``,
``benchmark.camera.render.render``, ``benchmark.camera.episode_file.load_episode`` and
``save_episode``, ``benchmark.world.episode.Episode``, ``benchmark.world.tasks.TASKS``.

NumPy's own vector loops are pinned here, before NumPy is imported, to the instructions every x86-64
CPU has (its "baseline"): its transcendental functions (``exp``, ``log``, ``log1p``, ``tan``,
``arccos``, ``power`` with exponents other than 2 and 1/2, ...) and its sorts are dispatched at run
time to AVX2 or AVX-512 versions that give other last bits than the baseline's, so the same scenario
would give another truth, depth or force on a CPU without AVX-512 (most AMD and desktop Intel CPUs).
The pin costs NumPy's vector loops their AVX2/AVX-512 speed (the compiled kernels keep theirs). It
holds for this process and the local worker processes it starts; a process that imported NumPy
before this package keeps NumPy's own choice, which ``fsv.provenance`` records (``numpy_simd``).
"""

import os as _os
import sys as _sys

NUMPY_BASELINE_ENV = {"NPY_ENABLE_CPU_FEATURES": " "}
"""The environment that keeps NumPy to its baseline instructions: no dispatched feature enabled
(NumPy refuses ``NPY_DISABLE_CPU_FEATURES`` beside it, so that one is removed)."""

if "numpy" not in _sys.modules:
    _os.environ.pop("NPY_DISABLE_CPU_FEATURES", None)
    _os.environ.update(NUMPY_BASELINE_ENV)
