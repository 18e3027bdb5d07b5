"""The floors of the house: every import, at module level or inside a function, goes down or sideways.

The project's modules form floors (``benchmark.layers.FLOORS``, drawn in ``docs/design.md``); a
module may import its own floor and the floors below it, never one above. Among all the project's
modules (``fsv`` and ``benchmark``) there is no import cycle. Both are read from the syntax trees,
so an import hidden inside a function counts like any other; optional heavy libraries are not the
project's and are not checked here.
"""

from __future__ import annotations

import pathlib

import pytest

from benchmark.layers import FLOORS, floor_of, import_cycles, upward_imports
from benchmark.source import import_graph

ROOT = pathlib.Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def graph():
    return import_graph(ROOT)


def test_every_module_has_a_floor(graph):
    missing = sorted(m for m in graph if floor_of(m) is None)
    assert not missing, missing


def test_no_import_goes_up_a_floor(graph):
    bad = upward_imports(graph)
    assert not bad, "\n".join(f"{a} ({floor_of(a)}) imports {b} ({floor_of(b)}) at line {line}" for a, b, line in bad)


def test_no_import_cycle(graph):
    cycles = import_cycles(graph)
    assert not cycles, cycles


def test_the_graph_sees_imports_inside_functions(tmp_path):
    # A planted upward import inside a function is found, as is the cycle it closes.
    for pkg in ("fsv", "benchmark", "benchmark/world", "benchmark/suites"):
        (tmp_path / pkg).mkdir(parents=True, exist_ok=True)
        (tmp_path / pkg / "__init__.py").write_text("")
    (tmp_path / "benchmark/world/a.py").write_text("def f():\n    from benchmark.suites.b import g\n    return g\n")
    (tmp_path / "benchmark/suites/b.py").write_text("from benchmark.world import a\n\ndef g():\n    return a\n")
    g = import_graph(tmp_path)
    assert [(a, b) for a, b, _ in upward_imports(g)] == [("benchmark.world.a", "benchmark.suites.b")]
    assert import_cycles(g) == [["benchmark.suites.b", "benchmark.world.a"]]


def test_the_floors_are_ordered_from_the_method_up():
    names = [name for name, _ in FLOORS]
    assert names[0] == "fsv" and names[-1] == "reproduce"
    assert names.index("world") < names.index("camera") < names.index("method") < names.index("scores") \
        < names.index("suites") < names.index("paper") < names.index("commands")


def test_the_command_line_imports_every_sub_command_where_the_floors_can_see_it(graph):
    """No sub-command is loaded by a string: the console script's and the command line's imports of
    them are in the graph the floors and the cycles are checked on."""
    from benchmark.commands import cli, entry

    seen = {b for b, _ in graph["benchmark.commands.cli"]} | {b for b, _ in graph["benchmark.commands.entry"]}
    modules = {name: entry.subcommand_module(name).__name__ for name in cli.ALL_SUBCOMMANDS}
    assert not {name: m for name, m in modules.items() if m not in seen}
    assert modules["reproduce"] == "benchmark.reproduce" and floor_of("benchmark.commands.entry") == "reproduce"
