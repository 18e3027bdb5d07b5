import pytest

from benchmark.atomic import atomic_path, write_text


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

    from benchmark.atomic import OUTPUT_MARKER, OutputFolderError, check_out, staging_folder, swap_folder

    out = tmp_path / "out"
    out.mkdir()
    check_out(out)  # empty: fine
    (out / "my-notes.txt").write_text("keep me")
    with pytest.raises(OutputFolderError, match="files that fsv-bench did not write"):
        check_out(out)
    check_out(out, replace=False)  # a folder that is resumed, not replaced
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


def test_the_next_run_removes_a_killed_runs_temporaries_and_keeps_a_live_ones(tmp_path):
    import os
    import subprocess

    from benchmark.atomic import remove_stale_temporaries, staging_folder

    dead = subprocess.Popen(["true"])
    dead.wait()
    (tmp_path / f".tmp-ep.npz.{dead.pid}.abcd1234.npz").write_bytes(b"half")
    (tmp_path / f".tmp-ep.npz.{os.getpid()}.abcd1234.npz").write_bytes(b"being written")
    (tmp_path / "ep.npz").write_bytes(b"complete")
    assert remove_stale_temporaries(tmp_path) == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted([f".tmp-ep.npz.{os.getpid()}.abcd1234.npz", "ep.npz"])
    (tmp_path / f".out.{dead.pid}.x1y2z3").mkdir()  # a killed run's staging folder
    (tmp_path / f".out.{os.getpid()}.live00").mkdir()
    new = staging_folder(tmp_path / "out")
    names = {p.name for p in tmp_path.iterdir()}
    assert f".out.{dead.pid}.x1y2z3" not in names and f".out.{os.getpid()}.live00" in names and new.name in names
