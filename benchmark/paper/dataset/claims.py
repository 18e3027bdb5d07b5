"""Which run makes which episode of a dataset folder: claim files, so that concurrent runs share the work."""

from __future__ import annotations

import json
import os
import socket
import time

from benchmark.world.scenario import episode_name

CLAIM_POLL_S = 0.5
"""How often a run checks on the episodes another run is making [s]."""


class Claims:
    """Which run makes which episode of a dataset folder: ``episodes/<id>.claim`` files.

    A run creates the claim (exclusively: ``O_CREAT | O_EXCL``, so two runs never both get it) with
    its host name and process id before building the episode and removes it once the episode's file
    is written. A claim whose process is gone (same host) is stale and may be taken over; claims of
    other hosts are trusted. Concurrent ``generate`` runs into one folder thus share the work.
    """

    def __init__(self, out: str):
        self.folder = os.path.join(out, "episodes")
        self.host, self.pid = socket.gethostname(), os.getpid()
        self.mine: set = set()
        self.waited = False

    def _path(self, episode: str) -> str:
        return os.path.join(self.folder, episode + ".claim")

    def take(self, episode: str) -> bool:
        path = self._path(episode)
        for _ in range(2):
            try:
                fd = os.open(path, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
            except FileExistsError:
                if not self._stale(path):
                    return False
                try:
                    os.unlink(path)
                except FileNotFoundError:
                    pass
                continue
            with os.fdopen(fd, "w") as fh:
                fh.write(json.dumps({"host": self.host, "pid": self.pid}))
            self.mine.add(episode)
            return True
        return False

    def _stale(self, path: str) -> bool:
        try:
            with open(path) as fh:
                owner = json.loads(fh.read() or "{}")
        except (OSError, ValueError):
            return False  # being written right now
        if owner.get("host") != self.host or not isinstance(owner.get("pid"), int):
            return False
        try:
            os.kill(owner["pid"], 0)
        except ProcessLookupError:
            return True
        except PermissionError:
            return False
        return False

    def release(self, episode: str) -> None:
        if episode in self.mine:
            self.mine.discard(episode)
            try:
                os.unlink(self._path(episode))
            except FileNotFoundError:
                pass

    def release_all(self) -> None:
        for episode in list(self.mine):
            self.release(episode)

    def wait_for_others(self, todo: list, bar) -> list:
        """Waits while other runs make the episodes of ``todo``; returns those whose run died."""
        while todo:
            self.waited = True
            left = []
            for sc in todo:
                e = episode_name(sc)
                if os.path.exists(os.path.join(self.folder, e + ".parquet")) and not os.path.exists(self._path(e)):
                    bar.update(1)
                elif os.path.exists(self._path(e)) and not self._stale(self._path(e)):
                    left.append(sc)
                else:
                    return todo  # a claim went stale (or vanished without a file): build what is left
            if not left:
                return []
            todo = left
            time.sleep(CLAIM_POLL_S)
        return []


