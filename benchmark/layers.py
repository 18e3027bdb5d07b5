"""The floors of the project, from the method up, and the import graph that keeps them.

A module may import modules of its own floor and of the floors below it (``tests/test_layers.py``
checks every import statement, inside functions too, and that the project's modules import each
other in no cycle). ``docs/design.md`` draws the floors and says where new code goes.
"""

from __future__ import annotations

from benchmark.source import import_graph  # noqa: F401 (the graph the floors are checked on)

FLOORS: tuple = (
    ("fsv", ("fsv",)),
    ("base", ("benchmark.errors", "benchmark.atomic", "benchmark.archive", "benchmark.sealed_table",
              "benchmark.background", "benchmark.simd", "benchmark.parallel", "benchmark.pool_server", "benchmark.pool_ready", "benchmark.collector", "benchmark.fingerprint", "benchmark.layers", "benchmark.source", "benchmark.interrupt", "benchmark.limits")),
    ("world", ("benchmark.world",)),
    ("camera", ("benchmark.camera",)),
    ("method", ("benchmark.method",)),
    ("scores", ("benchmark.scores",)),
    ("suites", ("benchmark.suites",)),
    ("paper", ("benchmark.paper",)),
    ("commands", ("benchmark.commands", "benchmark.exchange")),
    ("reproduce", ("benchmark.reproduce", "benchmark.perf", "benchmark.commands.entry", "benchmark")),
)
"""The floors from the ground up, each with the module prefixes it holds (the longest prefix wins):

- ``fsv``: the method; it imports nothing of ``benchmark`` (``tests/test_import_rule.py``);
- ``base``: errors, atomic files, archives, sealed tables, background jobs, worker pools, fingerprints;
- ``world``: scenario, simulation, truth, and what the truth implies (oracle contacts and
  kinematics, tracker-like poses), the episode record;
- ``camera``: rendering, the depth sensor, the depth codec and the episode file;
- ``method``: the adapter: what a method is given of an episode, and running it;
- ``scores``: pure functions of estimate and truth; gates;
- ``suites``: registry, evaluation, comparison, sweep, leaderboard;
- ``paper``: Table 1, Table 2, datasets, training, calibration: clients of the floors below;
- ``commands``: the main command's stages, pictures, reports, the command line, file exchange;
- ``reproduce``: regenerating every committed result; speed scripts; the console script
  (``benchmark.commands.entry``, which runs ``reproduce`` and hands every other command to
  ``benchmark.commands.cli``); the package itself (``benchmark/__init__.py``, a docstring naming
  where the world's and the camera's entry points live).
"""


def floor_of(module: str) -> str | None:
    """The floor holding ``module`` (dotted name), by the longest matching prefix; None if none."""
    best, best_len = None, -1
    for name, prefixes in FLOORS:
        for p in prefixes:
            if (module == p or module.startswith(p + ".")) and len(p) > best_len:
                best, best_len = name, len(p)
    return best


def _rank(floor: str) -> int:
    return [name for name, _ in FLOORS].index(floor)


def upward_imports(graph: dict) -> list:
    """[(importer, imported, line)] for every import from a lower floor to a higher one."""
    bad = []
    for a, edges in sorted(graph.items()):
        fa = floor_of(a)
        for b, line in edges:
            fb = floor_of(b)
            if fa is not None and fb is not None and _rank(fb) > _rank(fa):
                bad.append((a, b, line))
    return bad


def import_cycles(graph: dict) -> list:
    """The strongly connected components of more than one module (each sorted), Tarjan's algorithm."""
    index, low, stack, on, out = {}, {}, [], set(), []
    counter = [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w, _ in graph.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return sorted(out)
