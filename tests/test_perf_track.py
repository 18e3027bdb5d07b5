"""benchmark.perf.track: the side-by-side run works and names a bad baseline (timings are not tested)."""

import pytest

from benchmark.perf import track
from benchmark.perf.track import ROOT, baseline_fsv, main


def test_a_short_run_against_head_reports_both_versions_and_their_ratio(capsys, monkeypatch):
    """The side-by-side run, its baseline's ``fsv`` this checkout's: an extracted copy (tested
    below) has numba compile its kernels for the copy on a machine's first run, about 50 s of CPU
    in every clean CI run, which this test does not need to see."""
    asked = []
    monkeypatch.setattr(track, "baseline_fsv", lambda rev: asked.append(rev) or ROOT)
    assert main(["--duration", "1.0", "--rounds", "1", "--baseline", "HEAD"]) == 0
    assert asked == ["HEAD"]
    out = capsys.readouterr().out
    assert "this checkout" in out and "baseline HEAD" in out and "speed ratio this / baseline" in out
    rows = [line.split() for line in out.splitlines() if line.startswith(("this checkout", "baseline HEAD"))]
    errors = [float(r[-1]) for r in rows]
    assert len(errors) == 2 and max(errors) < 5.0  # both versions track the box (median error in mm)


def test_a_bad_baseline_is_named_before_any_work():
    with pytest.raises(SystemExit, match="--baseline 'no-such-rev'"):
        main(["--baseline", "no-such-rev"])


def test_a_baseline_is_extracted_once_per_content_into_the_users_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    folder = baseline_fsv("HEAD")
    assert folder.parent == tmp_path / "fsv-bench" / "perf-baselines" and (folder / "fsv" / "track" / "tracker.py").is_file()
    stamp = (folder / "fsv" / "__init__.py").stat().st_mtime_ns
    (folder / "fsv" / "kept.txt").write_text("what a run left (numba's caches)")
    assert baseline_fsv("HEAD") == folder and (folder / "fsv" / "kept.txt").exists()  # not extracted again
    assert (folder / "fsv" / "__init__.py").stat().st_mtime_ns == stamp
    assert [p.name for p in folder.parent.iterdir()] == [folder.name]  # no temporary folder left
    with pytest.raises(SystemExit, match="--baseline 'no-such-rev'"):
        baseline_fsv("no-such-rev")
