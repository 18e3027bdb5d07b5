"""Work over episodes in this process, a local process pool, or a Ray cluster, with the same results.

    for i, result in run_jobs(fn, jobs, workers=2): ...          # local pool (worker processes)
    for i, result in run_jobs(fn, jobs, ray_address="host:port"): # Ray tasks

``fn`` must be a module-level function (it is pickled to the workers; one that cannot be is
refused before any worker starts, :class:`UnpicklableJob`); on any error, the pool's workers are
ended before the error goes on. Results arrive as they are done, with the index of their job, so callers can keep the jobs' order. The Ray path needs the
``ray`` extra (``pip install 'fsv-bench[ray]'``); a bad address fails within seconds
(:func:`check_ray_address`).
"""

from __future__ import annotations

import atexit
import multiprocessing
import multiprocessing.forkserver
import os
import pickle
import queue
import signal
import socket
import sys
import threading
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from typing import Callable, Iterator

from benchmark import collector
from benchmark.errors import BenchmarkError, DatasetError
from benchmark.simd import NUMPY_BASELINE_ENV


class RayUnavailable(DatasetError):
    """A Ray address was given but Ray is not installed."""


class RayAddressError(DatasetError):
    """A Ray address that is malformed or where nothing answers."""


class UnpicklableJob(BenchmarkError, ValueError):
    """The function or a job given to the local pool cannot be sent to a worker process (pickled)."""


ONE_CORE_ENV = {"LP_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "NUMBA_NUM_THREADS": "1"}
"""Environment of a local worker process: one core's work each. The numerical libraries (and
Mesa's llvmpipe, where a worker draws with MuJoCo's GL renderer) would otherwise start a thread per
core in every worker, and the workers would compete for the cores the pool divides among them."""


def one_core_worker() -> None:
    """Limits this process's native thread pools to one thread (:data:`ONE_CORE_ENV`)."""

    os.environ.update(ONE_CORE_ENV)


_REPORT: Callable | None = None
"""Where :func:`report_progress` sends its counts in this process (None: nowhere)."""


def report_progress(count: int = 1) -> None:
    """Reports ``count`` units of work done (e.g. tracked frames) to the caller of :func:`run_jobs`.

    Called by a job's function anywhere: in the calling process, in a local worker (through a queue)
    or on Ray (dropped); it costs nothing when nobody listens.
    """
    if _REPORT is not None:
        _REPORT(count)


def _worker(progress_queue) -> None:
    """Local worker initializer: one core's work, :func:`report_progress` to the parent's queue, and
    the worker ends when its parent dies (even by SIGKILL, which no cleanup code sees): it waits on
    multiprocessing's sentinel of the parent, a pipe whose other end the parent holds, so that a
    worker forked by the fork server (whose process parent is the server) ends with the pool's
    owner too. Ctrl-C, which a terminal sends to the whole process group, is ignored here: the
    parent takes it and ends its workers (a worker's own KeyboardInterrupt would print
    "Process SpawnProcess-1:" and a traceback above the command's one line)."""

    global _REPORT
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    one_core_worker()
    collector.tune()  # a spawned worker's (a forked one has its server's)
    _REPORT = progress_queue.put if progress_queue is not None else None
    atexit.register(_end_without_teardown)
    parent = multiprocessing.parent_process()

    def watch():
        parent.join()
        os._exit(1)

    threading.Thread(target=watch, name="watch-parent", daemon=True).start()


def _end_without_teardown() -> None:
    """A local worker's last exit handler (run first): the worker has handed every result back and
    multiprocessing's own exit step has run (``BaseProcess._bootstrap``), so it ends here, before the
    interpreter's teardown, for which the pool's shutdown would wait (measured: 0.74 s of an
    ``evaluate(workers=2)``'s 3.3 s; finalisers of NumPy, numba, MuJoCo, SciPy and pandas)."""
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(0)


def run_jobs(fn: Callable, jobs: list, *, workers: int = 1, ray_address: str | None = None,
             on_progress: Callable[[int], None] | None = None) -> Iterator[tuple]:
    """Yields ``(index, fn(jobs[index]))`` for every job, in the order they finish.

    Args:
        fn: A module-level function of one job.
        jobs: The jobs.
        workers: Local worker processes (1: in this process); ignored with ``ray_address``. Local
            workers start fresh (:func:`pool_context`: forked from a fork server that has only
            imported modules, or spawned; no forked torch or OpenGL state), use one core each and
            end with this process.
        ray_address: A Ray cluster's address ("auto", "host:port" or "ray://host:port").
        on_progress: Called in this process with the counts the jobs report
            (:func:`report_progress`); not on Ray.
    """
    global _REPORT
    if ray_address is not None:
        yield from _ray(fn, jobs, ray_address)
    elif workers == 1:
        saved, _REPORT = _REPORT, on_progress
        try:
            for i, job in enumerate(jobs):
                yield i, fn(job)
        finally:
            _REPORT = saved
    else:
        yield from _pool(fn, jobs, workers, on_progress)


def check_picklable(fn: Callable, jobs: list) -> None:
    """Raises :class:`UnpicklableJob` (one line) unless ``fn`` and the first job can be sent to a
    worker process: a lambda, a nested function or an object holding one cannot."""
    for what, obj in (("the function", fn), ("the first job", jobs[0] if jobs else None)):
        try:
            pickle.dumps(obj)
        except Exception as e:  # PicklingError, or the TypeError/AttributeError of an object that refuses
            line = str(e).splitlines()[0] if str(e) else type(e).__name__
            raise UnpicklableJob(f"{what} given to the worker processes cannot be pickled ({line}); give a function "
                                 "defined at the top level of an importable module, or use one worker") from None


def _stop(pool, processes: list) -> None:
    """Shuts ``pool`` down at once and ends its worker processes (``processes``, taken before the
    shutdown forgets them): none outlives an error.

    The pool's manager thread joins the same processes; it is waited for last, so that a process
    it reaped first (whose exit this thread's join then cannot see) is recorded as ended before
    the error goes on."""
    manager = getattr(pool, "_executor_manager_thread", None)
    pool.shutdown(wait=False, cancel_futures=True)
    for p in processes:
        p.terminate()
    for p in processes:
        p.join(timeout=5.0)
        if p.is_alive():
            p.kill()
            p.join(timeout=5.0)
    if manager is not None:
        manager.join(timeout=5.0)


SERVER_SETUP = "benchmark.pool_server"
"""The module the fork server imports first (:func:`pool_context`): it sets :data:`ONE_CORE_ENV` in
the server's environment before any numerical library loads there."""

SERVER_READY = "benchmark.pool_ready"
"""The module the fork server imports last, after the job's: it makes numba's CPU target ready once
for every worker where the job's module uses numba."""

_server_env: dict | None = None
"""This process's environment when it started the fork server, less :data:`MOMENTARY_ENV` (None: it
has not)."""

MOMENTARY_ENV = frozenset({"PYTEST_CURRENT_TEST"})
"""Variables that name the moment, not a setting, left out when the environment is compared: pytest
sets ``PYTEST_CURRENT_TEST`` to the running test at each of its phases (for pytest's own use; no
library reads it), so every pool of a test session's would otherwise start another server."""


def _settings_env() -> dict:
    """This process's environment less :data:`MOMENTARY_ENV`."""
    return {k: v for k, v in os.environ.items() if k not in MOMENTARY_ENV}


def pool_context(fn: Callable) -> multiprocessing.context.BaseContext:
    """How a local pool starts its workers: forked by this process's fork server where it can be,
    else spawned.

    A spawned worker starts an interpreter and imports NumPy, SciPy, MuJoCo, numba and the job's
    module again (about 1 s of CPU a worker, measured); the fork server (Linux) imports them once,
    with :data:`ONE_CORE_ENV` (:data:`SERVER_SETUP`; numba readied where the job uses it:
    :data:`SERVER_READY`), and forks each worker from itself. It is
    started by this process's first pool, with ``fn``'s module preloaded, and serves its later pools
    while the process's environment is the one it started with, :data:`MOMENTARY_ENV` aside (a
    worker must see this process's: the libraries the server loaded read some of it when they
    loaded). After a change, the next pool stops the server and starts another with the environment
    of now, unless a process of this one's is running (one forked from it holds the server's "alive"
    pipe, and the server would not end before it): that pool's workers are spawned. Another platform
    (macOS's frameworks are not safe to fork) or a fork server that another library started (its
    preloads and environment are not known) gives spawned workers too. A forked worker is the same program in a fresh state as a
    spawned one: the results do not depend on which (``tests/test_parallel.py``).
    """
    global _server_env
    spawn = multiprocessing.get_context("spawn")
    if not sys.platform.startswith("linux") or "forkserver" not in multiprocessing.get_all_start_methods():
        return spawn
    server = multiprocessing.forkserver._forkserver
    if _server_env is not None and _settings_env() != _server_env:
        if multiprocessing.active_children():
            return spawn
        server._stop()  # multiprocessing's own stop: the server ends once no process holds its pipe
        _server_env = None
    if _server_env is None:
        if server._forkserver_pid is not None:
            return spawn
        job = [fn.__module__] if fn.__module__ not in ("__main__", __name__) else []
        preload = [SERVER_SETUP, *job, SERVER_READY]
        server.set_forkserver_preload(preload)
        server.ensure_running()
        _server_env = _settings_env()
    return multiprocessing.get_context("forkserver")


def _pool(fn: Callable, jobs: list, workers: int, on_progress) -> Iterator[tuple]:
    check_picklable(fn, jobs)
    ctx = pool_context(fn)
    manager = ctx.Manager() if on_progress is not None else None
    heard = manager.Queue() if manager is not None else None

    def drain():
        while heard is not None:
            try:
                on_progress(heard.get_nowait())
            except queue.Empty:
                return

    pool = ProcessPoolExecutor(max_workers=workers, mp_context=ctx, initializer=_worker, initargs=(heard,))
    try:
        futures = {pool.submit(fn, job): i for i, job in enumerate(jobs)}
        pending = set(futures)
        while pending:
            finished, pending = wait(pending, timeout=0.2, return_when=FIRST_COMPLETED)
            drain()
            for f in finished:
                yield futures[f], f.result()
    except BaseException:
        _stop(pool, list((getattr(pool, "_processes", None) or {}).values()))
        if manager is not None:
            manager.shutdown()
        raise
    pool.shutdown(wait=True)
    if manager is not None:
        drain()
        manager.shutdown()


def _ray(fn: Callable, jobs: list, address: str) -> Iterator[tuple]:
    check_ray_address(address)
    import ray  # lazy: optional Ray (0.3 s)

    host = (address[len("ray://"):] if address.startswith("ray://") else address).rpartition(":")[0]
    local = {"_node_ip_address": "127.0.0.1"} if host in ("127.0.0.1", "localhost") else {}  # stay on loopback
    # the job's workers run NumPy at its baseline as this process does (benchmark/__init__.py)
    ray.init(address=address, ignore_reinit_error=True, log_to_driver=False,
             runtime_env={"env_vars": dict(NUMPY_BASELINE_ENV)}, **local)
    remote = ray.remote(fn)
    refs = {remote.remote(job): i for i, job in enumerate(jobs)}
    pending = list(refs)
    try:
        while pending:
            ready, pending = ray.wait(pending, num_returns=1)
            yield refs[ready[0]], ray.get(ready[0])
    except BaseException:
        for r in pending:
            ray.cancel(r)
        raise


RAY_CONNECT_TIMEOUT_S = 5.0
"""How long the check of a Ray address waits for a connection and for the server's first answer [s]:
a cluster's head node answers at once, while Ray's own client retries for minutes."""

_HTTP2_PREFACE = b"PRI * HTTP/2.0\r\n\r\nSM\r\n\r\n" + bytes([0, 0, 0, 4, 0, 0, 0, 0, 0])
"""An HTTP/2 client's connection preface and an empty SETTINGS frame: a gRPC server (a Ray
cluster's GCS, or its client server behind ``ray://``) answers with a SETTINGS frame of its own."""


def check_ray_address(address: str) -> None:
    """Fails within seconds, before any work, unless a Ray cluster answers at ``address``.

    ``"auto"`` is resolved as Ray resolves it (``RAY_ADDRESS``, or the cluster ``ray start`` started
    on this machine); ``host:port`` and ``ray://host:port`` are connected to and must answer an
    HTTP/2 handshake as Ray's gRPC servers do, so that another service on that port is refused at
    once instead of Ray retrying for minutes.

    Raises:
        RayUnavailable: Ray is not installed.
        RayAddressError: Naming the address when it is malformed, nothing answers there, what
            answers is not a Ray cluster, or ``auto`` finds no cluster.
    """

    try:
        import ray  # lazy: optional Ray (0.3 s)  # noqa: F401
    except ImportError as e:
        raise RayUnavailable(f"--ray-address {address!r} needs Ray, which is not installed: pip install 'fsv-bench[ray]' "
                             "(or run without --ray-address to use the local process pool)") from e
    shown = address
    if address == "auto":
        from ray._private.services import get_ray_address_from_environment  # lazy: optional Ray (0.3 s)

        try:
            address = get_ray_address_from_environment("auto", None) or "auto"
        except ConnectionError:  # Ray's own word for "no cluster found"
            address = "auto"
        if address == "auto":
            raise RayAddressError("--ray-address auto: no Ray cluster runs on this machine; start one with "
                                  "`ray start --head` or run without --ray-address to use the local process pool")
    hostport = address[len("ray://"):] if address.startswith("ray://") else address
    host, _, port = hostport.rpartition(":")
    if not host or not port.isdigit():
        raise RayAddressError(f"--ray-address {shown!r}: expected 'auto', 'host:port' or 'ray://host:port'")
    try:
        with socket.create_connection((host, int(port)), timeout=RAY_CONNECT_TIMEOUT_S) as sock:
            sock.sendall(_HTTP2_PREFACE)
            answer = b""
            while len(answer) < 9:
                chunk = sock.recv(9 - len(answer))
                if not chunk:
                    break
                answer += chunk
    except socket.timeout:
        answer = b""
    except OSError as e:
        raise RayAddressError(f"--ray-address {shown!r}: no Ray cluster answers there ({e}); start one with "
                              "`ray start --head` or run without --ray-address to use the local process pool") from e
    if len(answer) < 9 or answer[3] != 4:
        raise RayAddressError(f"--ray-address {shown!r}: something listens there but it is not a Ray cluster (no gRPC "
                              f"answer within {RAY_CONNECT_TIMEOUT_S:g} s); give the address `ray start --head` printed")
