"""tests/kernel_python.py: scripts run as ``python -c`` would, in one kept interpreter per environment."""

import pytest
from conftest import worker_unit
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
