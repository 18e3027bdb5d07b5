"""One Python interpreter per OpenBLAS kernel, kept for the session and shared by the tests that
compare bits under several kernels.

OpenBLAS reads ``OPENBLAS_CORETYPE`` once, when NumPy loads it, so each kernel needs a process of
its own; starting one per test and kernel cost about 1.5 s of imports and numba cache loads each
(about twenty of them in the suite). Each :class:`KernelPython` runs the scripts it is sent, one at a
time, as ``python -c SCRIPT ARGS...`` would (``__name__ == "__main__"``, ``sys.argv``), and returns
what they printed. Scripts share the interpreter's caches (the world's models, grasp plans), which
are made under the same kernel.
"""

from __future__ import annotations

import json
import os
import pathlib
import select
import subprocess
import sys
import tempfile

ROOT = pathlib.Path(__file__).resolve().parent.parent

_SERVE = r"""
import contextlib, io, json, os, sys, traceback
from benchmark import collector
collector.tune()  # the command's collector, as in the test processes (tests/conftest.py)
replies = os.fdopen(os.dup(1), "w")
os.dup2(2, 1)  # what C code writes to fd 1 goes to stderr, not into the replies
for line in sys.stdin:
    request = json.loads(line)
    sys.argv = ["-c", *request["argv"]]
    out, ok, error = io.StringIO(), True, ""
    try:
        with contextlib.redirect_stdout(out):
            exec(compile(request["code"], "<script>", "exec"), {"__name__": "__main__"})
    except SystemExit as e:
        ok, error = e.code in (None, 0), f"SystemExit: {e.code}"
    except BaseException:
        ok, error = False, traceback.format_exc()
    replies.write(json.dumps({"ok": ok, "stdout": out.getvalue(), "error": error}) + "\n")
    replies.flush()
"""


class ScriptFailed(AssertionError):
    """A script raised (its traceback and the interpreter's stderr are the message)."""


class KernelPython:
    """An interpreter started with ``env`` added to this process's environment (``PYTHONPATH`` led
    by the checkout, the checkout as its working folder); :meth:`run` sends it a script."""

    def __init__(self, env: dict):
        self.env = dict(env)
        self._stderr = tempfile.TemporaryFile()  # a file, not a pipe: an unread pipe would block the child
        path = os.pathsep.join(p for p in (str(ROOT), os.environ.get("PYTHONPATH", "")) if p)
        self._proc = subprocess.Popen([sys.executable, "-u", "-c", _SERVE], stdin=subprocess.PIPE,
                                      stdout=subprocess.PIPE, stderr=self._stderr, cwd=ROOT, text=True,
                                      env={**os.environ, "PYTHONPATH": path, **self.env})

    def run(self, code: str, *argv: str, timeout_s: float = 300.0) -> str:
        """Runs ``code`` with ``sys.argv[1:] == argv``: what it printed; :class:`ScriptFailed` if it raised."""
        if self._proc.poll() is not None:
            raise ScriptFailed(f"the interpreter for {self.env} ended ({self._proc.returncode}): {self._tail()}")
        self._proc.stdin.write(json.dumps({"code": code, "argv": [str(a) for a in argv]}) + "\n")
        self._proc.stdin.flush()
        ready, _, _ = select.select([self._proc.stdout], [], [], timeout_s)
        line = self._proc.stdout.readline() if ready else ""
        if not line:
            self._proc.kill()
            tail = self._tail()
            self.close()
            raise ScriptFailed(f"no answer within {timeout_s} s from the interpreter for {self.env}: {tail}")
        reply = json.loads(line)
        if not reply["ok"]:
            raise ScriptFailed(f"the script failed under {self.env}:\n{reply['error']}\nstderr: {self._tail()}")
        return reply["stdout"]

    def _tail(self) -> str:
        if self._stderr.closed:
            return ""
        self._stderr.seek(0)
        return self._stderr.read()[-3000:].decode(errors="replace")

    def close(self) -> None:
        if self._proc.poll() is None:
            self._proc.stdin.close()
            try:
                self._proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                self._proc.kill()
                self._proc.wait()
        self._stderr.close()


class KernelPythons:
    """The interpreters of a session, one per environment asked for (made at its first use)."""

    def __init__(self):
        self._running: dict = {}

    def run(self, code: str, *argv: str, env: dict, timeout_s: float = 300.0) -> str:
        """:meth:`KernelPython.run` in the interpreter whose environment adds ``env``
        (e.g. ``{"OPENBLAS_CORETYPE": "Haswell"}``)."""
        key = tuple(sorted(env.items()))
        if key not in self._running:
            self._running[key] = KernelPython(env)
        return self._running[key].run(code, *argv, timeout_s=timeout_s)

    def close(self) -> None:
        for python in self._running.values():
            python.close()
        self._running.clear()
