"""benchmark.simd: NumPy's vector loops pinned to the baseline, the same truth on CPUs with and without AVX-512."""

import json
import os
import pathlib
import subprocess
import sys

import pytest

from benchmark.simd import NUMPY_BASELINE_ENV, pin_numpy_baseline
from fsv.provenance import numpy_simd

ROOT = pathlib.Path(__file__).resolve().parent.parent
_PROBE = """
import sys
if sys.argv[1] == "numpy-first":
    import numpy
import benchmark
import hashlib, json
import numpy as np
from fsv.provenance import numpy_simd
x = np.linspace(-20.0, 20.0, 100001)
maths = hashlib.sha256(b"".join(f(x).tobytes() for f in (np.exp, np.log1p, np.tanh, np.arctan)) + (np.abs(x) ** 1.7).tobytes())
out = {"simd": numpy_simd(), "maths": maths.hexdigest()}
if len(sys.argv) > 2:
    from benchmark.world.scenario import Scenario
    from benchmark.world.simulate import simulate
    from benchmark.commands.digests import digest
    out["truth"] = digest(simulate(Scenario(task="lift", duration_s=1.5)).truth)
print(json.dumps(out))
"""
_AVX2_CPU = {"NPY_DISABLE_CPU_FEATURES": "X86_V4 AVX512_ICL AVX512_SPR"}
"""What NumPy does on a CPU without AVX-512 (most AMD and desktop Intel CPUs), told to this one."""


def _run(order: str, env: dict, *extra) -> dict:
    clean = {k: v for k, v in os.environ.items() if not k.startswith("NPY_") or k in env}
    done = subprocess.run([sys.executable, "-c", _PROBE, order, *extra], env={**clean, **env,
                          "PYTHONPATH": str(ROOT)}, cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    return json.loads(done.stdout.strip().splitlines()[-1])


def test_this_process_runs_numpy_at_its_baseline():
    assert NUMPY_BASELINE_ENV == {"NPY_ENABLE_CPU_FEATURES": " "}
    assert numpy_simd() == {"dispatched": [], "baseline": True}


def test_the_pin_leaves_a_process_that_already_imported_numpy_alone(monkeypatch):
    monkeypatch.setenv("NPY_DISABLE_CPU_FEATURES", "X86_V4")
    assert pin_numpy_baseline() is False  # NumPy is imported here: its choice stands
    assert os.environ["NPY_DISABLE_CPU_FEATURES"] == "X86_V4"


def test_the_truth_is_the_same_with_and_without_avx512():
    """Told it has no AVX-512, NumPy's exp, log1p, tanh, arctan and power give other bits on this
    CPU (the control: NumPy imported before the package); after the package's pin, the same bits,
    and the simulated truth (the grip's relaxation is an exp) is the same."""
    native = _run("numpy-first", {})
    if not native["simd"]["dispatched"] or "X86_V4" not in native["simd"]["dispatched"]:
        pytest.skip(f"this CPU's NumPy dispatches no AVX-512 loops ({native['simd']})")
    assert _run("numpy-first", _AVX2_CPU)["maths"] != native["maths"], "NumPy's maths agree: this test cannot see SIMD"
    pinned, pinned_avx2 = _run("package-first", {}, "truth"), _run("package-first", _AVX2_CPU, "truth")
    assert pinned["simd"] == pinned_avx2["simd"] == {"dispatched": [], "baseline": True}
    assert pinned["maths"] == pinned_avx2["maths"]
    assert pinned["truth"] == pinned_avx2["truth"]
