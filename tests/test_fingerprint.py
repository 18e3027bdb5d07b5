"""Fingerprints of the code behind a result: code that runs counts; comments, docstrings and paths do not."""

import json
import pathlib

import pytest

from benchmark import fingerprint
from benchmark.fingerprint import (
    MEMO_ENTRIES,
    MEMO_NAME,
    RESULTS_ENTRY_POINTS,
    ROOT,
    WORLD_ENTRY_POINTS,
    code_of,
    remembered_world,
    results_fingerprint,
    sources_key,
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


def _tree_in(folder: pathlib.Path) -> pathlib.Path:
    folder.mkdir()
    return _tree(folder)


def test_a_remembered_world_is_read_back_without_parsing_and_made_again_when_a_byte_changes(tmp_path, monkeypatch):
    tree, memo = _tree_in(tmp_path / "t"), tmp_path / "memo.json"
    first = remembered_world(tree, memo)
    assert first == world_fingerprint(tree) and json.loads(memo.read_text()) == {sources_key(tree): first}

    def no_parsing(root):
        raise AssertionError("parsed again")

    monkeypatch.setattr(fingerprint, "_world", no_parsing)
    assert remembered_world(tree, memo) == first  # read back: nothing parsed
    monkeypatch.undo()
    helper = tree / "benchmark/world/helper.py"
    helper.write_text("# a comment\n" + helper.read_text())  # another key, the same fingerprint
    assert remembered_world(tree, memo) == first and len(json.loads(memo.read_text())) == 2
    helper.write_text(helper.read_text().replace("x + 1", "x + 2"))
    changed = remembered_world(tree, memo)
    assert changed != first and changed == world_fingerprint(tree)
    assert list(json.loads(memo.read_text()).values())[-1] == changed


@pytest.mark.parametrize("content", ["not json", "[1, 2]", '{"KEY": "short"}'])
def test_a_damaged_memo_is_made_again(tmp_path, content):
    tree, memo = _tree_in(tmp_path / "t"), tmp_path / "memo.json"
    memo.write_text(content.replace("KEY", sources_key(tree)))
    assert remembered_world(tree, memo) == world_fingerprint(tree)
    assert json.loads(memo.read_text()) == {sources_key(tree): world_fingerprint(tree)}


def test_the_memo_keeps_the_most_recent_entries_and_one_that_cannot_be_written_is_left_alone(tmp_path):
    tree, memo = _tree_in(tmp_path / "t"), tmp_path / "memo.json"
    memo.write_text(json.dumps({f"{i:064x}": f"{i:064x}" for i in range(MEMO_ENTRIES + 4)}))
    value = remembered_world(tree, memo)
    known = json.loads(memo.read_text())
    assert len(known) == MEMO_ENTRIES and list(known.items())[-1] == (sources_key(tree), value)
    assert f"{MEMO_ENTRIES + 3:064x}" in known and f"{0:064x}" not in known  # the oldest went
    blocked = tmp_path / "a-file"  # a memo that cannot be written (as root, no mode refuses it)
    blocked.write_text("x")
    assert remembered_world(tree, blocked / "memo.json") == value  # computed; nothing written, no error
    assert blocked.read_text() == "x"


def test_this_installations_world_is_remembered_in_the_users_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    fingerprint._this_world.cache_clear()
    try:
        value = world_fingerprint()
    finally:
        fingerprint._this_world.cache_clear()
    assert json.loads((tmp_path / "fsv-bench" / MEMO_NAME).read_text()) == {sources_key(ROOT): value}
    assert value == world_fingerprint(ROOT / ".") == fingerprint._world(ROOT)
