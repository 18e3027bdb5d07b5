"""Provenance: code, interpreter, libraries, BLAS kernel and CPU, JSON-ready and cheap to call."""

import json
import re
import shutil
import subprocess
from importlib import metadata

import numpy as np  # noqa: F401  (loads numpy's BLAS, as any numerical run does)
import pytest

from fsv import provenance as prov
from fsv.provenance import SIMD_FLAGS, blas_libraries, cpu_info, git_state, provenance

KEYS = {"fsv_bench", "python", "dependencies", "platform", "cpu", "blas"}


def test_keys_and_values_are_json_serialisable():
    p = provenance()
    assert KEYS <= set(p)
    assert json.loads(json.dumps(p)) == p
    assert p["fsv_bench"]["version"] == metadata.version("fsv-bench")
    assert set(p["fsv_bench"]) == {"version", "git_commit", "dirty"}
    assert p["python"]["version"].count(".") == 2 and p["python"]["implementation"] == "CPython"
    assert set(p["platform"]) == {"system", "release", "machine", "platform"}
    assert p["cpu"]["model"] and set(p["cpu"]["simd"]) <= set(SIMD_FLAGS)


def test_every_requirement_has_its_installed_version():
    deps = provenance()["dependencies"]
    for name in ("numpy", "torch", "mujoco", "threadpoolctl", "pyarrow", "scipy"):
        assert deps[name] == metadata.version(name), name
    assert "fsv-bench" not in deps
    for spec in metadata.requires("fsv-bench"):  # the distribution's metadata, extras included
        name = re.match(r"[A-Za-z0-9._-]+", spec).group(0)
        assert re.sub(r"[-_.]+", "-", name).lower() in deps, spec


def test_a_missing_dependency_is_null(monkeypatch):
    monkeypatch.setattr(prov, "requirement_names", lambda: ["numpy", "no-such-distribution-here"])
    deps = prov.dependency_versions()
    assert deps == {"numpy": metadata.version("numpy"), "no-such-distribution-here": None}


def test_blas_entry_names_the_openblas_kernel():
    from threadpoolctl import threadpool_info

    loaded = [lib for lib in threadpool_info() if lib.get("internal_api") == "openblas"]
    if not loaded:
        pytest.skip("no OpenBLAS loaded in this process")
    blas = provenance()["blas"]
    openblas = [b for b in blas if b["internal_api"] == "openblas"]
    assert len(openblas) == len(loaded)
    for entry, lib in zip(openblas, loaded):
        assert entry["architecture"] == lib["architecture"] and entry["architecture"]  # e.g. "Haswell"
        assert entry["version"] == lib["version"] and entry["num_threads"] == lib["num_threads"] >= 1
        assert "/" not in entry["filepath"] and lib["filepath"].endswith(entry["filepath"])


def test_blas_is_empty_without_threadpoolctl(monkeypatch):
    import builtins

    real = builtins.__import__

    def no_threadpoolctl(name, *args, **kw):
        if name == "threadpoolctl":
            raise ImportError(name)
        return real(name, *args, **kw)

    monkeypatch.setattr(builtins, "__import__", no_threadpoolctl)
    assert blas_libraries() == []


def test_openblas_coretype_is_recorded_only_when_set(monkeypatch):
    monkeypatch.delenv("OPENBLAS_CORETYPE", raising=False)
    assert "openblas_coretype" not in provenance()
    monkeypatch.setenv("OPENBLAS_CORETYPE", "Haswell")
    assert provenance()["openblas_coretype"] == "Haswell"


def test_cpu_model_and_simd_flags_from_cpuinfo(tmp_path):
    f = tmp_path / "cpuinfo"
    f.write_text("processor\t: 0\nmodel name\t: Test CPU 9000\nflags\t\t: fpu sse2 avx2 avx fma avx512f bogus\n\n"
                 "processor\t: 1\nmodel name\t: Test CPU 9000\nflags\t\t: fpu sse2\n")
    assert cpu_info(str(f)) == {"model": "Test CPU 9000", "simd": ["sse2", "avx", "fma", "avx2", "avx512f"]}
    arm = tmp_path / "arm"
    arm.write_text("processor\t: 0\nFeatures\t: fp asimd sve\n")
    assert cpu_info(str(arm))["simd"] == ["asimd", "sve"]
    missing = cpu_info(str(tmp_path / "none"))
    assert missing["simd"] == [] and isinstance(missing["model"], str) and missing["model"]


@pytest.mark.skipif(shutil.which("git") is None, reason="git is not installed")
def test_git_commit_and_dirty_flag(tmp_path):
    def git(*args):
        return subprocess.run(["git", "-C", str(tmp_path), *args], check=True, capture_output=True, text=True).stdout

    pkg = tmp_path / "pkg"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("x = 1\n")
    assert git_state(pkg) == {"git_commit": "unknown", "dirty": None}  # not a repository
    git("init", "-q")
    git("-c", "user.email=a@b", "-c", "user.name=a", "commit", "-q", "--allow-empty", "-m", "empty")
    assert git_state(pkg) == {"git_commit": "unknown", "dirty": None}  # in a repository, but not tracked
    git("add", "pkg/__init__.py")
    git("-c", "user.email=a@b", "-c", "user.name=a", "commit", "-q", "-m", "pkg")
    head = git("rev-parse", "HEAD").strip()
    (tmp_path / "untracked.txt").write_text("?")
    assert git_state(pkg) == {"git_commit": head, "dirty": False}  # untracked files do not count
    (pkg / "__init__.py").write_text("x = 2\n")
    assert git_state(pkg) == {"git_commit": head, "dirty": True}


def test_static_parts_are_computed_once_and_callers_get_copies():
    first = provenance()
    hits = prov._static.cache_info().hits
    first["dependencies"]["numpy"] = "changed"
    second = provenance()
    assert prov._static.cache_info().hits == hits + 1 and prov._static.cache_info().misses == 1
    assert second["dependencies"]["numpy"] == metadata.version("numpy")
