"""fsv.jit: a kernel's on-disk cache is keyed by every file it is compiled from."""

import os
import pathlib
import sys

import pytest

from benchmark.source import LazyImportGraph, closure, modules
from fsv import jit

ROOT = pathlib.Path(__file__).resolve().parents[1]

_CALLER = '''
import numba
from fsv.jit import kernel
from pkg.callee import value

@kernel
def with_key():
    return value() + 0.5

@numba.njit(cache=True)
def plain():
    return value() + 0.5
'''

_CALLEE = '''
from fsv.jit import kernel

@kernel
def value():
    return {v}
'''


def _load_caller(base: pathlib.Path):
    """A fresh import of ``pkg.caller`` from ``base`` (its dispatchers new, their caches read from disk)."""
    for name in [m for m in sys.modules if m == "pkg" or m.startswith("pkg.")]:
        del sys.modules[name]
    jit.sources_of.cache_clear()
    jit.sources_digest.cache_clear()
    import pkg.caller

    return pkg.caller


def test_a_kernel_is_compiled_again_when_only_a_file_it_calls_changed(tmp_path, monkeypatch):
    """The caller's file is left as it was (its time and size too); the callee's changes. numba's own
    key (``plain``) loads the old compiled code from its cache; :func:`fsv.jit.kernel` compiles again."""
    pkg = tmp_path / "pkg"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("")
    (pkg / "caller.py").write_text(_CALLER)
    (pkg / "callee.py").write_text(_CALLEE.format(v="1.0"))
    monkeypatch.syspath_prepend(str(tmp_path))
    try:
        caller = _load_caller(tmp_path)
        assert caller.with_key() == 1.5 and caller.plain() == 1.5  # compiled and cached
        caller_stat = (pkg / "caller.py").stat()
        (pkg / "callee.py").write_text(_CALLEE.format(v="2.0"))  # the same size, another value
        os.utime(pkg / "caller.py", ns=(caller_stat.st_atime_ns, caller_stat.st_mtime_ns))
        caller = _load_caller(tmp_path)
        assert caller.plain() == 1.5  # the control: numba's key misses the change
        assert caller.with_key() == 2.5
        assert jit.sources_of(pkg / "caller.py") == (pkg / "callee.py", pkg / "caller.py")  # its installation only
    finally:
        for name in [m for m in sys.modules if m == "pkg" or m.startswith("pkg.")]:
            del sys.modules[name]
        jit.sources_of.cache_clear()
        jit.sources_digest.cache_clear()


def test_the_sources_of_every_kernel_module_are_its_import_closure():
    """What the key covers, read from import lines, is what ``benchmark.source`` finds by parsing the
    modules (the closure the world's fingerprint uses), for every module that defines kernels."""
    mods = modules(ROOT)
    graph = LazyImportGraph(ROOT)
    kernels = [m for m, p in mods.items() if "@kernel" in p.read_text() and m != "fsv.jit"]
    assert {"fsv.track.hand.lm", "benchmark.camera.normal_draws", "benchmark.world.grip_kernels"} <= set(kernels)
    for m in kernels:
        assert jit.sources_of(mods[m]) == tuple(sorted(mods[x].resolve() for x in closure(graph, [m]))), m
    lm = {p.relative_to(ROOT).as_posix() for p in jit.sources_of(mods["fsv.track.hand.lm"])}
    assert {"fsv/track/hand_system.py", "fsv/track/capsules.py", "fsv/rotation.py"} <= lm


@pytest.mark.parametrize("text, names", [
    ("a, b as c", ["a", "b"]),
    ("(a,\n    b,  # why\n    c)", ["a", "b", "c"]),
    ("x  # noqa: F401", ["x"]),
])
def test_import_lists_are_read_as_python_reads_them(text, names):
    assert jit._names(text) == names
