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


def group_running(pgid: int) -> list:
    """The ids of the processes of process group ``pgid`` that are running (zombies have ended: a
    killed command's children wait up to 2 s here for init to reap them)."""
    members = []
    for stat in pathlib.Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rpartition(")")[2].split()
        except OSError:  # it ended while we looked
            continue
        if int(fields[2]) == pgid and fields[0] != "Z":
            members.append(int(stat.parent.name))
    return members
