"""Atomic file writes: a file the benchmark writes is either as it was or complete, never half-written.

Everything is first written to a temporary file in the target's folder (named
``.tmp-<name>.<random><suffix>``, so a crashed run's leftovers are easy to recognise and remove) and
then renamed over the target, which POSIX makes atomic.
"""

from __future__ import annotations

import contextlib
import os
import pathlib
import shutil
import tempfile
from typing import Iterator


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike) -> Iterator[pathlib.Path]:
    """A temporary path to write to; it replaces ``path`` when the block ends without an error.

    Args:
        path: The file to write; its folder is created if needed.

    Yields:
        The temporary file's path (same folder and suffix as ``path``, so writers that infer the
        format from the suffix still do). On any exception, including KeyboardInterrupt, it is
        removed and ``path`` is left untouched.
    """
    path = pathlib.Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".tmp-{path.name}.", suffix=path.suffix)
    os.close(fd)
    try:
        yield pathlib.Path(tmp)
        os.chmod(tmp, 0o644)  # mkstemp makes it private; results are shared like any data file
        os.replace(tmp, path)
    except BaseException:
        pathlib.Path(tmp).unlink(missing_ok=True)
        raise


def swap_folder(new: str | os.PathLike, dest: str | os.PathLike) -> pathlib.Path:
    """Moves the complete folder ``new`` into place as ``dest``, replacing any folder there.

    ``new`` must be on the same file system as ``dest`` (a sibling): the old folder is first renamed
    aside, then ``new`` is renamed in, then the old one is removed, so ``dest`` is always either the
    old or the new folder, never a mixture.
    """
    new, dest = pathlib.Path(new), pathlib.Path(dest)
    os.chmod(new, 0o755)  # mkdtemp makes it private; results are shared
    if not dest.exists():
        os.replace(new, dest)
        return dest
    old = dest.with_name(f".{dest.name}.old")
    shutil.rmtree(old, ignore_errors=True)
    os.replace(dest, old)
    os.replace(new, dest)
    shutil.rmtree(old)
    return dest


def write_bytes(path: str | os.PathLike, data: bytes) -> pathlib.Path:
    """Writes ``data`` to ``path`` atomically and returns the path."""
    with atomic_path(path) as tmp:
        tmp.write_bytes(data)
    return pathlib.Path(path)


def write_text(path: str | os.PathLike, text: str) -> pathlib.Path:
    """Writes ``text`` (UTF-8) to ``path`` atomically and returns the path."""
    return write_bytes(path, text.encode("utf-8"))


def save_figure(fig, path: str | os.PathLike, dpi: int = 110) -> pathlib.Path:
    """Saves a matplotlib figure atomically (format from the suffix) and returns the path."""
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=dpi)
    return pathlib.Path(path)
