"""No dead names: every top-level function, class and constant of ``benchmark`` and ``fsv`` is used
somewhere (in its own module, another module, a test, an example, a tool or the docs)."""

import ast
import collections
import pathlib
import re

ROOT = pathlib.Path(__file__).resolve().parents[1]


def _top_level_names(tree: ast.Module):
    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            yield node.lineno, node.name
        elif isinstance(node, ast.Assign):
            yield from ((node.lineno, t.id) for t in node.targets if isinstance(t, ast.Name))
        elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
            yield node.lineno, node.target.id


def test_every_top_level_name_is_used_somewhere():
    sources = [p for d in ("benchmark", "fsv", "tests", "examples", "tools") for p in sorted((ROOT / d).rglob("*.py"))]
    texts = {p: p.read_text() for p in sources + sorted((ROOT / "docs").rglob("*.md")) + [ROOT / "README.md"]}
    words = collections.Counter(w for t in texts.values() for w in re.findall(r"[A-Za-z_][A-Za-z0-9_]*", t))
    dead = []
    for path in sources:
        if path.relative_to(ROOT).parts[0] not in ("benchmark", "fsv"):
            continue
        for line, name in _top_level_names(ast.parse(texts[path])):
            if name.startswith("__"):
                continue
            if words[name] == 1:  # only its own definition
                dead.append(f"{path.relative_to(ROOT)}:{line}: {name}")
    assert not dead, "names defined and never used:\n" + "\n".join(dead)
