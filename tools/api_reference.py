"""Writes docs/api-reference.md: the public API from the docstrings, as Markdown readable in the repository.

    python tools/api_reference.py            # rewrite docs/api-reference.md
    python tools/api_reference.py --check    # exit 1 if it is out of date (tests/test_docs.py runs this)

The documentation site renders the same docstrings (docs/api.md, mkdocstrings); this file is the
same reference for a reader of the repository without the site.
"""

from __future__ import annotations

import argparse
import importlib
import inspect
import pathlib
import sys

ROOT = pathlib.Path(__file__).resolve().parents[1]
OUT = ROOT / "docs" / "api-reference.md"
MODULES = ("fsv.method", "fsv.method.stages", "fsv.method.baselines", "fsv.grip", "fsv.types", "benchmark.method",
           "benchmark.exchange")
"""The modules of docs/api.md: what a method author uses, and how the benchmark runs and exchanges."""


def _members(module) -> list:
    names = getattr(module, "__all__", None) or [n for n, v in vars(module).items()
                                                 if not n.startswith("_") and getattr(v, "__module__", "") == module.__name__]
    out = []
    for name in names:
        obj = getattr(module, name)
        if inspect.isclass(obj) or inspect.isfunction(obj):
            out.append((name, obj))
    return out


def _signature(obj) -> str:
    try:
        return str(inspect.signature(obj))
    except (TypeError, ValueError):
        return "(...)"


def render() -> str:
    sys.path.insert(0, str(ROOT))
    lines = ["# API reference (from the docstrings)", "",
             "Written by `python tools/api_reference.py` from the docstrings of the modules below; the "
             "documentation site renders the same text ([API reference](api.md)).", ""]
    for name in MODULES:
        module = importlib.import_module(name)
        lines += [f"## `{name}`", "", inspect.cleandoc(module.__doc__ or "").strip(), ""]
        for member, obj in _members(module):
            kind = "class" if inspect.isclass(obj) else "def"
            lines += [f"### `{member}`", "", "```python", f"{kind} {member}{_signature(obj)}", "```", "",
                      inspect.cleandoc(obj.__doc__ or "").strip(), ""]
    return "\n".join(line.rstrip() for line in lines).rstrip() + "\n"


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--check", action="store_true", help="exit 1 if docs/api-reference.md is out of date")
    args = p.parse_args(argv)
    text = render()
    if args.check:
        if not OUT.exists() or OUT.read_text() != text:
            print(f"{OUT.relative_to(ROOT)} is out of date: run python tools/api_reference.py", file=sys.stderr)
            return 1
        return 0
    OUT.write_text(text)
    print(f"wrote {OUT.relative_to(ROOT)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
