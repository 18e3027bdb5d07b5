"""Ctrl-C ends a command with status 130 within a second, whatever it is doing, and loses nothing.

:func:`install` makes SIGINT raise KeyboardInterrupt as usual (the command's handlers clean up and
return 130) and also starts a watchdog: if the process is still alive :data:`GRACE_S` later (the
interrupt was swallowed by a library that catches ``BaseException``, the main thread is inside a
long compiled kernel that cannot be interrupted, or it was compiling one, where no exception may be
raised: :func:`_handler` then leaves the exit to the watchdog), the watchdog kills the process's
children (a child still drawing a picture would write it into a removed folder, creating it again),
removes the command's staging folders (:func:`register`) and ends the process with status 130. An output folder being swapped into place
(:func:`critical`) is finished first, so the previous output is either kept or wholly replaced.
A staging folder is made inside :func:`deferred`, so that it is registered before Ctrl-C can cut
the command short, and :func:`exit_now` removes every staging folder still registered when the
command ends after Ctrl-C.
"""

from __future__ import annotations

import atexit
import contextlib
import os
import pathlib
import shutil
import signal
import sys
import threading
import time

GRACE_S = 1.0
"""How long after Ctrl-C the command may take to end by itself [s]."""

EXIT_INTERRUPTED = 130

_staging: set = set()
_lock = threading.RLock()
_fired = threading.Event()
_deferring = 0
"""How many :func:`deferred` blocks the main thread is in."""
_finished: int | None = None
"""The command's exit status once its work is complete (:func:`finished`), else None."""


def register(folder: str | os.PathLike) -> None:
    """A staging folder the watchdog removes if it has to end the process."""
    with _lock:
        _staging.add(pathlib.Path(folder))


def unregister(folder: str | os.PathLike) -> None:
    with _lock:
        _staging.discard(pathlib.Path(folder))


def critical():
    """A block the watchdog waits for (a folder swap: two renames that must not be split)."""
    return _lock


def _end_children() -> None:
    """Kills this process's multiprocessing children (background pictures, worker pools) and reaps
    them: a child still writing into a staging folder would create it again once it is removed."""
    import multiprocessing  # lazy: 5 ms, 17 modules: the console script imports this module before its handler is set

    children = multiprocessing.active_children()
    for child in children:
        child.kill()
    for child in children:
        child.join(timeout=GRACE_S)


def _remove_staging() -> None:
    """Removes every registered staging folder (the caller holds the lock)."""
    for folder in list(_staging):
        shutil.rmtree(folder, ignore_errors=True)
    _staging.clear()


def _force_exit() -> None:
    time.sleep(GRACE_S)
    if threading.main_thread().is_alive():
        with _lock:
            _end_children()
            _remove_staging()
            sys.stderr.write("fsv-bench: interrupted\n")
            sys.stderr.flush()
            os._exit(EXIT_INTERRUPTED)


_COMPILERS = (f"{os.sep}llvmlite{os.sep}",)
"""Packages in whose frames an exception must not be raised: LLVM calls back into Python while it
compiles (numba's kernels, on a first run), and an exception raised there is ignored by ctypes and
leaves LLVM's state broken (a segmentation fault followed). Only llvmlite's frames: numba's own
Python code (type inference, dispatch) takes a KeyboardInterrupt like any other."""


def _compiling(frame) -> bool:
    """True when the interrupted frame, or one it was called from, belongs to llvmlite (LLVM is compiling)."""
    while frame is not None:
        if any(part in frame.f_code.co_filename for part in _COMPILERS):
            return True
        frame = frame.f_back
    return False


def _handler(signum, frame):
    if _finished is not None:  # every file is written: Ctrl-C only ends the process, with the command's status
        exit_now(_finished)
    if _fired.is_set():  # a second Ctrl-C: the watchdog already ends the process within GRACE_S
        return
    _fired.set()
    threading.Thread(target=_force_exit, name="interrupt-watchdog", daemon=True).start()
    if _compiling(frame):  # the watchdog ends the process within GRACE_S, staging folders removed
        return
    if _deferring:  # raised where the block ends (deferred)
        return
    raise KeyboardInterrupt


@contextlib.contextmanager
def deferred():
    """A block that Ctrl-C does not cut short: its KeyboardInterrupt is raised where the block ends
    (and at its start, if Ctrl-C came before), so that a folder made and registered inside is
    registered before the interrupt can unwind the command (then :func:`exit_now` removes it). The
    watchdog still ends the process :data:`GRACE_S` after Ctrl-C if the block does not end.

    Raises:
        KeyboardInterrupt: Ctrl-C came before the block or during it.
    """
    global _deferring
    if _fired.is_set():
        raise KeyboardInterrupt
    main = threading.current_thread() is threading.main_thread()
    if main:
        _deferring += 1
    try:
        yield
    finally:
        if main:
            _deferring -= 1
    if _fired.is_set():
        raise KeyboardInterrupt


def _release_multiprocessing() -> None:
    """Runs multiprocessing's finalizers of priority 0 and above, as the interpreter's exit would:
    its named semaphores are unlinked, its queues closed, a manager process shut down. ``os._exit``
    skips them, and the resource tracker (a process of the command's group that outlives it) would
    print "There appear to be 5 leaked semaphore objects" under the interrupted command's line.
    ``_run_finalizers`` is multiprocessing's own exit step (``util._exit_function``)."""
    mp_util = sys.modules.get("multiprocessing.util")
    if mp_util is not None:
        mp_util._run_finalizers(0)


def finished(code: int) -> None:
    """Says that the command's work is complete, with exit status ``code``: a Ctrl-C from now on (in
    the interpreter's teardown, which joins threads and runs the libraries' finalisers for up to a
    second) ends the process at once with ``code``, not with a KeyboardInterrupt raised there (the
    process then died by SIGINT, status -2, without a line)."""
    global _finished
    _finished = int(code)


def exit_now(code: int = EXIT_INTERRUPTED) -> None:
    """Ends the process with ``code`` at once (after flushing the console), skipping the
    interpreter's teardown: for a command that was interrupted and has cleaned up. After Ctrl-C,
    the staging folders still registered (one whose command was cut short before it could remove
    it) are removed first, and multiprocessing's semaphores released (:func:`_release_multiprocessing`)."""
    with _lock:
        if _fired.is_set():
            _remove_staging()
            _release_multiprocessing()
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(code)


def _unraisable(args) -> None:
    """``sys.unraisablehook``: a KeyboardInterrupt raised where Python cannot propagate it (a hook it
    runs around a fork, a finaliser) is dropped without a traceback once Ctrl-C came: the watchdog
    ends the process within :data:`GRACE_S`. Anything else goes to the default hook."""
    if issubclass(args.exc_type, KeyboardInterrupt) and _fired.is_set():
        return
    sys.__unraisablehook__(args)


def _ignore_during_finalisation() -> None:
    """The last exit handler (registered first): after it the interpreter frees its modules, and
    it gives SIGINT back its default action unless it is ignored, so that a Ctrl-C then killed the
    process by the signal (status -2, no line) after the command had written everything."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def install() -> None:
    """Installs the handler (main thread only; elsewhere, e.g. a test runner's thread, it does nothing)."""
    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGINT, _handler)
        sys.unraisablehook = _unraisable
        atexit.register(_ignore_during_finalisation)


def interrupted() -> bool:
    """Whether Ctrl-C arrived (even if a library swallowed its KeyboardInterrupt)."""
    return _fired.is_set()
