"""Work a command starts now and waits for at its end: pictures and files off the critical path.

The main command's stages are a chain (each needs the one before), but their pictures and the
episode archive are not needed by any later stage. :class:`Background` runs them beside the
chain, on the machine's other core:

* :meth:`Background.process`: CPU-bound Python (matplotlib figures) in a forked child process, so
  it does not compete for the interpreter lock; the child sees the parent's memory as it was at
  the fork (no copying or pickling of the depth video);
* :meth:`Background.thread`: work that releases the interpreter lock (zlib compression of the
  episode archive) in a thread;
* :meth:`Background.preload`: modules the children will need (matplotlib), imported in a thread
  while the caller works in compiled code, so that each child does not import them again. A fork
  waits for the preload to end (a child must not inherit a half-done import).

:meth:`Background.wait` joins everything and raises if any of it failed, so a command that
finishes has all its files; :meth:`Background.cancel` stops the rest after a failure.
"""

from __future__ import annotations

import multiprocessing
import os
import signal
import sys
import threading
import traceback

from benchmark.errors import BenchmarkError


def _from_interrupt(error: BaseException | None) -> bool:
    """Whether ``error`` is a KeyboardInterrupt or was raised while handling one (a compiled
    module's import that Ctrl-C stopped fails with ImportError("initialization failed"))."""
    seen = set()
    while error is not None and id(error) not in seen:
        if isinstance(error, KeyboardInterrupt):
            return True
        seen.add(id(error))
        error = error.__cause__ or error.__context__
    return False


def _child(fn, args, kwargs) -> None:  # pragma: no cover - runs in the forked child
    signal.signal(signal.SIGTERM, signal.SIG_DFL)  # cancel() ends it, whatever handler the parent had (Ray's)
    try:
        fn(*args, **kwargs)
    except BaseException as e:
        if _from_interrupt(e):  # Ctrl-C reaches the whole process group: the parent reports it
            os._exit(130)
        traceback.print_exc(file=sys.stderr)
        sys.stderr.flush()
        os._exit(1)
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(0)


class Background:
    """Jobs running beside the caller until :meth:`wait`.

    Args:
        enabled: False runs every job at once in the caller (the same results, one core).
    """

    def __init__(self, enabled: bool = True):
        self.enabled = bool(enabled) and "fork" in multiprocessing.get_all_start_methods()
        self._jobs: list = []  # (name, Process | Thread, errors list or None)
        self._preload: threading.Thread | None = None

    def preload(self, *modules: str) -> None:
        """Imports ``modules`` in a thread (errors are left to the child that imports them again)."""
        if not self.enabled or self._preload is not None:
            return

        def target():
            import importlib

            for name in modules:
                try:
                    importlib.import_module(name)
                except Exception:  # the child's own import reports it
                    return

        self._preload = threading.Thread(target=target, name="preload", daemon=True)
        self._preload.start()

    def process(self, name: str, fn, *args, **kwargs) -> None:
        """Runs ``fn(*args, **kwargs)`` in a forked child process (its return value is dropped)."""
        if not self.enabled:
            fn(*args, **kwargs)
            return
        if self._preload is not None:
            self._preload.join()
        p = multiprocessing.get_context("fork").Process(target=_child, args=(fn, args, kwargs), name=name, daemon=True)
        p.start()
        self._jobs.append((name, p, None))

    def thread(self, name: str, fn, *args, **kwargs) -> None:
        """Runs ``fn(*args, **kwargs)`` in a thread (for work that releases the interpreter lock)."""
        if not self.enabled:
            fn(*args, **kwargs)
            return
        errors: list = []

        def target():
            try:
                fn(*args, **kwargs)
            except BaseException as e:  # re-raised by wait()
                errors.append(e)

        t = threading.Thread(target=target, name=name, daemon=True)
        t.start()
        self._jobs.append((name, t, errors))

    def wait(self) -> None:
        """Waits for every job.

        Raises:
            BenchmarkError: Naming the jobs that failed (a child's traceback is on stderr).
        """
        failed = []
        if self._preload is not None:
            self._preload.join()
        jobs, self._jobs = self._jobs, []
        for name, job, errors in jobs:
            job.join()
            if errors:
                failed.append(f"{name} ({type(errors[0]).__name__}: {errors[0]})")
            elif errors is None and job.exitcode != 0:
                failed.append(f"{name} (exit code {job.exitcode})")
        if failed:
            raise BenchmarkError(f"background work failed: {'; '.join(failed)}")

    def cancel(self) -> None:
        """Stops the child processes and waits for the threads (after a failure or an interrupt)."""
        if self._preload is not None:
            self._preload.join()
        jobs, self._jobs = self._jobs, []
        for _, job, errors in jobs:
            if errors is None and job.is_alive():
                job.terminate()
        for _, job, _ in jobs:
            job.join()
