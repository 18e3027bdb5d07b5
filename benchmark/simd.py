"""NumPy at its baseline instructions: the same last bits on every x86-64 CPU.

NumPy dispatches its transcendental functions (``exp``, ``log1p``, ``tanh``, ``arctan``, ``tan``,
``arccos``, ``power`` with exponents other than 2 and 1/2, ...) and its sorts at run time to AVX2
or AVX-512 loops, whose last bits differ from those of a CPU without them: the same scenario would
give another truth, depth or force on most AMD and desktop Intel CPUs than on an AVX-512 server.
:func:`pin_numpy_baseline`, called when the ``benchmark`` package is imported, sets the environment
that keeps NumPy to the instructions every x86-64 CPU has (its "baseline"), before NumPy is
imported. It holds for this process and the local worker processes it starts (they inherit the
environment; Ray jobs get it in their runtime environment, :mod:`benchmark.parallel`). A process
that imported NumPy before the package keeps NumPy's own choice, which ``fsv.provenance`` records
(``numpy_simd``). The compiled kernels (numba) keep their own instructions: scalar loops in a
fixed order, whose vectorisation does not change their bits.

This module imports only the standard library.
"""

from __future__ import annotations

import os
import sys

NUMPY_BASELINE_ENV = {"NPY_ENABLE_CPU_FEATURES": " "}
"""The environment that keeps NumPy to its baseline instructions: no dispatched feature enabled."""


def pin_numpy_baseline() -> bool:
    """Sets :data:`NUMPY_BASELINE_ENV` (and removes ``NPY_DISABLE_CPU_FEATURES``, which NumPy refuses
    beside it) if NumPy is not imported yet.

    Returns:
        True if set; False if NumPy was already imported (its choice stands for this process).
    """
    if "numpy" in sys.modules:
        return False
    os.environ.pop("NPY_DISABLE_CPU_FEATURES", None)
    os.environ.update(NUMPY_BASELINE_ENV)
    return True
