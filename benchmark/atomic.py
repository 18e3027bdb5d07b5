"""Atomic file writes: a file the benchmark writes is either as it was or complete, never half-written.

Everything is first written to a temporary file in the target's folder (named
``.tmp-<name>.<pid>.<random><suffix>``; a killed run's are removed by the next, but only in
fsv-bench's own folders: :func:`remove_stale_temporaries`) and then renamed over the target, which
POSIX makes atomic. A command's output folder is written the same way: into a staging sibling that
replaces it whole (:func:`staging_folder`, :func:`swap_folder`), and only if fsv-bench wrote it.

Nothing is deleted, renamed or replaced unless a proof inside says fsv-bench wrote it: the
:data:`OUTPUT_MARKER` of its folders (a random token), the :data:`STAGING_MARKER` and
:data:`ASIDE_MARKER` of its temporary folders (naming the folder and its process). Names prove
nothing. File outputs are checked before any work by :func:`check_file_out` (an existing file is
replaced only when the user says so), output folders by :func:`check_out`, caches by :func:`check_cache`.
"""

from __future__ import annotations

import contextlib
import json
import os
import pathlib
import re
import secrets
import shutil
import stat
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

    Raises:
        KeyboardInterrupt: After Ctrl-C (:func:`benchmark.interrupt.interrupted`), before anything is
            made: a background thread still writing while the interrupt removes the run's staging
            folder would otherwise make that folder again, and leave it behind.
    """
    path = pathlib.Path(path)
    if interrupt.interrupted():  # a thread still writing after Ctrl-C must not make a removed staging folder again
        raise KeyboardInterrupt(f"interrupted: {path.name} not written")
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
"""The file in every folder fsv-bench makes (an output folder, a dataset, a cache): a JSON object
with a random token (:func:`write_marker`). It is fsv-bench's proof that it wrote the folder: only
such a folder, an empty one or none is replaced by a command's ``--out`` or written into by
``generate``; a folder with anything else in it is refused, so that no file of the user's is ever
deleted. Names prove nothing: a folder is never recognised as fsv-bench's by its name."""

STAGING_MARKER = ".fsv-bench-staging"
"""The file in a staging folder (:func:`staging_folder`): a JSON object naming that folder and the
process writing it. A later run removes the staging folder only if this proof names it and the
process is gone."""

ASIDE_MARKER = ".fsv-bench-aside"
"""The file :func:`swap_folder` writes into the folder it renames aside: a JSON object naming the
aside folder and the process swapping. A later run restores or removes an aside folder (a swap cut
short) only if this proof names it and the process is gone."""

_LEGACY_MARKER_TEXT = "This folder was written by fsv-bench, which replaces it whole when a command writes here again.\n"
"""The content of :data:`OUTPUT_MARKER` in the folders of fsv-bench 0.x before the token (the
committed results among them): still accepted as proof, since no user writes this exact text."""

_MARKER_NOTE = "This folder was written by fsv-bench, which replaces it whole when a command writes here again."
_MAX_PROOF_BYTES = 4096


class OutputFolderError(ValueError):
    """An output fsv-bench may not write (a file, unwritable, a link, or holding files fsv-bench did not write)."""


OUT_AS_IT_WAS = "--out is as it was"
"""What Ctrl-C leaves of a sub-command whose output is written whole (:func:`staged_folder`,
:func:`atomic_path`), as its ``INTERRUPTED`` line says it."""

OUT_AS_IT_WAS_EPISODES_CACHED = (f"{OUT_AS_IT_WAS}; the episodes rendered so far stay in the cache, where the same "
                                 "command again finds them")
"""The same, for a sub-command that renders a suite's episodes into the episode cache first."""


def write_marker(folder: str | os.PathLike) -> pathlib.Path:
    """Writes :data:`OUTPUT_MARKER` (a new random token) into ``folder``, which fsv-bench made; returns its path."""
    marker = pathlib.Path(folder) / OUTPUT_MARKER
    _write_json(marker, {"written_by": "fsv-bench", "token": secrets.token_hex(16), "note": _MARKER_NOTE})
    return marker


def is_owned(folder: str | os.PathLike) -> bool:
    """Whether ``folder`` is a real folder (not a link) holding fsv-bench's :data:`OUTPUT_MARKER`."""
    folder = pathlib.Path(folder)
    if folder.is_symlink() or not folder.is_dir():
        return False
    text = _read_proof(folder / OUTPUT_MARKER)
    if text is None:
        return False
    if text == _LEGACY_MARKER_TEXT:
        return True
    doc = _json_object(text)
    token = doc.get("token") if doc else None
    return (doc is not None and doc.get("written_by") == "fsv-bench" and isinstance(token, str)
            and re.fullmatch(r"[0-9a-f]{32}", token) is not None)


def is_replaceable(folder: str | os.PathLike) -> bool:
    """Whether a command may replace ``folder``: it does not exist, or is a real folder (not a link)
    that is empty or fsv-bench's (:func:`is_owned`)."""
    folder = pathlib.Path(folder)
    if folder.is_symlink():
        return False
    return not folder.exists() or (folder.is_dir() and (not any(folder.iterdir()) or is_owned(folder)))


def check_out(out: str | os.PathLike, option: str = "--out", replace: bool = True) -> None:
    """Refuses an output folder before any work (:class:`OutputFolderError`, one line); writes nothing.

    Refused: a symbolic link (it would be replaced by a folder; the link and its target are named);
    a file; a folder that cannot be created or written; a non-empty folder without fsv-bench's
    :data:`OUTPUT_MARKER`, whether the command replaces it whole (``replace``) or writes into it (a
    resumed dataset); and, when it replaces it, the working folder or one holding it (the shell
    would be left in a deleted folder). Writability is tested by creating (and removing) a temporary
    folder in the nearest existing ancestor, which is where the output's temporary folder will be made.
    """
    out = pathlib.Path(out)
    if out.is_symlink():
        raise OutputFolderError(f"{option} {out}: is a symbolic link (to {os.readlink(out)}); give the folder "
                                "itself, not a link to it")
    if out.exists() and not out.is_dir():
        raise OutputFolderError(f"{option} {out}: exists and is not a folder")
    if replace and _holds_cwd(out):
        raise OutputFolderError(f"{option} {out}: is the working folder or holds it, which the command would "
                                f"replace whole; give a folder inside it, e.g. {option} {out / 'out'}")
    if not is_replaceable(out):
        raise OutputFolderError(f"{option} {out}: a folder with files that fsv-bench did not write (it has no "
                                f"{OUTPUT_MARKER}); give a new or empty folder, or move those files away")
    _check_writable(out, option)


def check_file_out(path: str | os.PathLike, option: str = "--out", force: bool = False) -> None:
    """Refuses a file to write before any work (:class:`OutputFolderError`, one line); writes nothing.

    Refused: a folder (or a link to one); an existing file (or link) unless ``force`` (the user's
    ``--force``: "replace it"); a file whose folder cannot be created or written.
    """
    path = pathlib.Path(path)
    if path.is_dir():
        raise OutputFolderError(f"{option} {path}: is a folder; give the path of a file to write")
    if (path.exists() or path.is_symlink()) and not force:
        raise OutputFolderError(f"{option} {path}: exists; give a new file name, or --force to replace it")
    _check_writable(path, option)


def check_cache(cache: str | os.PathLike, outs: dict) -> None:
    """Refuses an episode cache before any work (:class:`OutputFolderError`, one line): a path that
    exists and is not a folder, or one that is, holds or lies in one of the output folders ``outs``
    (``{option: path}``; the swap that replaces an output would delete the cache, or the cache's
    files would make a new output look foreign)."""
    cache = pathlib.Path(cache)
    if cache.exists() and not cache.is_dir():
        raise OutputFolderError(f"--cache {cache}: exists and is not a folder; give a folder for the episode cache")
    c = cache.resolve()
    for option, out in outs.items():
        o = pathlib.Path(out).resolve()
        if c == o or o in c.parents or c in o.parents:
            raise OutputFolderError(f"--cache {cache} and {option} {out}: the same folder or one inside the other; "
                                    "give them separate folders")


def claim_folder(folder: str | os.PathLike, option: str = "--out", adopt: bool = False) -> pathlib.Path:
    """Makes ``folder`` fsv-bench's to write into (a dataset, a cache): creates it with a new
    :data:`OUTPUT_MARKER` if missing or empty; accepts it if it is fsv-bench's already, or if
    ``adopt`` (the caller has recognised fsv-bench's content, e.g. a dataset of an earlier version)
    and then marks it. Raises :class:`OutputFolderError` for anything else; returns the folder."""
    folder = pathlib.Path(folder)
    if is_owned(folder):
        return folder
    if folder.is_symlink() or (folder.exists() and not folder.is_dir()):
        check_out(folder, option, replace=False)  # its one-line error
    if folder.is_dir() and any(folder.iterdir()) and not adopt:
        raise OutputFolderError(f"{option} {folder}: a folder with files that fsv-bench did not write (it has no "
                                f"{OUTPUT_MARKER}); give a new or empty folder, or move those files away")
    folder.mkdir(parents=True, exist_ok=True)
    write_marker(folder)
    return folder


def staging_folder(out: str | os.PathLike) -> pathlib.Path:
    """A new temporary sibling of ``out`` to write a command's output into (then :func:`swap_folder`).

    Named ``.<name>.<pid>.<random>`` and holding :data:`STAGING_MARKER`, which names it. Before it
    is made, what killed runs left beside ``out`` is cleaned up, where a proof inside says fsv-bench
    left it and its process is gone: staging folders are removed; a folder a swap renamed aside
    (:data:`ASIDE_MARKER`) is removed if ``out`` exists, else renamed back into place. Folders
    without such a proof, whatever their names, are never touched.
    """
    out = pathlib.Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    _clean_up_after_dead_runs(out)
    with interrupt.deferred():  # registered before Ctrl-C can unwind the caller (interrupt.exit_now removes it)
        folder = pathlib.Path(tempfile.mkdtemp(prefix=f".{out.name}.{os.getpid()}.", dir=out.parent))
        interrupt.register(folder)
    _write_json(folder / STAGING_MARKER, {"folder": folder.name, "pid": os.getpid()})
    return folder


def _clean_up_after_dead_runs(out: pathlib.Path) -> None:
    prefix = f".{out.name}."
    for sibling in sorted(out.parent.iterdir()):
        if not sibling.name.startswith(prefix):
            continue
        if sibling.name.endswith(".old"):
            pid = _proof_pid(sibling, ASIDE_MARKER)
            if pid is None or _alive(pid):
                continue
            if out.exists() or out.is_symlink():  # cut short after the new folder came in: the old one goes
                _remove_proven(sibling, ASIDE_MARKER)
            else:  # cut short between the two renames: the old folder comes back
                os.replace(sibling, out)
                (out / ASIDE_MARKER).unlink(missing_ok=True)
        else:
            pid = _proof_pid(sibling, STAGING_MARKER)
            if pid is not None and not _alive(pid):
                _remove_proven(sibling, STAGING_MARKER)


_TEMPORARY = re.compile(r"^\.tmp-.+\.(\d+)\.[a-z0-9_]{8}")


def remove_stale_temporaries(folder: str | os.PathLike, owner: str | os.PathLike | None = None) -> int:
    """Removes the temporary files (:func:`atomic_path`) in ``folder`` whose writing process is gone;
    returns how many. Those of live processes (another run writing there now) are kept, and nothing
    is removed unless ``owner`` (default: ``folder`` itself), the folder that holds ``folder``, is
    fsv-bench's (:func:`is_owned`): in a user's folder a name proves nothing."""
    if not is_owned(folder if owner is None else owner):
        return 0
    removed = 0
    for p in pathlib.Path(folder).glob(".tmp-*"):
        m = _TEMPORARY.match(p.name)
        if m and p.is_file() and not p.is_symlink() and not _alive(int(m.group(1))):
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
    except OverflowError:
        return False
    return True


def swap_folder(new: str | os.PathLike, dest: str | os.PathLike, *, replace_any: bool = False) -> pathlib.Path:
    """Moves the complete folder ``new`` into place as ``dest``, replacing any folder there.

    ``new`` must be on the same file system as ``dest`` (a sibling): the old folder gets
    :data:`ASIDE_MARKER` and is renamed aside (``.<name>.<pid>.<random>.old``), then ``new`` is
    renamed in, then the old one is removed, so ``dest`` is always either the old or the new folder,
    never a mixture. ``new`` gets a new :data:`OUTPUT_MARKER`. Refused
    (:class:`OutputFolderError`): a ``dest`` that is a symbolic link, and, unless ``replace_any``,
    one that holds files fsv-bench did not write.
    """
    new, dest = pathlib.Path(new), pathlib.Path(dest)
    if interrupt.interrupted():  # Ctrl-C came and a library swallowed it: the previous output stays
        raise KeyboardInterrupt
    if dest.is_symlink():
        raise OutputFolderError(f"{dest} is a symbolic link (to {os.readlink(dest)}): it is left as it is")
    if not replace_any and not is_replaceable(dest):
        raise OutputFolderError(f"{dest} holds files that fsv-bench did not write: it is left as it is")
    write_marker(new)
    (new / STAGING_MARKER).unlink(missing_ok=True)
    os.chmod(new, 0o755)  # mkdtemp makes it private; results are shared
    with interrupt.critical():  # Ctrl-C's watchdog waits: never between the two renames
        interrupt.unregister(new)
        if not dest.exists():
            os.replace(new, dest)
            return dest
        aside = dest.with_name(f".{dest.name}.{os.getpid()}.{secrets.token_hex(4)}.old")
        _write_json(dest / ASIDE_MARKER, {"folder": aside.name, "pid": os.getpid()})
        os.replace(dest, aside)
        os.replace(new, dest)
    _remove_proven(aside, ASIDE_MARKER)
    return dest


def _write_json(path: pathlib.Path, doc: dict) -> None:
    with atomic_path(path) as tmp:
        tmp.write_text(json.dumps(doc) + "\n")


def _read_proof(path: pathlib.Path) -> str | None:
    """The text of a proof file: a regular file (not a link) of at most a few kB, else None."""
    try:
        st = path.lstat()
        if not stat.S_ISREG(st.st_mode) or st.st_size > _MAX_PROOF_BYTES:
            return None
        return path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError):
        return None


def _json_object(text: str) -> dict | None:
    try:
        doc = json.loads(text)
    except ValueError:
        return None
    return doc if isinstance(doc, dict) else None


def _proof_pid(folder: pathlib.Path, marker: str) -> int | None:
    """The process ID in ``folder``'s proof ``marker`` if ``folder`` is a real folder (not a link)
    and the proof names it; else None."""
    if folder.is_symlink() or not folder.is_dir():
        return None
    text = _read_proof(folder / marker)
    doc = None if text is None else _json_object(text)
    if doc is None or doc.get("folder") != folder.name:
        return None
    pid = doc.get("pid")
    return pid if isinstance(pid, int) and not isinstance(pid, bool) and pid > 0 else None


def _remove_proven(folder: pathlib.Path, marker: str) -> None:
    """Removes a folder fsv-bench's proof ``marker`` names, the proof last (a removal cut short
    leaves the proof, and the next run finishes it)."""
    for child in folder.iterdir():
        if child.name == marker:
            continue
        if child.is_dir() and not child.is_symlink():
            shutil.rmtree(child, ignore_errors=True)
        else:
            child.unlink(missing_ok=True)
    (folder / marker).unlink(missing_ok=True)
    with contextlib.suppress(OSError):
        folder.rmdir()


def _holds_cwd(out: pathlib.Path) -> bool:
    o, cwd = out.resolve(), pathlib.Path.cwd().resolve()
    return o == cwd or o in cwd.parents


def _check_writable(out: pathlib.Path, option: str) -> None:
    probe = out.parent if str(out.parent) else pathlib.Path(".")
    while not probe.exists():
        probe = probe.parent
    if not probe.is_dir():
        raise OutputFolderError(f"{option} {out}: {probe} is not a folder")
    try:
        os.rmdir(tempfile.mkdtemp(prefix=".fsv-bench-probe.", dir=probe))
    except OSError as e:
        raise OutputFolderError(f"{option} {out}: cannot write in {probe} ({e.strerror or e})") from None


@contextlib.contextmanager
def staged_folder(out: str | os.PathLike) -> Iterator[pathlib.Path]:
    """A command's output folder, written whole: a :func:`staging_folder` to write into, which
    replaces ``out`` (:func:`swap_folder`) when the block ends without an error.

    Args:
        out: The output folder (checked before any work by :func:`check_out`).

    Yields:
        The staging folder (a sibling of ``out``). On any exception, KeyboardInterrupt included, it
        is removed and ``out`` is left as it was; the exception goes on.
    """
    tmp = staging_folder(out)
    try:
        yield tmp
        swap_folder(tmp, out)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise


def write_folder(out: str | os.PathLike, files: dict) -> pathlib.Path:
    """Writes a command's output folder whole: ``{file name: text}`` through :func:`staged_folder`;
    an error or an interrupt leaves ``out`` as it was. Returns ``out``."""
    with staged_folder(out) as tmp:
        for name, text in files.items():
            write_text(tmp / name, text)
    return pathlib.Path(out)


def user_cache() -> pathlib.Path:
    """fsv-bench's folder under the user's cache: ``$XDG_CACHE_HOME/fsv-bench``, else ``~/.cache/fsv-bench``."""
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return pathlib.Path(base) / "fsv-bench"


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
