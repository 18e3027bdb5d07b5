"""Fingerprints of the code and data that produce a result: content, never paths.

A cached episode and a dataset are keyed by :func:`world_fingerprint` (the simulation, the sensor,
the depth codec and their assets); the committed results by :func:`results_fingerprint` (the
world, the method, the scorers and the commands that write the results).

Which modules count is read from the code, not from a list of files: the modules that the entry
points (:data:`WORLD_ENTRY_POINTS`, :data:`RESULTS_ENTRY_POINTS`) import, directly or not, at
module level or inside functions (:func:`benchmark.source.closure`). Each module counts by its
normalised code (:func:`benchmark.source.normalised_code`: no comments, docstrings, formatting or
import paths) and each data file by its bytes; the digests are sorted before they are hashed. So a
pure move (a file renamed, its importers' import lines changed to the new path) changes no
fingerprint, invalidates no cached episode and makes no committed result stale, while a change to
any code that runs does.
"""

from __future__ import annotations

import functools
import hashlib
import json
import pathlib

from benchmark.atomic import user_cache, write_text
from benchmark.source import LazyImportGraph, closure, modules, normalised_code

ROOT = pathlib.Path(__file__).resolve().parent.parent

WORLD_ENTRY_POINTS = ("benchmark.world.simulate", "benchmark.camera.render", "benchmark.camera.episode_file")
"""What makes an episode's truth and depth and stores them: simulation, rendering, the episode file."""

RESULTS_ENTRY_POINTS = WORLD_ENTRY_POINTS + (
    "fsv", "benchmark.commands.cli", "benchmark.commands.humanness", "benchmark.commands.table1",
    "benchmark.paper.dataset.cli", "benchmark.paper.calibration", "benchmark.paper.training", "benchmark.paper.table2",
    "benchmark.commands.eval", "benchmark.suites.leaderboard", "benchmark.commands.learning_curve",
    "benchmark.commands.atlas", "benchmark.commands.colour_ablation",
)
"""What makes the committed results: the method, the main command and every sub-command that
``fsv-bench reproduce`` runs (:data:`benchmark.reproduce.RESULTS`)."""

DATA_FOLDERS = {"world": ("sim_assets",), "results": ("sim_assets", "fsv/data")}
"""Folders whose data files (directly in them) count: ``.xml``, ``.yaml``, ``.json`` and ``.npz``;
sub-folders hold results (the users' grip calibration, ``sim_assets/calibration/``), and the
shipped model (``fsv/data/*.npz``) is itself a result: neither counts."""


def _data_files(root: pathlib.Path, folders, suffixes=(".xml", ".yaml", ".json", ".npz")) -> list:
    return sorted(p for d in folders if (root / d).is_dir() for p in (root / d).iterdir()
                  if p.is_file() and p.suffix in suffixes and not p.name.startswith("."))


def content_fingerprint(python_files, data_files) -> str:
    """sha256 over the sorted digests of the files' contents: Python as normalised code, data as bytes."""
    digests = sorted([hashlib.sha256(normalised_code(p).encode()).hexdigest() for p in python_files]
                     + [hashlib.sha256(pathlib.Path(p).read_bytes()).hexdigest() for p in data_files])
    return hashlib.sha256("\n".join(digests).encode()).hexdigest()


def code_of(root: pathlib.Path, entry_points) -> list:
    """The files of every module that ``entry_points`` import, directly or not (with their own)."""
    root = pathlib.Path(root)
    mods = modules(root)
    return [mods[m] for m in closure(LazyImportGraph(root), entry_points)]


def world_fingerprint(root: pathlib.Path = ROOT) -> str:
    """Fingerprint of the world: the code :data:`WORLD_ENTRY_POINTS` run and ``sim_assets/``'s data.

    This installation's (``root`` left as it is) is computed once per process, and remembered across
    processes (:func:`remembered_world`): it keys every cached episode and file an evaluation
    touches, and its code does not change while it runs.
    """
    if pathlib.Path(root) == ROOT:
        return _this_world()
    return _world(pathlib.Path(root))


def _world(root: pathlib.Path) -> str:
    return content_fingerprint(code_of(root, WORLD_ENTRY_POINTS), _data_files(root, DATA_FOLDERS["world"]))


@functools.lru_cache(maxsize=1)
def _this_world() -> str:
    return remembered_world(ROOT, user_cache() / MEMO_NAME)


MEMO_NAME = "world-fingerprints.json"
"""The file, in fsv-bench's folder of the user's cache, that remembers world fingerprints."""

MEMO_ENTRIES = 16
"""How many (sources, fingerprint) pairs the memo keeps, the most recently made last."""


def sources_key(root: pathlib.Path) -> str:
    """sha256 over the path and bytes of every module of the packages and every world data file under
    ``root``: whatever could change :func:`world_fingerprint` changes it (6 ms, against 0.4 s for the
    fingerprint, which parses the modules the world imports)."""
    root = pathlib.Path(root)
    h = hashlib.sha256()
    for p in sorted(modules(root).values()) + _data_files(root, DATA_FOLDERS["world"]):
        data = p.read_bytes()
        h.update(f"{p.relative_to(root).as_posix()}\0{len(data)}\0".encode())
        h.update(data)
    return h.hexdigest()


def remembered_world(root: pathlib.Path, memo: pathlib.Path) -> str:
    """:func:`world_fingerprint` of ``root``, read from the JSON file ``memo`` under its
    :func:`sources_key`, or computed and added there (the :data:`MEMO_ENTRIES` most recent kept).
    Every process that keys a cached episode needs it (a pool's workers, each command): the first
    computes it, the others read it. A memo that cannot be read is made again; one that cannot be
    written (a read-only cache) is left as it is."""
    key = sources_key(root)
    try:
        known = json.loads(memo.read_text())
        if not isinstance(known, dict):
            known = {}
    except (OSError, ValueError):
        known = {}
    value = known.get(key)
    if isinstance(value, str) and len(value) == 64:
        return value
    value = _world(pathlib.Path(root))
    known.pop(key, None)
    known[key] = value
    try:
        write_text(memo, json.dumps(dict(list(known.items())[-MEMO_ENTRIES:]), indent=1) + "\n")
    except OSError:
        pass
    return value


def results_fingerprint(root: pathlib.Path = ROOT) -> str:
    """Fingerprint of what the committed results depend on: the code :data:`RESULTS_ENTRY_POINTS` run
    and the data of ``sim_assets/`` and ``fsv/data/`` (the shipped model excepted)."""
    root = pathlib.Path(root)
    data = [p for p in _data_files(root, DATA_FOLDERS["results"]) if p.suffix != ".npz"]
    return content_fingerprint(code_of(root, RESULTS_ENTRY_POINTS), data)
