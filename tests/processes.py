"""What a test can see of a process by its id (Linux's /proc)."""

from __future__ import annotations

import pathlib


def _stat(pid) -> list:
    """The fields of ``/proc/<pid>/stat`` after the command's name (state, parent, group, ...), or []
    if the process is gone."""
    try:
        return pathlib.Path(f"/proc/{pid}/stat").read_text().rpartition(")")[2].split()
    except OSError:
        return []


def state(pid: int) -> str:
    """Process ``pid``'s state letter in ``/proc/<pid>/stat`` (``"R"``, ``"S"``, ``"Z"`` for a zombie, ...),
    or ``"gone"``."""
    fields = _stat(pid)
    return fields[0] if fields else "gone"


def running(pid: int) -> bool:
    """Whether process ``pid`` is there and has not ended: a zombie (an ended process its parent, or
    init after the parent's death, has not reaped yet: up to 2 s here) has ended."""
    return state(pid) not in ("gone", "Z")


def group_running(pgid: int) -> list:
    """The ids of the processes of process group ``pgid`` that are running (zombies have ended: a
    killed command's children wait up to 2 s here for init to reap them)."""
    members = []
    for proc in pathlib.Path("/proc").glob("[0-9]*"):
        fields = _stat(proc.name)
        if fields and int(fields[2]) == pgid and fields[0] != "Z":
            members.append(int(proc.name))
    return members
