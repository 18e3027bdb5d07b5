"""The project's compiled kernels (numba), cached on disk under a key that sees every file they read.

numba caches a compiled function beside its source file (``__pycache__``) and keys the cache by that
one file's modification time and size. What the function takes from other files is compiled into
it, the kernels it calls and the constants it reads, but is not in the key (numba's documentation,
"Notes on caching": changes to other files are not detected). A change to
``fsv/track/hand_system.py`` alone, for instance, left ``fsv.track.hand.lm.solve`` running the old
normal equations from its cache, with no warning: after an edit, a ``git pull`` or a checkout of
another commit, a tracker that is not the code's.

:func:`kernel` compiles a function as ``numba.njit(cache=True, nogil=True, error_model="numpy")``
does, and keys its cache by :func:`sources_digest`: the bytes of its own module and of every module
of the same installation that it imports, directly or not (for the tracker's solver, 7 files). A
change to any of them compiles the function again, once (the first process that needs it writes
the new cache, the later ones load it); nothing else does.
"""

from __future__ import annotations

import functools
import hashlib
import pathlib
import re

import numba

_FROM = re.compile(r"^[ \t]*from[ \t]+([\w.]+)[ \t]+import[ \t]+(\([^)]*\)|[^\n]*)", re.M)
_IMPORT = re.compile(r"^[ \t]*import[ \t]+([^\n]*)", re.M)


def _names(text: str) -> list[str]:
    """The names of an import list: ``a, b as c`` or ``(a,\\n b)`` -> ``["a", "b"]``."""
    text = re.sub(r"#[^\n]*", "", text)  # comments
    return [n.split()[0] for n in text.strip("()\n ").replace("\n", " ").split(",") if n.strip()]


def _file_of(root: pathlib.Path, module: str) -> pathlib.Path | None:
    """The source file of ``module`` under ``root`` (the folder holding its top package), or None."""
    path = root.joinpath(*module.split("."))
    for candidate in (path.with_suffix(".py"), path / "__init__.py"):
        if candidate.is_file():
            return candidate
    return None


def _imported_files(root: pathlib.Path, source: pathlib.Path) -> set[pathlib.Path]:
    """The files under ``root`` of the modules that ``source`` imports (at any depth of its code),
    read from its import lines (no import is run). The packages above an imported module run when
    it is imported, but a kernel reads only the names it imports, so they count only where it
    imports from them."""
    text = source.read_text()
    modules = []
    for package, names in _FROM.findall(text):
        modules.append(package)
        modules += [f"{package}.{n}" for n in _names(names)]  # a name may be a sub-module
    for names in _IMPORT.findall(text):
        modules += _names(names)
    files = set()
    for module in modules:
        if module.startswith("."):  # a relative import: the project writes none
            continue
        found = _file_of(root, module)
        if found is not None:
            files.add(found)
    return files


def _root_of(source: pathlib.Path) -> pathlib.Path:
    """The folder holding the top package of the module in ``source``."""
    folder = source.parent
    while (folder / "__init__.py").is_file():
        folder = folder.parent
    return folder


@functools.lru_cache(maxsize=None)
def sources_of(source: pathlib.Path) -> tuple[pathlib.Path, ...]:
    """The files whose code a kernel of the module in ``source`` may be compiled from: the file
    itself and those of the modules of its installation that it imports, directly or not, sorted."""
    source = pathlib.Path(source).resolve()
    root = _root_of(source)
    seen, todo = {source}, [source]
    while todo:
        for found in _imported_files(root, todo.pop()):
            if found not in seen:
                seen.add(found)
                todo.append(found)
    return tuple(sorted(seen))


@functools.lru_cache(maxsize=None)
def sources_digest(source: pathlib.Path) -> str:
    """sha256 over the paths (relative to the installation) and bytes of :func:`sources_of` ``source``."""
    files = sources_of(pathlib.Path(source).resolve())
    root = _root_of(files[0])
    h = hashlib.sha256()
    for path in files:
        data = path.read_bytes()
        h.update(f"{path.relative_to(root).as_posix()}\0{len(data)}\0".encode())
        h.update(data)
    return h.hexdigest()


def kernel(fn=None, **options):
    """``numba.njit(cache=True, nogil=True, error_model="numpy", **options)`` with its cache keyed
    by :func:`sources_digest` of the function's module. As ``@kernel`` or ``@kernel(inline="always")``.
    """
    options = {"cache": True, "nogil": True, "error_model": "numpy", **options}
    if fn is None:
        return functools.partial(kernel, **options)
    dispatcher = numba.njit(**options)(fn)
    source = pathlib.Path(fn.__code__.co_filename)
    if options["cache"] and source.is_file():  # (numba caches nothing of a function without a file)
        # numba's index of the function's cache holds this stamp; a cache with another is not loaded
        # (its own stamp is the file's modification time and size)
        dispatcher._cache._cache_file._source_stamp = ("sources", sources_digest(source))
    return dispatcher
