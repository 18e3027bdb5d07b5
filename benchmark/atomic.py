"""Atomic file writes: a file the benchmark writes is either as it was or complete, never half-written.

Everything is first written to a temporary file in the target's folder (named
``.tmp-<name>.<pid>.<random><suffix>``, so that the leftovers of a run that was killed are easy to
recognise and remove: :func:`remove_stale_temporaries`) and then renamed over the target, which
POSIX makes atomic. A command's output folder is written the same way: into a staging sibling that
replaces it whole (:func:`staging_folder`, :func:`swap_folder`), and only if fsv-bench wrote it.
"""

from __future__ import annotations

import contextlib
import os
import pathlib
import re
import shutil
import tempfile
from typing import Iterator

from benchmark import interrupt


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
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".tmp-{path.name}.{os.getpid()}.", suffix=path.suffix)
    os.close(fd)
    try:
        yield pathlib.Path(tmp)
        os.chmod(tmp, 0o644)  # mkstemp makes it private; results are shared like any data file
        os.replace(tmp, path)
    except BaseException:
        pathlib.Path(tmp).unlink(missing_ok=True)
        raise


OUTPUT_MARKER = ".fsv-bench-output"
"""The file in every output folder fsv-bench writes. Only such a folder, an empty one or none is
replaced by a command's ``--out``: a folder with anything else in it is refused, so that no file of
the user's is ever deleted."""

_MARKER_TEXT = "This folder was written by fsv-bench, which replaces it whole when a command writes here again.\n"


class OutputFolderError(ValueError):
    """An output folder fsv-bench may not write (a file, unwritable, or holding files fsv-bench did not write)."""


def is_replaceable(folder: str | os.PathLike) -> bool:
    """Whether a command may replace ``folder``: it does not exist, is empty, or fsv-bench wrote it."""
    folder = pathlib.Path(folder)
    return not folder.exists() or (folder.is_dir() and (not any(folder.iterdir()) or (folder / OUTPUT_MARKER).is_file()))


def check_out(out: str | os.PathLike, option: str = "--out", replace: bool = True) -> None:
    """Refuses an output folder before any work (:class:`OutputFolderError`, one line); writes nothing.

    Refused: a file; a folder that cannot be created or written; and, when the command replaces the
    folder whole (``replace``), a non-empty folder without :data:`OUTPUT_MARKER`. Writability is
    tested by creating (and removing) a temporary folder in the nearest existing ancestor, which is
    where the output's temporary folder will be made.
    """
    out = pathlib.Path(out)
    if out.exists() and not out.is_dir():
        raise OutputFolderError(f"{option} {out}: exists and is not a folder")
    if replace and not is_replaceable(out):
        raise OutputFolderError(f"{option} {out}: a folder with files that fsv-bench did not write (it has no "
                                f"{OUTPUT_MARKER}); give a new or empty folder, or move those files away")
    probe = out.parent if str(out.parent) else pathlib.Path(".")
    while not probe.exists():
        probe = probe.parent
    if not probe.is_dir():
        raise OutputFolderError(f"{option} {out}: {probe} is not a folder")
    try:
        os.rmdir(tempfile.mkdtemp(prefix=".fsv-bench-probe.", dir=probe))
    except OSError as e:
        raise OutputFolderError(f"{option} {out}: cannot write in {probe} ({e.strerror or e})") from None


def staging_folder(out: str | os.PathLike) -> pathlib.Path:
    """A new temporary sibling of ``out`` to write a command's output into (then :func:`swap_folder`).

    Named ``.<name>.<pid>.<random>``; the staging folders of runs whose process is gone (killed, or
    interrupted before they could clean up) are removed first.
    """
    out = pathlib.Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    for old in out.parent.glob(f".{out.name}.*.*"):
        pid = old.name[len(out.name) + 2:].split(".")[0]
        if old.is_dir() and pid.isdigit() and not _alive(int(pid)):
            shutil.rmtree(old, ignore_errors=True)
    old = out.with_name(f".{out.name}.old")
    if old.is_dir():  # a swap that was cut short: between its renames (restore), or before removing the old one
        if out.exists():
            shutil.rmtree(old, ignore_errors=True)
        else:
            os.replace(old, out)
    folder = pathlib.Path(tempfile.mkdtemp(prefix=f".{out.name}.{os.getpid()}.", dir=out.parent))
    interrupt.register(folder)
    return folder


_TEMPORARY = re.compile(r"^\.tmp-.+\.(\d+)\.[a-z0-9_]{8}")


def remove_stale_temporaries(folder: str | os.PathLike) -> int:
    """Removes the temporary files (:func:`atomic_path`) in ``folder`` whose writing process is gone;
    returns how many. Those of live processes (another run writing there now) are kept."""
    removed = 0
    for p in pathlib.Path(folder).glob(".tmp-*"):
        m = _TEMPORARY.match(p.name)
        if m and p.is_file() and not _alive(int(m.group(1))):
            p.unlink(missing_ok=True)
            removed += 1
    return removed


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def swap_folder(new: str | os.PathLike, dest: str | os.PathLike, *, replace_any: bool = False) -> pathlib.Path:
    """Moves the complete folder ``new`` into place as ``dest``, replacing any folder there.

    ``new`` must be on the same file system as ``dest`` (a sibling): the old folder is first renamed
    aside, then ``new`` is renamed in, then the old one is removed, so ``dest`` is always either the
    old or the new folder, never a mixture. ``new`` gets :data:`OUTPUT_MARKER`; a ``dest`` that
    holds files fsv-bench did not write is refused (:class:`OutputFolderError`) unless ``replace_any``.
    """
    new, dest = pathlib.Path(new), pathlib.Path(dest)
    if interrupt.interrupted():  # Ctrl-C came and a library swallowed it: the previous output stays
        raise KeyboardInterrupt
    if not replace_any and not is_replaceable(dest):
        raise OutputFolderError(f"{dest} holds files that fsv-bench did not write: it is left as it is")
    (new / OUTPUT_MARKER).write_text(_MARKER_TEXT)
    os.chmod(new, 0o755)  # mkdtemp makes it private; results are shared
    with interrupt.critical():  # Ctrl-C's watchdog waits: never between the two renames
        interrupt.unregister(new)
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
