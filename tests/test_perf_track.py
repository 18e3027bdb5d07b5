"""benchmark.perf.track: the side-by-side run works and names a bad baseline (timings are not tested)."""

import pytest

from benchmark.perf.track import main


def test_a_short_run_against_head_reports_both_versions_and_their_ratio(capsys):
    assert main(["--duration", "1.0", "--rounds", "1", "--baseline", "HEAD"]) == 0
    out = capsys.readouterr().out
    assert "this checkout" in out and "baseline HEAD" in out and "speed ratio this / baseline" in out
    rows = [line.split() for line in out.splitlines() if line.startswith(("this checkout", "baseline HEAD"))]
    errors = [float(r[-1]) for r in rows]
    assert len(errors) == 2 and max(errors) < 5.0  # both versions track the box (median error in mm)


def test_a_bad_baseline_is_named_before_any_work():
    with pytest.raises(SystemExit, match="--baseline 'no-such-rev'"):
        main(["--baseline", "no-such-rev"])
