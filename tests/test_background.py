"""benchmark.background: jobs beside the caller, their failures reported at the end."""

import multiprocessing.util
import os
import signal
import sys
import time

import numpy as np
import pytest
from processes import running

from benchmark import interrupt
from benchmark.background import Background
from benchmark.errors import BenchmarkError


def _write(path, text):
    with open(path, "w") as fh:
        fh.write(text)


def _fail(message):
    raise ValueError(message)


def test_a_forked_child_and_a_thread_both_finish_before_wait_returns(tmp_path):
    bg = Background()
    assert bg.enabled
    bg.process("child", _write, tmp_path / "a.txt", "from the child")
    bg.thread("thread", _write, tmp_path / "b.txt", "from the thread")
    bg.wait()
    assert (tmp_path / "a.txt").read_text() == "from the child"
    assert (tmp_path / "b.txt").read_text() == "from the thread"


def test_the_child_sees_the_parents_memory_as_it_was_at_the_fork(tmp_path):
    data = {"value": 1}
    bg = Background()
    bg.process("child", lambda: _write(tmp_path / "v.txt", str(data["value"])))  # no pickling: a closure works
    data["value"] = 2  # after the fork: not seen by the child
    bg.wait()
    assert (tmp_path / "v.txt").read_text() == "1"


def test_failures_are_named_when_waiting(tmp_path, capfd):
    bg = Background()
    bg.process("picture", _fail, "no picture")
    bg.thread("archive", _fail, "no archive")
    bg.process("fine", _write, tmp_path / "ok.txt", "ok")
    with pytest.raises(BenchmarkError, match=r"picture \(exit code 1\).*archive \(ValueError: no archive\)"):
        bg.wait()
    assert "no picture" in capfd.readouterr().err  # the child's traceback
    assert (tmp_path / "ok.txt").read_text() == "ok"  # the others still ran
    bg.wait()  # nothing left


def test_disabled_runs_every_job_at_once_and_raises_at_once(tmp_path):
    bg = Background(enabled=False)
    bg.process("child", _write, tmp_path / "a.txt", "a")
    assert (tmp_path / "a.txt").read_text() == "a"
    with pytest.raises(ValueError, match="now"):
        bg.thread("thread", _fail, "now")


def test_cancel_stops_a_running_child():
    bg = Background()
    bg.process("sleeper", time.sleep, 60)
    t0 = time.perf_counter()
    bg.cancel()
    assert time.perf_counter() - t0 < 10
    bg.wait()  # cancelled jobs are forgotten


@pytest.mark.parametrize("start", ["process", "fork"])
def test_cancel_at_once_stops_a_child_whose_parent_has_a_sigterm_handler_that_returns(start):
    """A library in the parent (Ray's driver) may handle SIGTERM and return; a child forked just
    before cancel() must not run that handler instead of ending (it did: cancel() then waited the
    child's whole 60 s, seen when a Ray test had run earlier in the same pytest worker)."""
    old = signal.signal(signal.SIGTERM, lambda signum, frame: None)
    try:
        for _ in range(3):  # the race is at the child's first instructions: cancel() comes at once
            bg = Background()
            getattr(bg, start)("sleeper", time.sleep, 60)
            t0 = time.perf_counter()
            bg.cancel()
            assert time.perf_counter() - t0 < 10
    finally:
        signal.signal(signal.SIGTERM, old)


def test_a_preloaded_module_is_imported_before_the_fork(tmp_path):
    bg = Background()
    bg.preload("json", "no_such_module_here")  # a failing import is left to the child
    bg.process("child", lambda: _write(tmp_path / "pid.txt", str(os.getpid())))
    bg.wait()
    assert int((tmp_path / "pid.txt").read_text()) != os.getpid()


def _import_stopped_by_ctrl_c():
    try:
        raise KeyboardInterrupt
    except KeyboardInterrupt:
        raise ImportError("initialization failed")  # what a compiled module's interrupted import raises


def test_a_child_stopped_by_ctrl_c_inside_an_import_exits_130_without_a_traceback(capfd):
    import multiprocessing

    from benchmark.background import _child, _from_interrupt

    try:
        _import_stopped_by_ctrl_c()
    except ImportError as e:
        assert _from_interrupt(e)
    assert not _from_interrupt(ImportError("no such module")) and not _from_interrupt(None)
    for fn, code in ((_import_stopped_by_ctrl_c, 130), (_raise_value_error, 1)):
        p = multiprocessing.get_context("fork").Process(target=_child, args=(fn, (), {}))
        p.start()
        p.join(30)
        assert p.exitcode == code
    err = capfd.readouterr().err
    assert "ImportError" not in err and "ValueError: planted" in err  # only the real failure is reported


def _raise_value_error():
    raise ValueError("planted")


def _interrupt_lost_in_a_library():
    """Ctrl-C (the command's handler, as the console script installs it) lands in a library's
    compiled code, which replaces the KeyboardInterrupt with an error of its own, unchained."""
    interrupt.install()
    lost = False
    try:
        os.kill(os.getpid(), signal.SIGINT)
        time.sleep(10)
    except KeyboardInterrupt:
        lost = True
    if lost:
        raise ValueError("Invalid bounding box")  # what matplotlib's Agg renderer raised, once


def test_a_child_whose_library_replaced_ctrl_cs_interrupt_exits_130_without_a_traceback(capfd):
    """Seen in test_interrupt (the picture of Fig. 5 being drawn when the signal came): the child
    printed matplotlib's traceback and the command's Ctrl-C was no longer one line."""
    import multiprocessing

    from benchmark.background import _child

    p = multiprocessing.get_context("fork").Process(target=_child, args=(_interrupt_lost_in_a_library, (), {}))
    p.start()
    p.join(30)
    assert p.exitcode == 130
    assert "Traceback" not in capfd.readouterr().err


class _CtrlCAtTheFork:
    """While alive, every child multiprocessing forks is sent SIGINT in its start-up code, before
    the job's function: a Ctrl-C to the process group that lands while a picture's child starts."""

    def __init__(self):
        multiprocessing.util.register_after_fork(self, lambda _: os.kill(os.getpid(), signal.SIGINT))


@pytest.mark.parametrize("start", ["process", "fork"])
def test_ctrl_c_while_a_child_starts_ends_it_with_130_and_no_traceback(start, capfd):
    """Seen in test_interrupt: "Process Fig. 4: Traceback ... KeyboardInterrupt" printed by
    multiprocessing's start-up code, where the command's inherited handler raised it."""
    previous = signal.getsignal(signal.SIGINT), sys.unraisablehook
    interrupt.install()  # what the console script does; the child inherits it
    try:
        ctrl_c = _CtrlCAtTheFork()
        bg = Background()
        getattr(bg, start)("Fig. 4", time.sleep, 30)
        del ctrl_c
        job = bg._jobs[0][1]
        process = getattr(job, "process", job)
        process.join(20)
        assert process.exitcode == 130  # was 1, after the traceback
        bg.cancel()
    finally:
        signal.signal(signal.SIGINT, previous[0])
        sys.unraisablehook = previous[1]
    err = capfd.readouterr().err
    assert "Traceback" not in err and "KeyboardInterrupt" not in err, err


def test_cancel_stops_a_child_whose_parent_handles_sigterm():
    """A parent with a SIGTERM handler of its own (Ray's driver installs one) forks children that
    would inherit it and sleep on through ``terminate``: the child restores the default first."""
    import signal

    previous = signal.signal(signal.SIGTERM, lambda signum, frame: None)
    try:
        bg = Background()
        bg.process("sleeper", time.sleep, 60)
        time.sleep(0.5)  # the child is asleep when the signal comes
        t0 = time.perf_counter()
        bg.cancel()
        assert time.perf_counter() - t0 < 10
    finally:
        signal.signal(signal.SIGTERM, previous)


def _fill(array, value):
    array[...] = value
    return {"sum": int(array.sum())}


def _planted(kind):
    if kind == "benchmark":
        raise BenchmarkError("planted failure\nover two lines")
    raise KeyError("a bug")


def test_a_forked_job_returns_its_value_and_writes_shared_memory_the_caller_sees():
    from benchmark.background import shared_empty

    bg = Background()
    shared = shared_empty((3, 4, 5), "uint16")
    private = np.zeros((3, 4, 5), dtype=np.uint16)
    job = bg.fork("fill", _fill, shared, 7)
    job_private = bg.fork("private", _fill, private, 7)
    bg.wait()
    assert job.result() == {"sum": 7 * 60} and job_private.result() == {"sum": 7 * 60}
    assert shared.dtype == np.uint16 and np.all(shared == 7)  # written by the child, seen here
    assert np.all(private == 0)  # ordinary memory: the child wrote its own copy


def test_a_thread_job_returns_its_value():
    bg = Background()
    job = bg.thread("sum", sum, [1, 2, 3])
    bg.wait()
    assert job.result() == 6


def test_a_forked_jobs_failure_is_one_line_and_a_thread_waiting_for_it_is_not_reported_again(capfd):
    from benchmark.background import JobFailed

    bg = Background()
    job = bg.fork("colour", _planted, "benchmark")
    waiting = bg.thread("episode file", lambda: job.result())
    with pytest.raises(BenchmarkError) as info:
        bg.wait()
    assert str(info.value) == "background work failed: colour (BenchmarkError: planted failure over two lines)"
    assert "Traceback" not in capfd.readouterr().err  # the command's own error: one line, no traceback
    with pytest.raises(JobFailed, match="colour failed: BenchmarkError: planted"):
        waiting.result()
    bug = bg.fork("colour", _planted, "bug")
    with pytest.raises(BenchmarkError, match=r"^background work failed: colour \(KeyError: 'a bug'\)$"):
        bg.wait()
    assert "Traceback" in capfd.readouterr().err and bug.failure() == "KeyError: 'a bug'"  # a bug shows where


def test_cancel_ends_a_forked_job_and_wakes_a_thread_waiting_for_it():
    import multiprocessing

    bg = Background()
    job = bg.fork("sleeper", time.sleep, 60)
    waiting = bg.thread("waiting", lambda: job.result())
    time.sleep(0.3)
    t0 = time.perf_counter()
    bg.cancel()
    assert time.perf_counter() - t0 < 10
    assert not job.process.is_alive() and job.process.exitcode == -15  # SIGTERM
    assert not waiting.thread.is_alive() and "without a result" in job.failure()
    assert job.process not in multiprocessing.active_children()


def test_disabled_forks_at_once_and_returns_the_value():
    bg = Background(enabled=False)
    array = np.zeros(4)
    assert bg.fork("fill", _fill, array, 2).result() == {"sum": 8} and np.all(array == 2)  # the caller's own array
    assert bg.thread("sum", sum, [1, 2]).result() == 3


_PARENT = """
import sys, time
from benchmark import interrupt
from benchmark.background import Background
job = Background().fork("sleeper", time.sleep, 60)
print(job.process.pid, flush=True)
time.sleep(60)
"""


@pytest.mark.skipif(sys.platform != "linux", reason="the parent-death signal is Linux's")
def test_a_forked_job_dies_with_a_killed_parent():
    """SIGKILL gives the parent no chance to end its children: the child ends itself."""
    import signal
    import subprocess

    parent = subprocess.Popen([sys.executable, "-c", _PARENT], stdout=subprocess.PIPE,
                              env={**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)})
    child = int(parent.stdout.readline())
    time.sleep(0.3)
    os.kill(child, 0)  # alive
    parent.send_signal(signal.SIGKILL)
    parent.wait(30)
    deadline = time.perf_counter() + 10
    while running(child) and time.perf_counter() < deadline:  # a zombie has ended (init reaps it up to 2 s later)
        time.sleep(0.05)
    assert not running(child), "the forked job outlived its killed parent"


def _rows(done, shared, gate: int | None = None, fail_at: int | None = None, stop_at: int | None = None) -> float:
    """A streamed job: row k of ``shared`` set to k + 1, then ``done(k + 1)``; after row 0 it waits
    for a byte on the file descriptor ``gate`` (the test's go-ahead)."""
    for k in range(shared.shape[0]):
        if k == fail_at:
            raise BenchmarkError("planted failure at row 2")
        if k == stop_at:
            break
        shared[k] = k + 1
        done(k + 1)
        if k == 0 and gate is not None:
            os.read(gate, 1)
    return float(shared.sum())


def _streamed(**kwargs):
    """``(background, job, shared, go)``: a streamed job of :func:`_rows` over 4 rows, blocked after
    row 0 until ``go()`` (or 10 s, so that a broken stream fails its assertions instead of hanging)."""
    import threading

    from benchmark.background import shared_empty

    bg = Background()
    shared = shared_empty((4, 1000), "float32")
    read, write = os.pipe()
    job = bg.stream("rows", _rows, shared, read, **kwargs)
    os.close(read)
    lock = threading.Lock()

    def go():
        with lock:
            if not timer.finished.is_set():
                timer.cancel()
                os.write(write, b"x")

    timer = threading.Timer(10.0, go)
    timer.daemon = True
    timer.start()
    return bg, job, shared, go


def test_a_streamed_jobs_first_items_reach_the_caller_while_the_child_has_not_made_the_next():
    bg, job, shared, go = _streamed()
    waiting = bg.thread("whole", job.result)  # a second reader of the child's pipe, as the episode file's thread is
    job.wait_for(1)
    assert np.all(shared[0] == 1) and np.all(shared[1:] == 0)  # row 1 waits for the go-ahead
    go()
    job.wait_for(3)
    assert np.all(shared[:3] == np.arange(1, 4)[:, None])
    job.wait_for(4)
    job.wait_for(2)  # already there
    bg.wait()
    assert job.result() == waiting.result() == 1000.0 * (1 + 2 + 3 + 4)


def test_a_streamed_job_waited_for_in_a_process_forked_since_fails_there_instead_of_hanging():
    bg, job, shared, go = _streamed()
    job.wait_for(1)
    assert Background().fork("picture", job.wait_for, 1).result() is None  # what was there at the fork is there
    assert "waited for in a process forked from the one that started it" in Background().fork(
        "picture", job.wait_for, 4).failure()
    go()
    job.wait_for(4)
    bg.wait()


def test_a_streamed_job_that_fails_or_ends_short_raises_where_the_caller_waits_for_its_items():
    from benchmark.background import JobFailed

    bg, job, shared, go = _streamed(fail_at=2)
    job.wait_for(1)
    go()
    with pytest.raises(JobFailed, match=r"^rows failed: BenchmarkError: planted failure at row 2$"):
        job.wait_for(3)
    job.wait_for(2)  # what came before the failure is there
    with pytest.raises(BenchmarkError, match=r"background work failed: rows \(BenchmarkError: planted"):
        bg.wait()
    bg, job, shared, go = _streamed(stop_at=2)
    go()
    with pytest.raises(JobFailed, match=r"^rows failed: it ended after 2 items, not 4$"):
        job.wait_for(4)
    bg.cancel()


def test_disabled_streams_at_once():
    bg = Background(enabled=False)
    array = np.zeros((3, 2))
    job = bg.stream("rows", _rows, array)
    job.wait_for(3)
    assert job.result() == 12.0 and np.all(array == [[1], [2], [3]])
