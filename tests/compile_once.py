"""numba's kernels compiled once, before pytest-xdist's workers run their first test.

With an empty numba cache (a machine's first run, every clean CI run) each process compiles the
kernels it calls and writes them to the cache once compiled. The two workers, and the processes
their first tests start, call the same kernels within seconds of each other, and each compiled them
again (the tracker's alone take about 28 s). The controller now starts one short main command
(depth and colour, no pictures) as soon as the session is configured, while the workers start and
collect their tests (about 10-18 s); each worker waits for it before its first test, and then loads
the kernels from the cache. With a warm cache the command is about 3 s of CPU beside the collection.
"""

from __future__ import annotations

import os
import pathlib
import shutil
import subprocess
import sys
import tempfile
import time

ROOT = pathlib.Path(__file__).resolve().parent.parent

MARKER_ENV = "FSV_TESTS_KERNELS_COMPILED"
"""The file the compiling command writes when it is done (set by the controller, read by the workers)."""

COMMAND = ("--task", "lift", "--duration", "1", "--streams", "depth,colour", "--no-pictures", "--quiet", "--force")
"""The main command that compiles the kernels: the world's, the sensor's, the colour renderer's and
the whole method's (every stage runs on the 1 s lift)."""

_SCRIPT = """
import pathlib, sys
try:
    from benchmark.commands.cli import main
    main([*sys.argv[3:], "--out", sys.argv[1]])
finally:
    pathlib.Path(sys.argv[2]).write_text("done")
"""


class Compiling:
    """The compiling command, started at once in its own temporary folder (:meth:`close` ends it
    if it still runs and removes the folder)."""

    def __init__(self, command: tuple = COMMAND):
        self.folder = pathlib.Path(tempfile.mkdtemp(prefix="fsv-tests-compile-"))
        self.marker = self.folder / "done"
        path = os.pathsep.join(p for p in (str(ROOT), os.environ.get("PYTHONPATH", "")) if p)
        self._proc = subprocess.Popen([sys.executable, "-c", _SCRIPT, str(self.folder / "run"), str(self.marker),
                                       *command], cwd=ROOT, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                                      env={**os.environ, "PYTHONPATH": path})

    def close(self) -> None:
        if self._proc.poll() is None:
            self._proc.kill()
        self._proc.wait()
        shutil.rmtree(self.folder, ignore_errors=True)


def wait_for(marker: str | os.PathLike, timeout_s: float = 600.0) -> bool:
    """Waits until ``marker`` exists (the compiling command is done, whether it passed or failed:
    a failure shows in the tests themselves), at most ``timeout_s``; whether it came."""
    deadline = time.monotonic() + timeout_s
    while not os.path.exists(marker):
        if time.monotonic() > deadline:
            return False
        time.sleep(0.1)
    return True
