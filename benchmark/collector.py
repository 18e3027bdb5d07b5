"""The garbage collector's settings in fsv-bench's own processes: the command's, and its local pool's
fork server and workers.

CPython collects its youngest generation after every 700 new container objects, and the whole heap
when enough has survived; the command's NumPy-heavy stages make many short-lived small objects, and
each full collection scans every object the imported libraries made. On 50 000 new objects instead
(:data:`THRESHOLD`), the main command's whole process runs 6 % faster (4.38 s against 4.69 s, median
of 5, interleaved; docs/speed.md). Cyclic garbage waits a little longer; nothing else changes: no
result depends on when the collector runs.
"""

from __future__ import annotations

import gc

THRESHOLD = (50_000, 20, 20)
"""``gc.set_threshold``'s three thresholds (CPython's: 700, 10, 10)."""


def tune() -> None:
    """Sets :data:`THRESHOLD` in this process (and the processes it forks)."""
    gc.set_threshold(*THRESHOLD)
