"""Work a command starts now and waits for at its end: pictures and files off the critical path.

The main command's stages are a chain (each needs the one before), but their pictures and the
episode archive are not needed by any later stage. :class:`Background` runs them beside the
chain, on the machine's other core:

* :meth:`Background.process`: CPU-bound Python (matplotlib figures) in a forked child process, so
  it does not compete for the interpreter lock; the child sees the parent's memory as it was at
  the fork (no copying or pickling of the depth video);
* :meth:`Background.thread`: work that releases the interpreter lock (zlib compression of the
  episode archive) in a thread;
* :meth:`Background.fork`: CPU-bound work whose (small) result the caller needs later, in a forked
  child that sends it back through a pipe (:meth:`Job.result`); large arrays it makes go into
  memory shared with the caller (:func:`shared_empty`), not through the pipe;
* :meth:`Background.stream`: such work that makes its output in order (the frames of a video) and
  says through the same pipe how much of it is done, so that the caller may use the first items
  while the child makes the later ones (:meth:`Job.wait_for`);
* :meth:`Background.preload`: modules the children will need (matplotlib), imported in a thread
  while the caller works in compiled code, so that each child does not import them again. A fork
  waits for the preload to end (a child must not inherit a half-done import).

:meth:`Background.wait` joins everything and raises if any of it failed (one line naming the job
and its error), so a command that finishes has all its files; :meth:`Background.cancel` stops the
rest after a failure or Ctrl-C (a forked child is terminated; a thread waiting for its result is
woken by the closed pipe).
"""

from __future__ import annotations

import ctypes
import importlib
import mmap
import multiprocessing
import os
import signal
import sys
import threading
import traceback

import numpy as np

from benchmark import interrupt
from benchmark.errors import BenchmarkError
from fsv.errors import FsvError, one_line

EXPECTED_ERRORS = (BenchmarkError, FsvError, OSError)
"""Failures a forked job reports as one line (the command's own errors, a full disk); any other
exception is a bug and its traceback goes to stderr too."""


def _from_interrupt(error: BaseException | None) -> bool:
    """Whether ``error`` is a KeyboardInterrupt or was raised while handling one (a compiled
    module's import that Ctrl-C stopped fails with ImportError("initialization failed")), or
    whether Ctrl-C came at all (:func:`benchmark.interrupt.interrupted`): a library whose compiled
    code called back into Python when the KeyboardInterrupt was raised may replace it with an error
    of its own that does not name it (matplotlib's renderer: ``ValueError: Invalid bounding box``)."""
    if interrupt.interrupted():
        return True
    seen = set()
    while error is not None and id(error) not in seen:
        if isinstance(error, KeyboardInterrupt):
            return True
        seen.add(id(error))
        error = error.__cause__ or error.__context__
    return False


_BLOCKED_FOR_FORK = frozenset({signal.SIGTERM, signal.SIGINT})
"""Signals blocked in the forking thread while it forks a job (:func:`_start_forked`)."""


def _terminable() -> None:  # pragma: no cover - runs in the forked child
    """SIGTERM's default action, then SIGTERM and SIGINT unblocked (:func:`_start_forked` blocked
    them for the fork): a cancel() sent before this line is delivered here and ends the child, not
    the parent's handler (Ray's, which returns) that the child inherited; a Ctrl-C that came during
    the fork raises its KeyboardInterrupt here, inside the child's ``try`` (exit 130, no traceback),
    not in multiprocessing's start-up code, which would print one."""
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, _BLOCKED_FOR_FORK)


def _start_forked(process) -> None:
    """``process.start()`` (a fork) with SIGTERM and SIGINT blocked in the forking thread for the
    fork's duration, so that the child starts with them blocked until :func:`_terminable`; the
    caller's own signal, if one comes meanwhile, is delivered when the fork returns."""
    old = signal.pthread_sigmask(signal.SIG_BLOCK, _BLOCKED_FOR_FORK)
    try:
        process.start()
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old)


def _child(fn, args, kwargs) -> None:  # pragma: no cover - runs in the forked child
    try:
        _terminable()  # cancel() ends it, whatever handler the parent had (Ray's)
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


def _end_with_parent(parent: int) -> None:  # pragma: no cover - runs in the forked child
    """Linux: this process is killed when its parent dies, however it dies (SIGKILL included, which
    no cleanup code of the parent sees), so that no worker outlives its command."""
    if sys.platform != "linux":
        return

    try:
        ctypes.CDLL(None, use_errno=True).prctl(1, signal.SIGKILL)  # PR_SET_PDEATHSIG
    except (OSError, AttributeError):
        return
    if os.getppid() != parent:  # it died before the call
        os._exit(1)


def _child_returning(conn, parent, fn, args, kwargs) -> None:  # pragma: no cover - runs in the forked child
    """A forked job: sends ``("value", fn(...))`` or ``("error", one line)`` through ``conn``, then exits."""
    try:
        _terminable()
        _end_with_parent(parent)
        message = ("value", fn(*args, **kwargs))
        code = 0
    except BaseException as e:
        if _from_interrupt(e):
            os._exit(130)
        if not isinstance(e, EXPECTED_ERRORS):
            traceback.print_exc(file=sys.stderr)
        message, code = ("error", f"{type(e).__name__}: {one_line(e)}"), 1
    try:
        conn.send(message)
        conn.close()
    except BaseException:  # an unpicklable result, or the parent gone
        traceback.print_exc(file=sys.stderr)
        code = 1
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(code)


def _child_streaming(conn, parent, fn, args, kwargs) -> None:  # pragma: no cover - runs in the forked child
    """A streamed job (:meth:`Background.stream`): ``fn(done, ...)``, where ``done(n)`` sends
    ``("done", n)`` through ``conn`` ahead of the result."""

    def done(n: int) -> None:
        conn.send(("done", int(n)))

    _child_returning(conn, parent, fn, (done, *args), kwargs)


def shared_empty(shape: tuple, dtype) -> np.ndarray:
    """An uninitialised array in anonymous shared memory: what a child forked after this call
    (:meth:`Background.fork`) writes into it, this process sees, with no copy and no pickling. The
    memory has no name (nothing to clean up when a process is killed) and is freed with its last
    reference in every process."""
    dtype = np.dtype(dtype)
    count = int(np.prod(shape, dtype=np.int64))
    buffer = mmap.mmap(-1, max(count * dtype.itemsize, 1), flags=mmap.MAP_SHARED)
    return np.frombuffer(buffer, dtype=dtype, count=count).reshape(shape)


class JobFailed(BenchmarkError):
    """Raised by :meth:`Job.result` of a job that failed (``job``: that job)."""

    def __init__(self, job: "Job"):
        super().__init__(f"{job.name} failed: {job.failure()}")
        self.job = job


class Job:
    """A job started on a :class:`Background`: its result once done."""

    def __init__(self, name: str):
        self.name = name
        self._done = False
        self._value = None
        self._error: str | None = None

    def _set(self, value=None, error: str | None = None) -> None:
        self._value, self._error, self._done = value, error, True

    def _wait(self) -> None:  # overridden by the kinds that run beside the caller
        pass

    def failure(self) -> str | None:
        """None if the job succeeded, else what went wrong, one line (waits for the job)."""
        self._wait()
        return self._error

    def result(self):
        """The job's return value (waits for it).

        Raises:
            JobFailed: One line naming the job and its error.
        """
        if self.failure() is not None:
            raise JobFailed(self)
        return self._value

    def wait_for(self, n: int) -> None:
        """Returns once the job has said that the first ``n`` items of its output are done
        (:meth:`Background.stream`); a job of another kind once it has ended.

        Raises:
            JobFailed: The job failed before it got so far (or ended without getting there).
        """
        self.result()


class _ThreadJob(Job):
    def __init__(self, name: str, fn, args, kwargs):
        super().__init__(name)

        def target():
            try:
                value = fn(*args, **kwargs)
            except BaseException as e:  # reported by failure(), wait()
                self._exception = e
                self._set(error=f"{type(e).__name__}: {one_line(e)}")
                return
            self._set(value)

        self._exception = None
        self.thread = threading.Thread(target=target, name=name, daemon=True)
        self.thread.start()

    def _wait(self) -> None:
        self.thread.join()


class _ForkJob(Job):
    def __init__(self, name: str, fn, args, kwargs, streamed: bool = False):
        super().__init__(name)
        ctx = multiprocessing.get_context("fork")
        self._conn, child_end = ctx.Pipe(duplex=False)
        target = _child_streaming if streamed else _child_returning
        self.process = ctx.Process(target=target, args=(child_end, os.getpid(), fn, args, kwargs), name=name,
                                   daemon=True)
        _start_forked(self.process)
        child_end.close()  # only the child holds the writing end: its exit, however it comes, ends our read
        # Threads may wait for the result or for a count of items while wait() or cancel() does: one
        # reads the pipe at a time (without the lock), the others wait for what it read.
        self._changed = threading.Condition()
        self._reading = False
        self._count = 0  # the items the child has said are done
        self._owner = os.getpid()  # the pipe is read in this process only (not in a child forked since)

    def _receive(self, enough) -> None:
        """Reads the child's messages until ``enough()`` or the job has ended."""
        if os.getpid() != self._owner and not (self._done or enough()):
            raise BenchmarkError(f"the job {self.name} is waited for in a process forked from the one that started it")
        with self._changed:
            while not (self._done or enough()):
                if self._reading:
                    self._changed.wait()
                    continue
                self._reading = True
                try:
                    self._changed.release()
                    try:
                        message = self._conn.recv()
                    except Exception:  # the child's exit (EOF), or a read that Ctrl-C cut short
                        message = None
                    finally:
                        self._changed.acquire()
                finally:
                    self._reading = False
                    self._changed.notify_all()
                self._take(message)

    def _take(self, message) -> None:
        kind, payload = message if isinstance(message, tuple) and len(message) == 2 else (None, None)
        if kind == "done":
            self._count = payload
            return
        self._conn.close()
        self.process.join()
        if kind == "value":
            self._set(payload)
        elif kind == "error":
            self._set(error=payload)
        else:
            self._set(error=f"the process ended without a result (exit code {self.process.exitcode})")

    def _wait(self) -> None:
        self._receive(lambda: False)

    def wait_for(self, n: int) -> None:
        self._receive(lambda: self._count >= n)
        if self._count >= n:
            return
        if self._error is None:  # it returned without saying so: its output is not whole
            self._error = f"it ended after {self._count} items, not {n}"
        raise JobFailed(self)

    def terminate(self) -> None:
        """Sends SIGTERM (nothing if already reaped); no waitpid here, a thread may be joining it."""
        self.process.terminate()


class _DoneJob(Job):
    def __init__(self, name: str, value):
        super().__init__(name)
        self._set(value)


class Background:
    """Jobs running beside the caller until :meth:`wait`.

    Args:
        enabled: False runs every job at once in the caller (the same results, one core).
    """

    def __init__(self, enabled: bool = True):
        self.enabled = bool(enabled) and "fork" in multiprocessing.get_all_start_methods()
        self._jobs: list = []  # (name, Process or Job)
        self._preload: threading.Thread | None = None

    def preload(self, *modules: str) -> None:
        """Imports ``modules`` in a thread (errors are left to the child that imports them again)."""
        if not self.enabled or self._preload is not None:
            return

        def target():
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
        _start_forked(p)
        self._jobs.append((name, p))

    def fork(self, name: str, fn, *args, **kwargs) -> Job:
        """Runs ``fn(*args, **kwargs)`` in a forked child process whose return value (pickled: keep
        it small, put large arrays in :func:`shared_empty` memory made before this call) comes
        back as the :class:`Job`'s result. Its failure is one line (``Type: message``; a traceback on
        stderr too where it is not one of :data:`EXPECTED_ERRORS`); Ctrl-C ends it with the caller,
        and on Linux it is killed when the thread that forked it dies, however it dies."""
        if not self.enabled:
            return _DoneJob(name, fn(*args, **kwargs))
        if self._preload is not None:
            self._preload.join()
        job = _ForkJob(name, fn, args, kwargs)
        self._jobs.append((name, job))
        return job

    def stream(self, name: str, fn, *args, **kwargs) -> Job:
        """:meth:`fork` for work that makes its output in order into :func:`shared_empty` memory:
        it runs ``fn(done, *args, **kwargs)``, where ``done(n)`` (called with a growing ``n``)
        says that the first ``n`` items are written, and the caller's :meth:`Job.wait_for` returns
        once they are (the pipe orders the child's writes before the caller's reads)."""
        if not self.enabled:
            return _DoneJob(name, fn(lambda n: None, *args, **kwargs))
        if self._preload is not None:
            self._preload.join()
        job = _ForkJob(name, fn, args, kwargs, streamed=True)
        self._jobs.append((name, job))
        return job

    def thread(self, name: str, fn, *args, **kwargs) -> Job:
        """Runs ``fn(*args, **kwargs)`` in a thread (for work that releases the interpreter lock);
        the :class:`Job` holds its return value."""
        if not self.enabled:
            return _DoneJob(name, fn(*args, **kwargs))
        job = _ThreadJob(name, fn, args, kwargs)
        self._jobs.append((name, job))
        return job

    def wait(self) -> None:
        """Waits for every job.

        Raises:
            BenchmarkError: Naming the jobs that failed (a child's traceback is on stderr).
        """
        failed = []
        if self._preload is not None:
            self._preload.join()
        jobs, self._jobs = self._jobs, []
        waited = [job for _, job in jobs]
        for name, job in jobs:
            if isinstance(job, Job):
                error = job.failure()
                upstream = getattr(job, "_exception", None)
                if isinstance(upstream, JobFailed) and upstream.job in waited:
                    continue  # it failed because a job it waited for did: that one is reported
                if error is not None:
                    failed.append(f"{name} ({error})")
                continue
            job.join()
            if job.exitcode != 0:
                failed.append(f"{name} (exit code {job.exitcode})")
        if failed:
            raise BenchmarkError(f"background work failed: {'; '.join(failed)}")

    def cancel(self) -> None:
        """Stops the child processes and waits for the threads (after a failure or an interrupt)."""
        if self._preload is not None:
            self._preload.join()
        jobs, self._jobs = self._jobs, []
        for _, job in jobs:
            if isinstance(job, _ForkJob):
                job.terminate()
            elif isinstance(job, multiprocessing.process.BaseProcess) and job.is_alive():
                job.terminate()
        for _, job in jobs:  # a forked job's process first: a thread may be waiting for its result
            if isinstance(job, _ForkJob):
                job.failure()
        for _, job in jobs:
            if isinstance(job, Job):
                job.failure()
            else:
                job.join()
