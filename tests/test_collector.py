"""benchmark.collector: the garbage collector's thresholds in the command's process and its pool's workers."""

import gc
import os
import subprocess
import sys

import pytest

from benchmark import collector
from benchmark.commands import entry

_JOBS = """
import gc, multiprocessing.forkserver, sys
from benchmark.parallel import run_jobs

def threshold(_):
    return gc.get_threshold()

if __name__ == "__main__":
    if sys.argv[1] == "spawned":  # another library started the fork server: the pool spawns its workers
        multiprocessing.forkserver.ensure_running()
    print(gc.get_threshold(), sorted(set(r for _, r in run_jobs(threshold, [0, 1, 2, 3], workers=2))))
"""


def test_the_command_sets_the_threshold_in_its_own_process_only(monkeypatch):
    before = gc.get_threshold()
    monkeypatch.setattr(entry.interrupt, "install", lambda: None)
    monkeypatch.setattr(entry, "run", lambda: 0)
    monkeypatch.setattr(entry, "main_command_done", lambda argv: False)
    monkeypatch.setattr(entry.interrupt, "finished", lambda code: None)
    try:
        assert entry.main() == 0
        assert gc.get_threshold() == collector.THRESHOLD != (700, 10, 10)
    finally:
        gc.set_threshold(*before)


@pytest.mark.parametrize("start", ["forked", "spawned"])
def test_a_pools_workers_collect_at_the_threshold_whoever_started_them(tmp_path, start):
    """Forked from the fork server (which set it) or spawned (the worker's initializer sets it); the
    pool's owner, a caller's process, keeps its own."""
    (tmp_path / "jobs.py").write_text(_JOBS)
    out = subprocess.run([sys.executable, "jobs.py", start], cwd=tmp_path, capture_output=True, text=True, timeout=120,
                         env={**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)})
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == f"(700, 10, 10) [{collector.THRESHOLD}]"
