"""Fingerprints of the code behind a result: code that runs counts; comments, docstrings and paths do not."""

import pathlib

from benchmark.fingerprint import (
    RESULTS_ENTRY_POINTS,
    ROOT,
    WORLD_ENTRY_POINTS,
    code_of,
    results_fingerprint,
    world_fingerprint,
)


def _tree(tmp_path) -> pathlib.Path:
    """A minimal project: every entry point a module; the simulation imports a helper, the method a tracker."""
    for m in RESULTS_ENTRY_POINTS:
        *pkgs, leaf = m.split(".")
        for i in range(1, len(pkgs) + 1):
            (tmp_path / pathlib.Path(*pkgs[:i])).mkdir(exist_ok=True)
            (tmp_path / pathlib.Path(*pkgs[:i]) / "__init__.py").write_text("")
        if pkgs:
            (tmp_path / pathlib.Path(*pkgs) / f"{leaf}.py").write_text(f"NAME = {m!r}\n")
    (tmp_path / "fsv").mkdir()
    (tmp_path / "benchmark/world/helper.py").write_text("def step(x):\n    return x + 1\n")
    (tmp_path / "benchmark/world/simulate.py").write_text("from benchmark.world.helper import step\n\nY = step(1)\n")
    (tmp_path / "fsv/track.py").write_text("def track(d):\n    return d\n")
    (tmp_path / "fsv/__init__.py").write_text("from fsv.track import track\n")
    (tmp_path / "sim_assets").mkdir()
    (tmp_path / "sim_assets/box.yaml").write_text("size: 1\n")
    (tmp_path / "fsv/data").mkdir()
    return tmp_path


def test_comments_and_docstrings_do_not_count_code_and_data_do(tmp_path):
    root = _tree(tmp_path)
    mod = root / "fsv/track.py"
    base = results_fingerprint(root)
    mod.write_text('def track(d):\n    """Other words."""\n    # reworded\n    return d\n')
    assert results_fingerprint(root) == base
    mod.write_text("def track(d):\n    return d + 0\n")
    assert results_fingerprint(root) != base
    mod.write_text("def track(d):\n    return d\n")
    assert results_fingerprint(root) == base
    (root / "sim_assets/box.yaml").write_text("size: 2\n")
    assert results_fingerprint(root) != base


def test_the_world_fingerprint_ignores_the_method_but_not_the_world(tmp_path):
    root = _tree(tmp_path)
    base = world_fingerprint(root)
    (root / "fsv/track.py").write_text("def track(d):\n    return 2 * d\n")
    (root / "benchmark/paper/table1.py").write_text("NAME = 'another'\n")
    assert world_fingerprint(root) == base
    (root / "benchmark/world/helper.py").write_text("def step(x):\n    return x + 2\n")  # imported, not an entry point
    assert world_fingerprint(root) != base


def test_a_pure_move_changes_no_fingerprint(tmp_path):
    root = _tree(tmp_path)
    world, results = world_fingerprint(root), results_fingerprint(root)
    (root / "benchmark/camera/helper.py").write_text((root / "benchmark/world/helper.py").read_text())
    (root / "benchmark/world/helper.py").unlink()
    (root / "benchmark/world/simulate.py").write_text("from benchmark.camera.helper import step\n\nY = step(1)\n")
    assert (world_fingerprint(root), results_fingerprint(root)) == (world, results)
    # ... and a relative import of the same module is the same code too
    (root / "benchmark/world/simulate.py").write_text("from ..camera.helper import step\n\nY = step(1)\n")
    assert world_fingerprint(root) == world
    # a change of what is imported is not a move
    (root / "benchmark/world/simulate.py").write_text("from benchmark.camera.helper import step as s\n\nY = s(1)\n")
    assert world_fingerprint(root) != world


def test_the_world_runs_no_method_code():
    files = {str(p.relative_to(ROOT)) for p in code_of(ROOT, WORLD_ENTRY_POINTS)}
    assert "benchmark/world/simulate.py" in files and "benchmark/camera/sensor.py" in files
    method = sorted(f for f in files if f.startswith(("fsv/track", "fsv/forces", "fsv/learn", "fsv/method",
                                                      "benchmark/scores", "benchmark/suites", "benchmark/paper")))
    assert not method, method


def test_the_world_fingerprint_reads_only_the_modules_the_world_imports(tmp_path):
    """A module outside the world's closure is never parsed: one that is not even Python leaves the
    world's fingerprint as it was (the whole import graph cannot be built), and the closure read
    lazily is the closure of the whole graph on this project."""
    from benchmark.source import LazyImportGraph, closure, import_graph

    root = _tree(tmp_path)
    base = world_fingerprint(root)
    (root / "benchmark/paper/table1.py").write_text("this is not python (\n")
    assert world_fingerprint(root) == base
    whole = import_graph(ROOT)
    for entry_points in (WORLD_ENTRY_POINTS, RESULTS_ENTRY_POINTS):
        lazy, expected = LazyImportGraph(ROOT), closure(whole, entry_points)
        assert closure(lazy, entry_points) == expected == sorted(lazy.parsed) and len(lazy.parsed) < len(whole)
