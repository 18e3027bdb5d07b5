"""The arrays handed to the tracker's compiled kernels: one numba specialisation per kernel.

numba compiles a kernel once for every combination of argument types it is called with, and a
read-only array is another type than a writable one. A pose that reached the hand's fit read-only
(as the method's first-frame initialisation does) and one the tracker computed made numba compile
the whole Levenberg-Marquardt fit (:func:`fsv.track.hand.lm.solve`) two or three times: a 1.5 s
lift's command with an empty cache took 33.7 s, 28.1 s with each kernel compiled once. Every array
a kernel only reads goes in through :func:`readonly`, whatever its origin.
"""

from __future__ import annotations

import numpy as np


def readonly(x, dtype=np.float64) -> np.ndarray:
    """``x`` as a read-only, C-ordered array of ``dtype``: a read-only view of ``x`` itself where it
    already is one of that order and type (no copy), else a read-only copy. Same shape, same values."""
    a = np.ascontiguousarray(x, dtype=dtype)
    if a.flags.writeable:
        a = a.view()
        a.flags.writeable = False
    return a
