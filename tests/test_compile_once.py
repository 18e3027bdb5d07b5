"""tests/compile_once.py: the command that compiles numba's kernels before the workers' first test."""

import threading
import time

import compile_once
from compile_once import Compiling, wait_for


def test_the_marker_is_written_when_the_command_ends_even_by_failing_and_close_removes_its_folder():
    for command in (("--help",), ("--task", "juggle", "--quiet")):  # exit 0; a bad task: exit 2
        compiling = Compiling(command)
        assert wait_for(compiling.marker, timeout_s=120)
        folder = compiling.folder
        compiling.close()
        assert not folder.exists()


def test_close_ends_a_command_that_still_runs():
    compiling = Compiling(compile_once.COMMAND)  # seconds at least: ended at once here
    t0 = time.monotonic()
    compiling.close()
    assert time.monotonic() - t0 < 5 and compiling._proc.returncode != 0 and not compiling.folder.exists()


def test_wait_for_returns_once_the_marker_exists_and_gives_up_after_its_timeout(tmp_path):
    marker = tmp_path / "done"
    assert not wait_for(marker, timeout_s=0.3)
    threading.Timer(0.3, marker.write_text, ("done",)).start()
    t0 = time.monotonic()
    assert wait_for(marker, timeout_s=10) and 0.2 < time.monotonic() - t0 < 5
