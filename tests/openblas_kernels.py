"""The OpenBLAS kernels this CPU can run, for the tests that compare bits under several of them."""

from __future__ import annotations

import pathlib

KERNEL_FLAGS = {"Sandybridge": {"avx"}, "Haswell": {"avx2", "fma"}, "SkylakeX": {"avx512f", "avx512bw", "avx512vl"}}
"""CPU flags each kernel needs; OpenBLAS falls back to another kernel on a CPU without them."""


def cpu_flags() -> set:
    """This CPU's flags (/proc/cpuinfo; empty elsewhere)."""
    info = pathlib.Path("/proc/cpuinfo")
    if info.is_file():
        for line in info.read_text().splitlines():
            if line.startswith("flags"):
                return set(line.split(":", 1)[1].split())
    return set()


def runnable_kernels() -> list:
    """The kernels of :data:`KERNEL_FLAGS` that this CPU runs (Sandybridge, Haswell, SkylakeX order)."""
    flags = cpu_flags()
    return [k for k, need in KERNEL_FLAGS.items() if need <= flags]
