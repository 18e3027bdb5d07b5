"""Loading a user's stage or method named ``module:attribute`` (or ``path/to/file.py:attribute``)."""

from __future__ import annotations

import importlib
import importlib.util
import inspect
import os
import pathlib
import sys


def load_object(spec: str, option: str):
    """The object a ``module:attribute`` spec names, made ready to use.

    ``module`` is imported with the current directory on the import path (as ``python -m`` does);
    ``path/to/file.py`` is loaded from that file. A class is instantiated without arguments; a
    function taking no arguments is called and its result used (a factory); anything else is used
    as it is.

    Args:
        spec: ``module:attribute``, ``module:attribute.sub`` or ``file.py:attribute``.
        option: The option that gave it (for messages), e.g. ``--tracker``.

    Raises:
        ValueError: One line naming the spec and what went wrong (before any expensive work).
    """
    module_name, sep, attribute = str(spec).partition(":")
    if not sep or not module_name or not attribute:
        raise ValueError(f"{option} {spec!r}: expected module:attribute (e.g. mypkg.track:MyTracker) "
                         "or path/to/file.py:attribute")
    try:
        if module_name.endswith(".py"):
            path = pathlib.Path(module_name)
            if not path.is_file():
                raise ValueError(f"{option} {spec!r}: no file {path}")
            name = f"fsv_bench_user_{path.stem}"
            module_spec = importlib.util.spec_from_file_location(name, path)
            module = importlib.util.module_from_spec(module_spec)
            sys.modules[name] = module
            module_spec.loader.exec_module(module)
        else:
            if os.getcwd() not in sys.path:
                sys.path.insert(0, os.getcwd())
            module = importlib.import_module(module_name)
    except ValueError:
        raise
    except Exception as e:  # an import error, or the user's module failing as it loads
        raise ValueError(f"{option} {spec!r}: cannot import {module_name}: {type(e).__name__}: {e}") from e
    obj = module
    for part in attribute.split("."):
        if not hasattr(obj, part):
            raise ValueError(f"{option} {spec!r}: {module_name} has no attribute {attribute!r}")
        obj = getattr(obj, part)
    try:
        if isinstance(obj, type):
            obj = obj()
        elif callable(obj) and _takes_no_arguments(obj):
            obj = obj()
    except Exception as e:
        raise ValueError(f"{option} {spec!r}: building it failed: {type(e).__name__}: {e}") from e
    if not callable(obj):
        raise ValueError(f"{option} {spec!r}: {type(obj).__name__} is not callable; a stage is a function or an "
                         "object with __call__")
    return obj


def _takes_no_arguments(fn) -> bool:
    try:
        params = inspect.signature(fn).parameters.values()
    except (TypeError, ValueError):
        return False
    return all(p.default is not p.empty or p.kind in (p.VAR_POSITIONAL, p.VAR_KEYWORD) for p in params)
