"""Fingerprints of the source that produces a result: comments and docstrings do not count.

A cached episode is keyed by :func:`world_fingerprint` (the simulation, the sensor and their
assets); the committed results by :func:`results_fingerprint` (the world, the method and the
learning).
"""

from __future__ import annotations

import ast
import hashlib
import pathlib

ROOT = pathlib.Path(__file__).resolve().parent.parent

WORLD_MODULES = ("episode", "world/grip", "world/hand", "world/living", "camera/render", "world/scenario", "camera/sensor",
                 "world/simulate", "world/truth", "world/assets")
"""``benchmark`` modules (paths without ``.py``) that decide an episode's truth and depth (with
``benchmark/world/tasks/``)."""

RESULTS_MODULES = WORLD_MODULES + ("world/humanness", "paper/dataset", "paper/samples", "world/motion", "paper/table1", "paper/table2", "world/tactile",
                                   "paper/training", "method/spec", "method/run", "method/load", "method/init")
"""``benchmark`` modules that decide the committed results (with ``fsv/`` and the packages of
:data:`RESULTS_PACKAGES`)."""

RESULTS_PACKAGES = ("world/tasks", "scores", "suites")
"""``benchmark`` sub-packages that decide the committed results."""


def source_fingerprint(root: pathlib.Path, python_files: list, data_files: list) -> str:
    """sha256 over the given files: Python as its syntax tree without docstrings, data as bytes."""
    h = hashlib.sha256()
    for p in python_files:
        h.update(str(p.relative_to(root)).encode())
        h.update(_normalised_source(p.read_text()).encode())
    for p in data_files:
        h.update(str(p.relative_to(root)).encode())
        h.update(p.read_bytes())
    return h.hexdigest()


def _data_files(root: pathlib.Path, folders) -> list:
    """The data files directly in ``folders``; sub-folders hold results (the users' grip calibration,
    ``sim_assets/calibration/``), which no fingerprint includes."""
    return sorted(p for d in folders if (root / d).is_dir() for p in (root / d).iterdir()
                  if p.is_file() and p.suffix in (".xml", ".yaml", ".json", ".npz") and not p.name.startswith("."))


def world_fingerprint(root: pathlib.Path = ROOT) -> str:
    """Fingerprint of the world: ``sim_assets/``, ``benchmark/world/tasks/`` and :data:`WORLD_MODULES`."""
    files = sorted((root / "benchmark" / "world" / "tasks").glob("*.py")) + \
        [root / "benchmark" / f"{m}.py" for m in sorted(WORLD_MODULES)]
    return source_fingerprint(root, files, _data_files(root, ("sim_assets",)))


def results_fingerprint(root: pathlib.Path = ROOT) -> str:
    """Fingerprint of what the committed results depend on: ``fsv/`` (code and its data files, the
    shipped model excepted, which is itself a result), ``sim_assets/``, :data:`RESULTS_PACKAGES` and
    :data:`RESULTS_MODULES`."""
    files = sorted((root / "fsv").rglob("*.py"))
    for pkg in RESULTS_PACKAGES:
        files += sorted((root / "benchmark" / pkg).glob("*.py"))
    files += [root / "benchmark" / f"{m}.py" for m in sorted(RESULTS_MODULES)]
    data = [p for p in _data_files(root, ("sim_assets", "fsv/data")) if p.suffix != ".npz"]
    return source_fingerprint(root, files, data)


def _normalised_source(src: str) -> str:
    tree = ast.parse(src)
    for node in ast.walk(tree):
        body = getattr(node, "body", None)
        if isinstance(body, list) and body and isinstance(body[0], ast.Expr) \
                and isinstance(body[0].value, ast.Constant) and isinstance(body[0].value.value, str):
            node.body = body[1:] or [ast.Pass()]
    return ast.dump(tree)
