"""Seconds spent compiling numba kernels while a block of code runs.

The first run after installing compiles the kernels (tens of seconds for the tracker's); later runs
load them from numba's on-disk cache and spend none. A speed quoted without them is the speed a
user sees from the second run on.

>>> with CompileClock() as clock:
...     tracking = track(...)
>>> clock.s  # seconds compiling, [s]
"""

from __future__ import annotations

import time

from numba.core import event


class CompileClock(event.Listener):
    """Sums the wall time of numba's outermost compilations (a kernel compiled while another is
    compiled counts once) between ``__enter__`` and ``__exit__``, in any thread of the process.

    Attributes:
        s: Seconds compiled so far, [s].
    """

    def __init__(self):
        self.s = 0.0
        self._depth = 0
        self._t0 = 0.0

    def on_start(self, ev) -> None:
        if self._depth == 0:
            self._t0 = time.perf_counter()
        self._depth += 1

    def on_end(self, ev) -> None:
        self._depth -= 1
        if self._depth == 0:
            self.s += time.perf_counter() - self._t0

    def __enter__(self) -> CompileClock:
        event.register("numba:compile", self)
        return self

    def __exit__(self, *exc) -> None:
        event.unregister("numba:compile", self)
