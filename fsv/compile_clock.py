"""Seconds spent compiling numba kernels while a block of code runs.

The first run after installing compiles the kernels (tens of seconds for the tracker's); later runs
load them from numba's on-disk cache and spend none. A speed quoted without them is the speed a
user sees from the second run on.

>>> with CompileClock() as clock:
...     tracking = track(...)
>>> clock.s  # seconds compiling, [s]
"""

from __future__ import annotations

from numba.core import event


class CompileClock(event.TimingListener):
    """numba's timer of its outermost compilations (a kernel compiled while another is compiled
    counts once), listening to ``numba:compile`` between ``__enter__`` and ``__exit__``, in any
    thread of the process, with the seconds so far readable at any time (:attr:`s`)."""

    @property
    def s(self) -> float:
        """Seconds compiled so far, [s]."""
        return self.duration if self.done else 0.0

    def __enter__(self) -> CompileClock:
        event.register("numba:compile", self)
        return self

    def __exit__(self, *exc) -> None:
        event.unregister("numba:compile", self)
