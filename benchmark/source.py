"""The project's own source as data: its modules, the imports between them, their code without paths.

Read from the syntax trees, never by importing: an import inside a function counts like one at the
top of a module. Used by the floors' test (:mod:`benchmark.layers`) and by the fingerprints
(:mod:`benchmark.fingerprint`).
"""

from __future__ import annotations

import ast
import functools
import pathlib
from collections.abc import Mapping

PACKAGES = ("fsv", "benchmark")
"""The project's top-level packages."""


def modules(root: pathlib.Path) -> dict:
    """``{dotted module name: path}`` of every module of :data:`PACKAGES` under ``root`` (a package is its ``__init__``)."""
    mods = {}
    for top in PACKAGES:
        for p in sorted((pathlib.Path(root) / top).rglob("*.py")):
            parts = p.relative_to(root).with_suffix("").parts
            if parts[-1] == "__init__":
                parts = parts[:-1]
            mods[".".join(parts)] = p
    return mods


@functools.lru_cache(maxsize=4096)
def _tree(path: pathlib.Path, mtime_ns: int) -> ast.Module:
    return ast.parse(path.read_text(), filename=str(path))


def parse(path: pathlib.Path) -> ast.Module:
    """The syntax tree of a file (cached per path and modification time; do not modify it)."""
    return _tree(path, path.stat().st_mtime_ns)


def _imports(name: str, path: pathlib.Path):
    """``(node, base module, [imported names or None])`` of every import statement of a module."""
    is_pkg = path.name == "__init__.py"
    for node in ast.walk(parse(path)):
        if isinstance(node, ast.Import):
            for a in node.names:
                yield node, a.name, None
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                here = name.split(".") if is_pkg else name.split(".")[:-1]
                here = here[:len(here) - node.level + 1]
                base = ".".join(here + ([base] if base else []))
            yield node, base, [a.name for a in node.names]


def _reexports(mods: dict, package: str) -> dict:
    """``{name: module}`` for the names a package's ``__init__`` imports at its top level from elsewhere."""
    path = mods[package]
    top = {id(node) for node in parse(path).body}
    return {a.asname or a.name: (base, a.name) for node, base, names in _imports(package, path)
            if names is not None and id(node) in top for a in node.names}


def _resolve(mods: dict, base: str, name: str | None, depth: int = 0) -> str | None:
    """The project module that ``from base import name`` (or ``import base``) takes its object from."""
    if name is not None and f"{base}.{name}" in mods:
        return f"{base}.{name}"
    if base in mods and name is not None and mods[base].name == "__init__.py" and depth < 8:
        source = _reexports(mods, base).get(name)
        if source is not None:
            found = _resolve(mods, source[0], source[1], depth + 1)
            if found is not None:
                return found
    while base and base not in mods:
        base = base.rpartition(".")[0]
    return base or None


def imports_of(mods: dict, name: str) -> list:
    """The project modules that module ``name`` imports: ``[(imported module, line), ...]``.

    ``from package import name`` counts as importing the submodule ``package.name`` where one
    exists; a name that a package's ``__init__`` only re-exports counts as importing the module it
    comes from (so that ``from fsv import Poses`` depends on ``fsv.types``, not on all of ``fsv``);
    any other name counts as importing the package. Relative imports are resolved.

    Args:
        mods: :func:`modules` of the tree.
        name: A key of ``mods``.
    """
    edges = []
    for node, base, names in _imports(name, mods[name]):
        for n in (names or [None]):
            t = _resolve(mods, base, n)
            if t and t != name and (t, node.lineno) not in edges:
                edges.append((t, node.lineno))
    return edges


def import_graph(root: pathlib.Path) -> dict:
    """The project's imports: ``{module: imports_of(module)}`` for every module (:func:`imports_of`)."""
    mods = modules(pathlib.Path(root))
    return {name: imports_of(mods, name) for name in mods}


def closure(graph, roots) -> list:
    """Every module that ``roots`` import, directly or not, with the roots themselves, sorted.

    Args:
        graph: ``{module: [(imported module, line), ...]}``: :func:`import_graph`, or
            :class:`LazyImportGraph` (which reads only the modules the walk reaches).
        roots: Module names.
    """
    seen, todo = set(), list(roots)
    while todo:
        m = todo.pop()
        if m in seen:
            continue
        if m not in graph:
            raise KeyError(f"{m} is not a module of the project")
        seen.add(m)
        todo += [t for t, _ in graph[m]]
    return sorted(seen)


class LazyImportGraph(Mapping):
    """:func:`import_graph` of the tree at ``root``, each module parsed when it is first looked up:
    a :func:`closure` reads only the modules it reaches (the world's 57 of 218, a third of the time
    of the whole graph)."""

    def __init__(self, root: pathlib.Path):
        self._mods = modules(pathlib.Path(root))
        self._edges: dict = {}

    def __getitem__(self, name: str) -> list:
        if name not in self._edges:
            if name not in self._mods:
                raise KeyError(name)
            self._edges[name] = imports_of(self._mods, name)
        return self._edges[name]

    def __contains__(self, name) -> bool:
        return name in self._mods

    def __iter__(self):
        return iter(self._mods)

    def __len__(self) -> int:
        return len(self._mods)

    @property
    def parsed(self) -> tuple:
        """The modules read so far, in the order they were."""
        return tuple(self._edges)


def _ours(module: str | None, level: int = 0) -> bool:
    return bool(level) or (module or "").split(".")[0] in PACKAGES


class _NoPaths(ast.NodeTransformer):
    """Drops docstrings, and the project's module paths from import statements (the imported names
    stay; other libraries' imports are kept whole)."""

    def generic_visit(self, node):
        body = getattr(node, "body", None)
        if isinstance(body, list) and body and isinstance(body[0], ast.Expr) \
                and isinstance(body[0].value, ast.Constant) and isinstance(body[0].value.value, str):
            node.body = body[1:] or [ast.Pass()]
        return super().generic_visit(node)

    def visit_ImportFrom(self, node):
        return ast.ImportFrom(module=None, names=node.names, level=0) if _ours(node.module, node.level) else node

    def visit_Import(self, node):
        return ast.Import(names=[ast.alias(name=a.asname or a.name.rpartition(".")[2]) if _ours(a.name) else a
                                 for a in node.names])


def normalised_code(path: pathlib.Path) -> str:
    """A module's code as text that ignores comments, docstrings, formatting and where its imports come from.

    A pure move of a module (the same code under another path, its importers' import statements
    changed to the new path) leaves every module's normalised code as it was.
    """
    tree = ast.parse(pathlib.Path(path).read_text())
    return ast.dump(_NoPaths().visit(tree))
