"""benchmark.parallel: jobs in this process or a local pool, their progress, and workers that end with their parent."""

import json
import os
import signal
import subprocess
import sys
import textwrap
import time

import pytest
from processes import running

from benchmark.parallel import ONE_CORE_ENV, report_progress, run_jobs


def _square_reporting(x):
    report_progress(x)
    return x * x


def test_in_process_jobs_give_their_results_and_report_their_progress():
    heard = []
    assert sorted(run_jobs(_square_reporting, [1, 2, 3], on_progress=heard.append)) == [(0, 1), (1, 4), (2, 9)]
    assert heard == [1, 2, 3]
    report_progress(5)  # nobody listens any more: nothing happens


JOBS = textwrap.dedent("""
    import json, os, signal, sys, time
    from benchmark.parallel import report_progress, run_jobs

    def square(x):
        report_progress(x)
        return x * x

    def ctrl_c(x):  # what a terminal's Ctrl-C sends to every process of the command's group
        os.kill(os.getpid(), signal.SIGINT)
        time.sleep(0.2)
        return x

    def sleep(x):
        os.write(1, f"{os.getpid()}\\n".encode())  # one write: the two workers' lines never interleave
        time.sleep(60)

    def sleep_or_fail(x):
        if x == 0:
            time.sleep(1)
            raise ValueError("job 0 failed")
        sleep(x)

    class Said:  # writes its file when the interpreter's teardown frees it
        def __init__(self, name):
            self.name = name

        def __del__(self, _open=os.open, _close=os.close, flags=os.O_CREAT | os.O_WRONLY):
            _close(_open(self.name, flags))  # os's functions, bound now: the builtins may be gone by then

    def where(x):  # how the worker was started, and what it was given
        return (os.getppid(), os.environ.get("OPENBLAS_NUM_THREADS"), os.environ.get("NPY_ENABLE_CPU_FEATURES"),
                os.environ.get("FSV_TEST_CHANGED"))

    def numba_state(x):  # a job of __main__: the server imported nothing of it
        return "numba" in sys.modules, "numba.np.arraymath" in sys.modules

    KEPT = []

    def keep(x):
        KEPT.append(Said(f"teardown-{os.getpid()}"))
        time.sleep(0.2)
        return x

    if __name__ == "__main__":
        if sys.argv[1] == "square":
            heard = []
            print(sorted(run_jobs(square, [1, 2, 3, 4], workers=2, on_progress=heard.append)), sorted(heard))
        elif sys.argv[1] == "ctrl-c":
            print(sorted(run_jobs(ctrl_c, [1, 2], workers=2)))
        elif sys.argv[1] == "fail":
            list(run_jobs(sleep_or_fail, [0, 1], workers=2))
        elif sys.argv[1] == "teardown":
            KEPT.append(Said("teardown-parent"))
            print(sorted(run_jobs(keep, [1, 2], workers=2)))
        elif sys.argv[1] == "numba-state":
            import numba_job  # a module that uses numba (tests/test_parallel.py writes it beside this file)
            fn = numba_job.numba_state if sys.argv[2] == "numba-job" else numba_state
            print(json.dumps(sorted(set(r for _, r in run_jobs(fn, [0, 1], workers=2)))))
        elif sys.argv[1] == "lambda":
            list(run_jobs(lambda x: x, [0, 1], workers=2))
        elif sys.argv[1] == "where":
            pools = [sorted(set(r for _, r in run_jobs(where, [0, 1, 2, 3], workers=2)))]
            os.environ["PYTEST_CURRENT_TEST"] = "tests/test_x.py::test_y (call)"  # the moment, not a setting
            pools.append(sorted(set(r for _, r in run_jobs(where, [0, 1, 2, 3], workers=2))))
            os.environ["FSV_TEST_CHANGED"] = "1"
            pools.append(sorted(set(r for _, r in run_jobs(where, [0, 1, 2, 3], workers=2))))
            import multiprocessing
            busy = multiprocessing.get_context("fork").Process(target=time.sleep, args=(30,), daemon=True)
            busy.start()  # a process of this one's runs (a background job): the server cannot be replaced now
            os.environ["FSV_TEST_CHANGED"] = "2"
            pools.append(sorted(set(r for _, r in run_jobs(where, [0, 1, 2, 3], workers=2))))
            busy.kill()
            print(json.dumps({"parent": os.getpid(), "pools": pools}))
        else:
            if sys.argv[1] == "sleep-spawned":  # another library started the fork server: the pool spawns
                import multiprocessing.forkserver
                multiprocessing.forkserver.ensure_running()
            list(run_jobs(sleep, [0, 1], workers=2))
""")


def test_a_pool_gives_every_result_and_hears_the_workers_progress(tmp_path):
    (tmp_path / "jobs.py").write_text(JOBS)
    out = subprocess.run([sys.executable, "jobs.py", "square"], cwd=tmp_path, capture_output=True, text=True,
                         timeout=120, env={**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)})
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "[(0, 1), (1, 4), (2, 9), (3, 16)] [1, 2, 3, 4]"


NUMBA_JOB = textwrap.dedent("""
    import sys

    import numba  # noqa: F401  (what makes this a job that uses numba)

    def numba_state(x):
        return "numba" in sys.modules, "numba.np.arraymath" in sys.modules  # the second: the CPU target readied
""")


@pytest.mark.skipif(sys.platform != "linux", reason="forks its workers from a fork server on Linux only")
@pytest.mark.parametrize("job, expected", [("numba-job", [[True, True]]), ("main-job", [[False, False]])])
def test_the_fork_server_readies_numba_only_for_a_job_that_uses_it(tmp_path, job, expected):
    """A job whose module imports numba gets workers whose numba CPU target the server readied once
    (its registries' modules loaded before the fork); a job of ``__main__``, whose module the server
    does not import, gets workers without numba: its server did not import it (measured: 0.5 s of
    CPU a server)."""
    (tmp_path / "jobs.py").write_text(JOBS)
    (tmp_path / "numba_job.py").write_text(NUMBA_JOB)
    out = subprocess.run([sys.executable, "jobs.py", "numba-state", job], cwd=tmp_path, capture_output=True,
                         text=True, timeout=120, env={**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)})
    assert out.returncode == 0, out.stderr
    assert json.loads(out.stdout) == expected


def test_a_worker_leaves_ctrl_c_to_its_parent_and_says_nothing(tmp_path):
    """The group's SIGINT reaches each worker too: it goes on (the parent, which gets it as well,
    ends the pool), and no worker prints "Process SpawnProcess-1:" and a KeyboardInterrupt."""
    (tmp_path / "jobs.py").write_text(JOBS)
    out = subprocess.run([sys.executable, "jobs.py", "ctrl-c"], cwd=tmp_path, capture_output=True, text=True,
                         timeout=120, env={**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)})
    assert (out.returncode, out.stdout.strip(), out.stderr) == (0, "[(0, 1), (1, 2)]", "")


def test_a_worker_ends_without_the_interpreters_teardown(tmp_path):
    """A worker ends after handing its results back, before the teardown that frees its modules'
    objects (the pool's shutdown waited 0.74 s for it); the parent, the control, is torn down."""
    (tmp_path / "jobs.py").write_text(JOBS)
    out = subprocess.run([sys.executable, "jobs.py", "teardown"], cwd=tmp_path, capture_output=True, text=True,
                         timeout=120, env={**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)})
    assert (out.returncode, out.stdout.strip(), out.stderr) == (0, "[(0, 1), (1, 2)]", "")
    assert sorted(p.name for p in tmp_path.glob("teardown-*")) == ["teardown-parent"]


@pytest.mark.skipif(sys.platform != "linux", reason="forks its workers from a fork server on Linux only")
def test_a_pool_forks_its_workers_from_one_server_with_one_core_each_while_the_environment_stands(tmp_path):
    """Two pools' workers are forked by one fork server (their parent, not the pool's owner), with one
    core's environment and NumPy's baseline, though pytest's ``PYTEST_CURRENT_TEST`` changed between
    them; after the owner changes its environment, the next
    pool's workers come from another server, which sees the change; while a process of the owner's
    runs (a forked background job), the server is not replaced: the workers are spawned, the
    owner's children, and see the change too."""
    (tmp_path / "jobs.py").write_text(JOBS)
    # the owner without one core's settings (a test worker has them: tests/conftest.py): the pool sets them
    owner_env = {k: v for k, v in os.environ.items() if k not in ONE_CORE_ENV}
    out = subprocess.run([sys.executable, "jobs.py", "where"], cwd=tmp_path, capture_output=True, text=True,
                         timeout=120, env={**owner_env, "PYTHONPATH": os.pathsep.join(sys.path)})
    assert out.returncode == 0, out.stderr
    said = json.loads(out.stdout)
    first, second, changed, busy = said["pools"]
    assert len(first) == 1 and first == second, said  # one server, the parent of every worker of both pools
    server, threads, simd, seen = first[0]
    assert server != said["parent"] and (threads, simd, seen) == ("1", " ", None), said
    (other, *rest), = changed
    assert other not in (server, said["parent"]) and rest == ["1", " ", "1"], said
    assert busy == [[said["parent"], "1", " ", "2"]], said


@pytest.mark.skipif(sys.platform != "linux", reason="reads /proc")
@pytest.mark.parametrize("mode", ["sleep", "sleep-spawned"], ids=["forked", "spawned"])
def test_no_worker_outlives_its_parent_killed_by_sigkill(tmp_path, mode):
    (tmp_path / "jobs.py").write_text(JOBS)
    parent = subprocess.Popen([sys.executable, "jobs.py", mode], cwd=tmp_path, stdout=subprocess.PIPE, text=True,
                              env={**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)})
    try:
        workers = [int(parent.stdout.readline()) for _ in range(2)]
    finally:
        os.kill(parent.pid, signal.SIGKILL)
        parent.wait(timeout=10)
    deadline = time.monotonic() + 10
    alive = workers
    while alive and time.monotonic() < deadline:
        time.sleep(0.2)
        alive = [p for p in workers if running(p)]
    assert not alive, f"workers {alive} outlived their parent"


def _fail_or_sleep(x):
    if x == 0:
        raise ValueError("job 0 failed")
    time.sleep(60)
    return x


def _live_workers() -> list:
    """This process's worker processes still running (not zombies), read from /proc: its spawned
    children and the children of its fork server (the resource tracker and the fork server, which
    multiprocessing keeps for the process's lifetime, are not workers)."""
    import multiprocessing.forkserver

    me, alive = os.getpid(), []
    server = multiprocessing.forkserver._forkserver._forkserver_pid
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            try:
                with open(f"/proc/{entry}/stat") as fh:
                    fields = fh.read().rsplit(")", 1)[1].split()
                with open(f"/proc/{entry}/cmdline", "rb") as fh:
                    command = fh.read()
            except OSError:
                continue
            if fields[0] == "Z":
                continue
            if (int(fields[1]) == me and b"spawn_main" in command) or (server and int(fields[1]) == server):
                alive.append(int(entry))
    return alive


@pytest.mark.skipif(sys.platform != "linux", reason="reads /proc")
@pytest.mark.parametrize("fn, jobs, error, needle", [
    (lambda x: x, [1, 2], "UnpicklableJob", "the function given to the worker processes cannot be pickled"),
    (_square_reporting, [1, lambda: 0, 3], "PicklingError", "Can't pickle"),
    (_fail_or_sleep, [1, 0], "ValueError", "job 0 failed"),
], ids=["lambda", "unpicklable-job", "failing-job"])
def test_on_any_error_the_pool_ends_its_workers_and_the_call_raises_at_once(fn, jobs, error, needle):
    import multiprocessing

    before = set(multiprocessing.active_children())  # children of earlier tests in this process are not the call's
    workers_before = set(_live_workers())
    t0 = time.monotonic()
    with pytest.raises(Exception) as caught:
        list(run_jobs(fn, jobs, workers=2))
    assert type(caught.value).__name__ == error and needle in str(caught.value)
    assert len(str(caught.value).splitlines()) == 1
    assert time.monotonic() - t0 < 10
    assert not set(multiprocessing.active_children()) - before
    assert not set(_live_workers()) - workers_before, "a worker outlived the call"


@pytest.mark.skipif(sys.platform != "linux", reason="reads /proc")
@pytest.mark.parametrize("mode, needle", [("fail", "ValueError: job 0 failed"),
                                          ("lambda", "UnpicklableJob: the function given to the worker processes")])
def test_a_command_whose_job_fails_ends_in_seconds_and_leaves_no_worker(tmp_path, mode, needle):
    (tmp_path / "jobs.py").write_text(JOBS)
    t0 = time.monotonic()
    parent = subprocess.Popen([sys.executable, "jobs.py", mode], cwd=tmp_path, stdout=subprocess.PIPE,
                              stderr=subprocess.PIPE, text=True, env={**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)})
    try:
        out, err = parent.communicate(timeout=30)
    finally:
        parent.kill()
    assert parent.returncode == 1 and needle in err
    assert time.monotonic() - t0 < 20
    sleepers = [int(line) for line in out.split()]
    assert len(sleepers) == (1 if mode == "fail" else 0)
    deadline = time.monotonic() + 5
    while any(running(p) for p in sleepers) and time.monotonic() < deadline:
        time.sleep(0.2)
    assert not [p for p in sleepers if running(p)], "a worker outlived the command"
