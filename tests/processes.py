"""What a test can see of a process by its id (Linux's /proc)."""

from __future__ import annotations

import pathlib


def state(pid: int) -> str:
    """Process ``pid``'s state letter in ``/proc/<pid>/stat`` (``"R"``, ``"S"``, ``"Z"`` for a zombie, ...),
    or ``"gone"``."""
    try:
        return pathlib.Path(f"/proc/{pid}/stat").read_text().rpartition(")")[2].split()[0]
    except OSError:
        return "gone"


def running(pid: int) -> bool:
    """Whether process ``pid`` is there and has not ended: a zombie (an ended process its parent, or
    init after the parent's death, has not reaped yet: up to 2 s here) has ended."""
    return state(pid) not in ("gone", "Z")
