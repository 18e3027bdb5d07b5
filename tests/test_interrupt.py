"""Ctrl-C ends fsv-bench with status 130 within a second in every phase and leaves the previous output as it was.

The signal is sent at times drawn from a seeded generator to the command's whole process group, as
a terminal does: during the imports, the simulation, the rendering, the numba tracker, the pictures.
"""

import json
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from benchmark.atomic import OUTPUT_MARKER

pytestmark = pytest.mark.skipif(sys.platform != "linux", reason="process groups and signals as on Linux")

LIMIT_S = 2.0
"""Signal-to-exit limit checked here [s]: the watchdog's 1 s grace plus the interpreter's exit on a
loaded two-core machine (measured 0.05-1.1 s)."""


def _run_and_interrupt(out, delay_s: float) -> tuple:
    cmd = [sys.executable, "-m", "benchmark.commands.entry", "--task", "lift", "--duration", "2", "--quiet",
           "--no-gif", "--out", str(out)]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, start_new_session=True,
                            env={**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)})
    time.sleep(delay_s)
    sent = time.perf_counter()
    try:
        os.killpg(proc.pid, signal.SIGINT)
    except ProcessLookupError:  # it had finished
        pass
    _, err = proc.communicate(timeout=60)
    return proc.returncode, time.perf_counter() - sent, err.decode()


def test_ctrl_c_at_random_times_gives_130_and_keeps_the_previous_output(tmp_path):
    out = tmp_path / "run"
    out.mkdir()
    (out / OUTPUT_MARKER).write_text("")
    (out / "summary.json").write_text('{"previous": true}')
    delays = np.random.default_rng(2026).uniform(0.2, 6.0, size=4)
    interrupted = 0
    for delay in delays:
        code, took, err = _run_and_interrupt(out, float(delay))
        assert code in (130, 0, 1), (delay, code, err)
        summary = json.loads((out / "summary.json").read_text())
        if code == 130:
            interrupted += 1
            assert took < LIMIT_S, (delay, took)
            assert "interrupted" in err and "Traceback" not in err, err
            assert summary == {"previous": True} or "verdict" in summary  # the old output, or an earlier run's whole one
        else:  # it finished before the signal: its whole output replaced the old one
            assert "verdict" in summary
        leftovers = sorted(p.name for p in tmp_path.iterdir() if p.name != "run")
        assert not leftovers, leftovers
    assert interrupted >= 2  # most draws land while it runs
