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
    from benchmark.atomic import swap_folder

    dest = tmp_path / "out"
    dest.mkdir()
    (dest / "old.txt").write_text("old")
    new = tmp_path / ".out.tmp"
    new.mkdir()
    (new / "scores.json").write_text("{}")
    assert swap_folder(new, dest) == dest
    assert sorted(p.name for p in dest.iterdir()) == ["scores.json"]  # nothing of the old folder
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out"]  # no temporary or old folder left
    fresh = tmp_path / ".fresh"
    fresh.mkdir()
    swap_folder(fresh, tmp_path / "first")
    assert (tmp_path / "first").is_dir() and not fresh.exists()
