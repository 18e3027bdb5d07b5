"""Where a result came from: the code, the interpreter, the libraries and the machine.

:func:`provenance` returns a JSON-serialisable dict that model files (:mod:`fsv.learn`) and the
benchmark's outputs (``summary.json``, ``dataset.json``, ``table2.json``) record, so that a number
can be traced to the code and the numerical libraries that produced it. Floating-point results
depend on the BLAS kernel a library picked for this CPU (OpenBLAS chooses one per CPU model, and
``OPENBLAS_CORETYPE`` overrides it), so the kernel and the CPU's SIMD flags are recorded too.

Keys:

    fsv_bench     {"version", "git_commit", "dirty"}: the distribution's version; the commit of the
                  source tree if the package is a git checkout ("unknown" otherwise, with dirty None),
                  and whether tracked files differ from it
    python        {"version", "implementation"}
    dependencies  {name: version or None}: every requirement of the fsv-bench distribution
                  (its metadata, plus the checkout's pyproject.toml for source trees), extras
                  included; None if not installed
    platform      {"system", "release", "machine", "platform"}
    cpu           {"model", "simd"}: the CPU's model name and which of ``SIMD_FLAGS`` it has
                  (from /proc/cpuinfo; model from :func:`platform.processor` and simd [] without it)
    blas          [{"internal_api", "version", "architecture", "num_threads", "filepath"}]: the
                  BLAS libraries loaded in this process (``threadpoolctl``), with the file's basename;
                  "architecture" is the kernel OpenBLAS picked (e.g. "Haswell")
    openblas_coretype  the ``OPENBLAS_CORETYPE`` environment variable, only if it is set
    numpy_simd    {"dispatched": [features NumPy's vector loops use beyond its baseline],
                  "baseline": bool}: ``baseline`` True when none is used (the pin that ``benchmark``
                  sets before NumPy is imported; other choices give other last bits to NumPy's
                  transcendental functions and sorts); absent before NumPy is imported

Everything but ``blas`` and ``openblas_coretype`` is computed once per process (the loaded
libraries and their thread counts can change, so those two are read on every call). Nothing here
raises: what cannot be found is recorded as "unknown", None or [].

This module imports only the standard library (and ``threadpoolctl`` when called), so both `fsv`
and `benchmark` can use it.
"""

from __future__ import annotations

import copy
import functools
import os
import pathlib
import platform
import re
import subprocess
import sys
from importlib import metadata

DISTRIBUTION = "fsv-bench"
SIMD_FLAGS = (
    "sse2", "ssse3", "sse4_1", "sse4_2", "avx", "f16c", "fma", "avx2", "avx512f", "avx512dq", "avx512cd",
    "avx512bw", "avx512vl", "avx512_vnni", "avx512_bf16", "amx_tile", "neon", "asimd", "sve", "sve2",
)
"""SIMD instruction-set flags that are looked for in /proc/cpuinfo (x86 "flags", Arm "Features")."""

_PACKAGE_DIR = pathlib.Path(__file__).resolve().parent
_GIT_TIMEOUT_S = 5.0


def provenance() -> dict:
    """The provenance of results computed in this process (keys: see the module docstring).

    Returns:
        A new JSON-serialisable dict on every call (callers may modify it).
    """
    out = copy.deepcopy(_static())
    out["blas"] = blas_libraries()
    coretype = os.environ.get("OPENBLAS_CORETYPE")
    if coretype is not None:
        out["openblas_coretype"] = coretype
    simd = numpy_simd()
    if simd is not None:
        out["numpy_simd"] = simd
    return out


def numpy_simd() -> dict | None:
    """Which of NumPy's run-time dispatched CPU features its vector loops use in this process:
    ``{"dispatched": [names], "baseline": bool}``, or None if NumPy is not imported (or does not say)."""
    core = sys.modules.get("numpy._core._multiarray_umath") or sys.modules.get("numpy.core._multiarray_umath")
    if core is None:
        return None
    features, dispatch = getattr(core, "__cpu_features__", None), getattr(core, "__cpu_dispatch__", None)
    if features is None or dispatch is None:
        return None
    used = [name for name in dispatch if features.get(name)]
    return {"dispatched": used, "baseline": not used}


@functools.lru_cache(maxsize=1)
def _static() -> dict:
    return {
        "fsv_bench": {"version": _version(), **git_state(_PACKAGE_DIR)},
        "python": {"version": platform.python_version(), "implementation": platform.python_implementation()},
        "dependencies": dependency_versions(),
        "platform": {"system": platform.system(), "release": platform.release(), "machine": platform.machine(),
                     "platform": platform.platform()},
        "cpu": cpu_info(),
    }


def _version() -> str:
    try:
        return metadata.version(DISTRIBUTION)
    except metadata.PackageNotFoundError:
        return "unknown"


def _git(folder: pathlib.Path, *args: str) -> str | None:
    """Output of ``git -C folder args``, or None if git is missing, fails or times out."""
    try:
        done = subprocess.run(["git", "-C", str(folder), *args], capture_output=True, text=True,
                              timeout=_GIT_TIMEOUT_S, check=False)
    except (OSError, subprocess.SubprocessError):
        return None
    return done.stdout if done.returncode == 0 else None


def git_state(folder) -> dict:
    """The git commit of the checkout that holds package folder ``folder``.

    A folder counts as a checkout only if its ``__init__.py`` is tracked by the repository around
    it (an installed copy inside some other repository, e.g. a virtual environment in a project
    folder, is not).

    Args:
        folder: A package folder.

    Returns:
        ``{"git_commit": <40 hex digits> or "unknown", "dirty": True/False, or None if unknown}``;
        dirty means tracked files differ from the commit.
    """
    folder = pathlib.Path(folder)
    head = _git(folder, "rev-parse", "HEAD")
    tracked = _git(folder, "ls-files", "--error-unmatch", "--", "__init__.py")
    if head is None or tracked is None or not re.fullmatch(r"[0-9a-f]{40,64}", head.strip()):
        return {"git_commit": "unknown", "dirty": None}
    status = _git(folder, "status", "--porcelain", "--untracked-files=no")
    return {"git_commit": head.strip(), "dirty": None if status is None else bool(status.strip())}


def requirement_names() -> list[str]:
    """Names of every requirement of the fsv-bench distribution (extras included), sorted.

    From the installed distribution's metadata and, when the package sits in a source tree next to
    a ``pyproject.toml`` of fsv-bench (an editable install whose metadata may predate the tree),
    from that file too.
    """

    specs = []
    try:
        specs += metadata.requires(DISTRIBUTION) or []
    except metadata.PackageNotFoundError:
        pass
    specs += _pyproject_requirements(_PACKAGE_DIR.parent / "pyproject.toml")
    names = {_canonical(m.group(1)) for m in (re.match(r"\s*([A-Za-z0-9][A-Za-z0-9._-]*)", s) for s in specs) if m}
    names.discard(_canonical(DISTRIBUTION))  # self-references of extras, e.g. "fsv-bench[ray]"
    return sorted(names)


def _pyproject_requirements(path: pathlib.Path) -> list[str]:
    try:
        import tomllib  # lazy: Python 3.10 has no tomllib
    except ImportError:  # Python 3.10: the installed metadata alone
        return []
    try:
        project = tomllib.loads(path.read_text(encoding="utf-8")).get("project", {})
    except (OSError, ValueError):
        return []
    if project.get("name") != DISTRIBUTION:
        return []
    out = list(project.get("dependencies", []))
    for extra in project.get("optional-dependencies", {}).values():
        out += list(extra)
    return [s for s in out if isinstance(s, str)]


def _canonical(name: str) -> str:
    return re.sub(r"[-_.]+", "-", name).lower()


def dependency_versions() -> dict:
    """``{requirement name: installed version or None}`` for :func:`requirement_names`."""

    out = {}
    for name in requirement_names():
        try:
            out[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            out[name] = None
    return out


def cpu_info(path: str = "/proc/cpuinfo") -> dict:
    """``{"model": str, "simd": [flags]}`` from ``path`` (Linux); without it, the model from
    :func:`platform.processor` (or "unknown") and no flags.

    Args:
        path: The cpuinfo file to read.
    """
    try:
        text = pathlib.Path(path).read_text(encoding="utf-8", errors="replace")
    except OSError:
        return {"model": platform.processor() or "unknown", "simd": []}
    fields = {}
    for line in text.splitlines():
        key, sep, value = line.partition(":")
        if sep:
            fields.setdefault(key.strip().lower(), value.strip())
    model = fields.get("model name") or fields.get("hardware") or fields.get("cpu model") or platform.processor()
    flags = set((fields.get("flags") or fields.get("features") or "").split())
    return {"model": model or "unknown", "simd": [f for f in SIMD_FLAGS if f in flags]}


def blas_libraries() -> list[dict]:
    """The BLAS libraries loaded in this process and their kernels, from ``threadpoolctl``.

    Returns:
        One dict per library: ``internal_api`` (e.g. "openblas", "mkl"), ``version``,
        ``architecture`` (the kernel, e.g. "Haswell"; None if the library does not say),
        ``num_threads`` and ``filepath`` (the file's basename); [] without threadpoolctl.
    """
    try:
        from threadpoolctl import threadpool_info  # lazy: threadpoolctl, only for a run's provenance

        info = threadpool_info()
    except Exception:  # threadpoolctl missing or failing: provenance never fails
        return []
    return [
        {"internal_api": lib.get("internal_api"), "version": lib.get("version"),
         "architecture": lib.get("architecture"), "num_threads": lib.get("num_threads"),
         "filepath": os.path.basename(lib.get("filepath") or "")}
        for lib in info if lib.get("user_api") == "blas"
    ]


if __name__ == "__main__":  # python -m fsv.provenance: print this process's provenance
    import json

    import numpy  # noqa: F401  (loads the BLAS that numerical work would use)

    json.dump(provenance(), sys.stdout, indent=1)
    print()
