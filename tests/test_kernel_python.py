"""tests/kernel_python.py: scripts run as ``python -c`` would, in one kept interpreter per environment;
and what tests/conftest.py hands an xdist worker, and how a worker ends."""

import atexit
import json
import os
import pathlib
import types

import pytest
from conftest import (
    UNIT_SECONDS,
    one_core_each,
    one_worker_per_core,
    pytest_unconfigure,
    report_unit,
    unit_seconds,
    unit_seconds_json,
    worker_unit,
)
from kernel_python import KernelPythons, ScriptFailed

_SHOW = """
import os, sys
print(os.getpid(), os.environ.get("OPENBLAS_CORETYPE"), __name__, *sys.argv[1:])
"""


@pytest.fixture
def pythons():
    p = KernelPythons()
    yield p
    p.close()


def test_a_script_prints_its_argv_under_its_environment_and_the_interpreter_is_kept(pythons):
    first = pythons.run(_SHOW, "a", 2, env={"OPENBLAS_CORETYPE": "Haswell"}).split()
    again = pythons.run(_SHOW, env={"OPENBLAS_CORETYPE": "Haswell"}).split()
    other = pythons.run(_SHOW, env={"OPENBLAS_CORETYPE": "Sandybridge"}).split()
    assert first[1:] == ["Haswell", "__main__", "a", "2"] and again[1:] == ["Haswell", "__main__"]
    assert first[0] == again[0] != other[0] and other[1] == "Sandybridge"


def test_output_written_to_fd_1_by_c_code_does_not_reach_the_reply(pythons):
    out = pythons.run("import os\nos.write(1, b'from C\\n')\nprint('from Python')", env={})
    assert out == "from Python\n"


def test_a_failing_script_raises_with_its_traceback_and_the_interpreter_goes_on(pythons):
    with pytest.raises(ScriptFailed, match=r"(?s)<script>\", line 2.*ZeroDivisionError"):
        pythons.run("x = 1\n1 / 0", env={})
    with pytest.raises(ScriptFailed, match="SystemExit: 3"):
        pythons.run("import sys\nsys.exit(3)", env={})
    assert pythons.run("import sys\nsys.exit(0)", env={}) == ""
    assert pythons.run("print(6 * 7)", env={}) == "42\n"


def test_a_script_that_hangs_is_stopped_at_its_timeout(pythons):
    with pytest.raises(ScriptFailed, match="no answer within 0.5 s"):
        pythons.run("import time\ntime.sleep(30)", env={}, timeout_s=0.5)


def test_a_worker_is_handed_a_file_or_the_tests_of_a_shared_fixture(request):
    """Under ``-n`` (pyproject's ``--dist loadgroup``) xdist hands a worker a whole test file, or
    every test that uses a fixture of ``SHARED_ON_ONE_WORKER``, and marks each test's id with its
    unit. pytest 9.2 builds ids another way and xdist 3.8's mark is silently lost (every test its
    own unit: module fixtures made on both workers); requirements.lock keeps pytest 9.1."""
    if not getattr(request.config.option, "loadgroup", False):
        pytest.skip("not run by an xdist worker with --dist loadgroup")
    for item in request.session.items:
        assert item.nodeid.endswith("@" + worker_unit(item)), item.nodeid
    assert request.node.nodeid.endswith("@test_kernel_python")
    kernel_tests = [i.nodeid for i in request.session.items if "kernel_python" in i.fixturenames]
    assert all(i.endswith("@openblas-kernels") for i in kernel_tests), kernel_tests


def test_the_units_are_handed_out_longest_first(request):
    """The session's tests come unit by unit (each unit's tests together), the units longest first
    (conftest's ``UNIT_SECONDS``, from tests/unit_seconds.json), and pyproject tells xdist to keep that order."""
    units = [worker_unit(item) for item in request.session.items]
    starts = [u for i, u in enumerate(units) if i == 0 or units[i - 1] != u]
    assert len(starts) == len(set(starts)), "a unit's tests are not together"
    costs = [unit_seconds(u) for u in starts]
    assert costs == sorted(costs, reverse=True)
    if len(starts) > 20:  # the whole suite: the OpenBLAS kernels' unit (about 36 s) among the first three
        assert {"openblas-kernels"} <= set(starts[:3]) and costs[0] > 5 * costs[len(costs) // 2]
        assert set(UNIT_SECONDS) <= set(starts), "tests/unit_seconds.json names a unit that is gone"
    assert request.config.getoption("loadscopereorder", default=False) is False


@pytest.mark.parametrize("exitstatus, code", [(0, 0), (1, 1)])
def test_an_xdist_worker_ends_at_unconfigure_without_the_interpreters_finalisation(tmp_path, exitstatus, code):
    """conftest's ``pytest_unconfigure`` ends a worker with its session's status and runs no atexit
    handler (the interpreter's finalisation is skipped); outside a worker it returns."""
    worker = types.SimpleNamespace(workerinput={"workerid": "gw0"}, workeroutput={"exitstatus": exitstatus})
    marker = tmp_path / "finalised"
    pid = os.fork()
    if pid == 0:  # the child: a worker at its end
        try:
            atexit.register(marker.write_text, "atexit ran")
            pytest_unconfigure(types.SimpleNamespace())  # the controller (no workerinput): returns
            pytest_unconfigure(worker)
        finally:
            os._exit(99)  # reached only if pytest_unconfigure returned
    _, status = os.waitpid(pid, 0)
    assert os.waitstatus_to_exitcode(status) == code and not marker.exists()


@pytest.mark.parametrize("fixtures, named, unit", [
    (("tmp_path",), None, "test_x"),  # its file
    (("tmp_path",), "frames-data", "frames-data"),  # the group its file names (files that share a cache)
    (("kernel_python",), "frames-data", "openblas-kernels"),  # a shared fixture's group first
])
def test_a_tests_unit_is_its_shared_fixtures_then_its_files_named_group_then_its_file(fixtures, named, unit):
    mark = pytest.mark.xdist_group(named).mark if named else None
    item = types.SimpleNamespace(fixturenames=fixtures, path=pathlib.Path("tests/test_x.py"),
                                 get_closest_marker=lambda name: mark if name == "xdist_group" else None)
    assert worker_unit(item) == unit


@pytest.mark.parametrize("nodeid, unit", [
    ("tests/test_a.py::test_x@test_a", "test_a"),
    ("tests/test_b.py::test_y[Haswell]@openblas-kernels", "openblas-kernels"),
    ("tests/test_b.py::test_y[a@b]@ray", "ray"),  # a parameter with "@": the last one is xdist's
    ("tests/test_a.py::test_x", None),  # no xdist group (a run without -n): no unit
])
def test_a_reports_unit_is_its_xdist_group(nodeid, unit):
    assert report_unit(nodeid) == unit


def test_the_unit_seconds_file_holds_the_units_of_a_second_or_more_longest_first():
    text = unit_seconds_json({"test_b": 2.04, "ray": 11.36, "test_c": 0.99, "test_a": 2.04, "openblas-kernels": 36.0})
    assert list(json.loads(text).items()) == [("openblas-kernels", 36.0), ("ray", 11.4), ("test_a", 2.0), ("test_b", 2.0)]
    assert text.endswith("}\n") and text == unit_seconds_json(json.loads(text) | {"test_c": 0.5})


@pytest.mark.parametrize("worker, count, preset, taken", [
    ("gw0", "2", {}, {"LP_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "NUMBA_NUM_THREADS"}),
    ("gw1", "2", {"OMP_NUM_THREADS": "4"}, {"LP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "NUMBA_NUM_THREADS"}),
    ("gw0", "1", {}, set()),  # fewer workers than cores: the libraries may use the others
    (None, None, {}, set()),  # not an xdist worker (pytest without -n)
])
def test_an_xdist_worker_of_one_per_core_takes_one_cores_settings_the_environment_leaves_unset(
        monkeypatch, worker, count, preset, taken):
    monkeypatch.setattr(os, "cpu_count", lambda: 2)
    for k, v in {"PYTEST_XDIST_WORKER": worker, "PYTEST_XDIST_WORKER_COUNT": count}.items():
        monkeypatch.delenv(k, raising=False) if v is None else monkeypatch.setenv(k, v)
    for k in ("LP_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "NUMBA_NUM_THREADS"):
        monkeypatch.delenv(k, raising=False)
    for k, v in preset.items():
        monkeypatch.setenv(k, v)
    settings = one_core_each()
    assert set(settings) == taken and set(settings.values()) <= {"1"}


def test_a_worker_of_one_per_core_runs_openblas_on_one_thread():
    """The setting took effect: NumPy's OpenBLAS, loaded after tests/conftest.py set it, runs one thread
    in this worker (the machine's cores, 2 here, without it)."""
    if not one_worker_per_core():
        pytest.skip("not an xdist worker of one per core (pytest without -n auto)")
    import numpy  # noqa: F401  (loaded already, by tests/conftest.py)
    from threadpoolctl import threadpool_info

    threads = [i["num_threads"] for i in threadpool_info() if i["internal_api"] == "openblas"]
    assert threads and set(threads) == {1}, threads
