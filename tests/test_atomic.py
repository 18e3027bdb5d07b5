import json
import os
import pathlib
import subprocess

import pytest

from benchmark.atomic import (
    ASIDE_MARKER,
    OUTPUT_MARKER,
    STAGING_MARKER,
    OutputFolderError,
    atomic_path,
    check_cache,
    check_file_out,
    check_out,
    is_owned,
    is_replaceable,
    remove_stale_temporaries,
    staged_folder,
    staging_folder,
    swap_folder,
    user_cache,
    write_marker,
    write_text,
)


def test_write_text_replaces_the_file(tmp_path):
    p = tmp_path / "sub" / "a.json"
    write_text(p, "one")
    write_text(p, "two")
    assert p.read_text() == "two"
    assert [f.name for f in p.parent.iterdir()] == ["a.json"]


def test_a_failed_write_keeps_the_old_file_and_leaves_no_temporary(tmp_path):
    p = tmp_path / "a.txt"
    p.write_text("old")
    with pytest.raises(KeyboardInterrupt):
        with atomic_path(p) as tmp:
            assert tmp.parent == tmp_path and tmp.name.startswith(".tmp-a.txt.") and tmp.suffix == ".txt"
            tmp.write_text("half")
            raise KeyboardInterrupt
    assert p.read_text() == "old"
    assert [f.name for f in tmp_path.iterdir()] == ["a.txt"]


def test_staged_folder_replaces_the_output_whole_or_leaves_it_as_it_was(tmp_path):
    out = tmp_path / "out"
    with staged_folder(out) as tmp:
        (tmp / "a.txt").write_text("first")
        assert not out.exists()  # nothing in place until the block ends
    assert (out / "a.txt").read_text() == "first" and is_owned(out)
    for error in (RuntimeError("boom"), KeyboardInterrupt()):
        with pytest.raises(type(error)):
            with staged_folder(out) as tmp:
                (tmp / "a.txt").write_text("half")
                (tmp / "b.txt").write_text("half")
                raise error
        assert sorted(f.name for f in out.iterdir()) == sorted(["a.txt", OUTPUT_MARKER])
        assert (out / "a.txt").read_text() == "first"
        assert [f.name for f in tmp_path.iterdir()] == ["out"]  # the staging folder is gone
    with staged_folder(out) as tmp:
        (tmp / "b.txt").write_text("second")
    assert sorted(f.name for f in out.iterdir()) == sorted(["b.txt", OUTPUT_MARKER])
    assert [f.name for f in tmp_path.iterdir()] == ["out"]


def test_swap_folder_replaces_a_folder_whole_and_leaves_nothing_behind(tmp_path):
    from benchmark.atomic import OUTPUT_MARKER, swap_folder, write_marker

    dest = tmp_path / "out"
    dest.mkdir()
    (dest / "old.txt").write_text("old")
    write_marker(dest)  # an earlier run's output
    new = tmp_path / ".out.tmp"
    new.mkdir()
    (new / "scores.json").write_text("{}")
    assert swap_folder(new, dest) == dest
    assert sorted(p.name for p in dest.iterdir()) == sorted([OUTPUT_MARKER, "scores.json"])  # nothing of the old folder
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out"]  # no temporary or old folder left
    fresh = tmp_path / ".fresh"
    fresh.mkdir()
    swap_folder(fresh, tmp_path / "first")
    assert (tmp_path / "first").is_dir() and not fresh.exists()


def test_an_output_folder_with_the_users_files_is_refused_and_kept(tmp_path):
    import pytest

    from benchmark.atomic import (
        OUTPUT_MARKER,
        OutputFolderError,
        check_out,
        staging_folder,
        swap_folder,
    )

    out = tmp_path / "out"
    out.mkdir()
    check_out(out)  # empty: fine
    (out / "my-notes.txt").write_text("keep me")
    with pytest.raises(OutputFolderError, match="files that fsv-bench did not write"):
        check_out(out)
    with pytest.raises(OutputFolderError, match="files that fsv-bench did not write"):
        check_out(out, replace=False)  # nor written into (a resumed dataset)
    new = staging_folder(out)
    (new / "scores.json").write_text("{}")
    with pytest.raises(OutputFolderError):
        swap_folder(new, out)
    assert (out / "my-notes.txt").read_text() == "keep me" and new.is_dir()
    swap_folder(new, tmp_path / "fresh")
    assert (tmp_path / "fresh" / OUTPUT_MARKER).is_file()
    check_out(tmp_path / "fresh")  # fsv-bench's own output: replaced on the next run
    again = staging_folder(tmp_path / "fresh")
    (again / "scores.json").write_text('{"new": 1}')
    swap_folder(again, tmp_path / "fresh")
    assert (tmp_path / "fresh" / "scores.json").read_text() == '{"new": 1}'


def _dead_pid() -> int:
    proc = subprocess.Popen(["true"])
    proc.wait()
    return proc.pid


def _left_by(folder: pathlib.Path, marker: str, pid: int) -> pathlib.Path:
    """A folder as a run of process ``pid`` leaves it: with the proof ``marker`` naming it."""
    folder.mkdir()
    (folder / marker).write_text(json.dumps({"folder": folder.name, "pid": pid}))
    (folder / "scores.json").write_text("{}")
    return folder


def test_the_next_run_removes_a_killed_runs_temporaries_and_keeps_a_live_ones(tmp_path):
    dead = _dead_pid()
    write_marker(tmp_path)  # fsv-bench's folder: its temporaries may go
    (tmp_path / f".tmp-ep.npz.{dead}.abcd1234.npz").write_bytes(b"half")
    (tmp_path / f".tmp-ep.npz.{os.getpid()}.abcd1234.npz").write_bytes(b"being written")
    (tmp_path / "ep.npz").write_bytes(b"complete")
    assert remove_stale_temporaries(tmp_path) == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted([f".tmp-ep.npz.{os.getpid()}.abcd1234.npz", "ep.npz",
                                                                 OUTPUT_MARKER])
    _left_by(tmp_path / f".out.{dead}.x1y2z3", STAGING_MARKER, dead)  # a killed run's staging folder
    _left_by(tmp_path / f".out.{os.getpid()}.live00", STAGING_MARKER, os.getpid())
    new = staging_folder(tmp_path / "out")
    names = {p.name for p in tmp_path.iterdir()}
    assert f".out.{dead}.x1y2z3" not in names and f".out.{os.getpid()}.live00" in names and new.name in names
    assert json.loads((new / STAGING_MARKER).read_text()) == {"folder": new.name, "pid": os.getpid()}


def test_temporaries_in_a_users_folder_are_never_removed(tmp_path):
    """A user's file named like a killed run's temporary stays: a name proves nothing."""
    dead = _dead_pid()
    mine = tmp_path / f".tmp-notes.txt.{dead}.abcd1234.txt"
    mine.write_text("mine")
    assert remove_stale_temporaries(tmp_path) == 0
    (tmp_path / "episodes").mkdir()
    (tmp_path / "episodes" / mine.name).write_text("mine too")
    assert remove_stale_temporaries(tmp_path / "episodes", owner=tmp_path) == 0
    assert mine.read_text() == "mine" and (tmp_path / "episodes" / mine.name).read_text() == "mine too"


def test_a_users_siblings_named_like_staging_or_backup_folders_are_kept(tmp_path):
    """``p/.res.<digits>.backup/`` and ``p/.res.old/`` of the user's survive runs to ``p/res``, with
    and without ``p/res``; the old folder is never renamed into place."""
    dead = _dead_pid()
    backup, old = tmp_path / f".res.{dead}.backup", tmp_path / ".res.old"
    for folder in (backup, old, tmp_path / ".res.2024.backup"):
        folder.mkdir()
        (folder / "data.csv").write_text("precious")
    fake = tmp_path / f".res.{dead}.abcdef12"  # a proof that names another folder proves nothing
    _left_by(fake, STAGING_MARKER, dead)
    (fake / STAGING_MARKER).write_text(json.dumps({"folder": "elsewhere", "pid": dead}))
    target = tmp_path / "elsewhere"  # a link named like a staging folder, to a folder whose proof names the link
    target.mkdir()
    (target / STAGING_MARKER).write_text(json.dumps({"folder": f".res.{dead}.linked", "pid": dead}))
    (target / "data.csv").write_text("precious")
    (tmp_path / f".res.{dead}.linked").symlink_to(target)
    new = staging_folder(tmp_path / "res")  # p/res absent: nothing renamed into place
    assert not (tmp_path / "res").exists()
    swap_folder(new, tmp_path / "res")
    again = staging_folder(tmp_path / "res")  # p/res present
    (again / "scores.json").write_text("{}")
    swap_folder(again, tmp_path / "res")
    for folder in (backup, old, tmp_path / ".res.2024.backup"):
        assert (folder / "data.csv").read_text() == "precious"
    assert (fake / "scores.json").is_file()
    assert (tmp_path / f".res.{dead}.linked").is_symlink() and (target / "data.csv").read_text() == "precious"
    assert sorted(p.name for p in (tmp_path / "res").iterdir()) == [OUTPUT_MARKER, "scores.json"]


def test_a_swap_cut_short_is_restored_or_finished_only_where_its_proof_says_so(tmp_path):
    dead = _dead_pid()
    out = tmp_path / "res"
    aside = _left_by(tmp_path / f".res.{dead}.0a1b2c3d.old", ASIDE_MARKER, dead)  # cut between the two renames
    write_marker(aside)
    new = staging_folder(out)
    assert (out / "scores.json").is_file() and not aside.exists() and not (out / ASIDE_MARKER).exists()
    assert is_owned(out)
    aside = _left_by(tmp_path / f".res.{dead}.9f8e7d6c.old", ASIDE_MARKER, dead)  # cut before removing the old one
    live = _left_by(tmp_path / f".res.{os.getpid()}.11111111.old", ASIDE_MARKER, os.getpid())  # a live swap's
    staging_folder(out)
    assert not aside.exists() and live.is_dir() and (out / "scores.json").is_file()
    swap_folder(new, out)
    assert sorted(p.name for p in out.iterdir()) == [OUTPUT_MARKER]


def test_a_symlinked_output_is_refused_and_left_as_it_is(tmp_path):
    target = tmp_path / "target"
    target.mkdir()
    write_marker(target)
    (target / "scores.json").write_text("{}")
    link = tmp_path / "link"
    link.symlink_to(target)
    with pytest.raises(OutputFolderError, match=f"--out {link}: is a symbolic link \\(to {target}\\)"):
        check_out(link)
    new = staging_folder(link)
    with pytest.raises(OutputFolderError, match="symbolic link"):
        swap_folder(new, link)
    assert link.is_symlink() and (target / "scores.json").read_text() == "{}"
    assert {p.name for p in tmp_path.iterdir()} == {"link", new.name, "target"}


def test_the_working_folder_and_its_ancestors_are_refused(tmp_path, monkeypatch):
    work = tmp_path / "work"
    work.mkdir()
    monkeypatch.chdir(work)
    for out in (".", str(work), "..", str(tmp_path)):
        with pytest.raises(OutputFolderError, match="working folder"):
            check_out(out)
    check_out("sub")
    assert list(work.iterdir()) == []


LEGACY = "This folder was written by fsv-bench, which replaces it whole when a command writes here again.\n"


def test_markers_prove_ownership_by_their_content(tmp_path):
    for content, owned in (("", False), ("{}", False), ('{"written_by": "fsv-bench", "token": "x"}', False),
                           (LEGACY, True)):
        folder = tmp_path / f"f{len(content)}"
        folder.mkdir()
        (folder / OUTPUT_MARKER).write_text(content)
        assert is_owned(folder) is owned, content
        assert is_replaceable(folder) is owned
    write_marker(folder)
    token = json.loads((folder / OUTPUT_MARKER).read_text())["token"]
    assert is_owned(folder) and len(token) == 32
    write_marker(folder)
    assert json.loads((folder / OUTPUT_MARKER).read_text())["token"] != token  # random


def test_file_outputs_refuse_an_existing_file_or_a_folder(tmp_path):
    notes = tmp_path / "notes.txt"
    notes.write_text("mine")
    with pytest.raises(OutputFolderError, match=f"--out {notes}: exists; .*--force"):
        check_file_out(notes)
    check_file_out(notes, force=True)
    with pytest.raises(OutputFolderError, match="is a folder"):
        check_file_out(tmp_path, force=True)
    check_file_out(tmp_path / "new" / "model.npz")
    assert notes.read_text() == "mine" and sorted(p.name for p in tmp_path.iterdir()) == ["notes.txt"]


def test_a_cache_apart_from_the_output_only(tmp_path):
    (tmp_path / "file").write_text("x")
    with pytest.raises(OutputFolderError, match="--cache .*file: exists and is not a folder"):
        check_cache(tmp_path / "file", {"--out": tmp_path / "out"})
    for cache, out in (("x", "x"), ("x/cache", "x"), ("x", "x/out"), ("a/../x", "x")):
        with pytest.raises(OutputFolderError, match="one inside the other"):
            check_cache(tmp_path / cache, {"--out": tmp_path / out})
    check_cache(tmp_path / "cache", {"--out": tmp_path / "out"})


def test_after_ctrl_c_no_write_makes_a_removed_folder_again(tmp_path, monkeypatch):
    """A background thread still writing while Ctrl-C's cleanup removes the staging folder: the
    write is refused before anything is made, so the folder stays removed (CI saw one left behind)."""
    from benchmark import interrupt

    gone = tmp_path / ".run.1.x"
    monkeypatch.setattr(interrupt, "interrupted", lambda: True)
    with pytest.raises(KeyboardInterrupt, match="episode.npz not written"):
        with atomic_path(gone / "episode.npz") as tmp:
            tmp.write_bytes(b"late")
    assert not gone.exists() and list(tmp_path.iterdir()) == []
    monkeypatch.setattr(interrupt, "interrupted", lambda: False)
    with atomic_path(gone / "episode.npz") as tmp:  # without Ctrl-C the folder is made as before
        tmp.write_bytes(b"on time")
    assert (gone / "episode.npz").read_bytes() == b"on time"


def test_the_users_cache_is_xdg_cache_home_or_the_home_folders_dot_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert user_cache() == tmp_path / "xdg" / "fsv-bench"
    monkeypatch.delenv("XDG_CACHE_HOME")
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    assert user_cache() == tmp_path / "home" / ".cache" / "fsv-bench"
    monkeypatch.setenv("XDG_CACHE_HOME", "")  # empty: as if unset
    assert user_cache() == tmp_path / "home" / ".cache" / "fsv-bench"
