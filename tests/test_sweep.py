"""fsv-bench sweep: a suite along one axis, each error against it; bad axes and values exit 2."""

import json

import pytest
from tiny_suite import TINY

from benchmark.commands.cli import main
from benchmark.suites import SUITES


@pytest.fixture
def tiny(monkeypatch):
    monkeypatch.setitem(SUITES, "tiny", TINY)
    return TINY


def test_a_sweep_of_the_initialisation_error_moves_the_tracking_error(tiny, tiny_cache, tmp_path):
    out = tmp_path / "sweep"
    assert main(["sweep", "--suite", "tiny", "--axis", "init", "--values", "0,3", "--out", str(out),
                 "--cache", str(tiny_cache), "--quiet", "--internal", "none", "--knowledge", "exact"]) == 0
    doc = json.loads((out / "sweep.json").read_text())
    assert doc["values"] == [0.0, 3.0] and (out / "sweep.png").stat().st_size > 10_000
    exact, far = (a["box_pos_err_mm"]["median"]["value"] for a in doc["aggregate"])
    assert exact != far and 0 < exact < 1.5  # measured 0.60 mm from the exact start
    assert doc["aggregate"][0]["learned_rel_err_pct"]["median"]["value"] is None  # --internal none: not scored
    assert "| 3.0 |" in (out / "sweep.md").read_text()


def test_a_sweep_of_the_knowledge_tells_the_method_exact_then_measured_values(tiny, tiny_cache, tmp_path):
    out = tmp_path / "sweep"
    assert main(["sweep", "--suite", "tiny", "--axis", "knowledge", "--values", "exact,lab-camera,lab-camera:3",
                 "--out", str(out), "--cache", str(tiny_cache), "--quiet", "--internal", "none"]) == 0
    doc = json.loads((out / "sweep.json").read_text())
    assert doc["values"] == ["exact", "lab-camera", "lab-camera:3"]
    told = [eps[0]["knowledge"] for eps in doc["episodes"]]
    assert [t["knowledge"] for t in told] == ["exact", "lab-camera", "lab-camera:3"]
    assert told[0]["cx_px"]["error"] == 0.0 != told[1]["cx_px"]["error"] and told[1]["mass_kg"]["error"] == 0.0
    assert told[2]["cx_px"]["error"] == pytest.approx(3 * told[1]["cx_px"]["error"], rel=1e-9)  # the same draw, thrice
    exact, lab, worse = (a["box_pos_err_mm"]["median"]["value"] for a in doc["aggregate"])
    assert exact < lab < worse  # the calibration's error moves the box as the method sees it
    # the header names the suite and the method swept, not the first value's
    assert doc["suite"]["name"] == "tiny" and "knowledge" not in doc["method"] and "internal" in doc["method"]
    assert (out / "sweep.md").read_text().startswith("# Sweep of tiny along what the method is told")


@pytest.mark.parametrize("argv, needle", [
    (["--axis", "friction", "--values", "0.5,1"], "--axis 'friction': accepted: noise, mass, fps, init, sensor, hand_surface, grip_control, knowledge"),
    (["--axis", "hand_surface", "--values", "capsules,mesh"], "'mesh' is not a hand surface; accepted: capsules, skin"),
    (["--axis", "knowledge", "--values", "exact,psychic"], "--knowledge 'psychic': accepted: exact, lab"),
    (["--axis", "mass", "--values", "0,x"], "--values '0,x': 'x' is not an integer"),
    (["--axis", "mass", "--values", "0,42"], "mass 42 does not exist"),
    (["--axis", "noise", "--values", "0.01"], "need at least two distinct values"),
    (["--axis", "sensor", "--values", "ds325,sonar"], "sensor must be one of ds325, kinect-v1, ideal, got 'sonar'"),
])
def test_bad_sweeps_exit_2_before_any_work(tiny, tmp_path, capsys, argv, needle):
    assert main(["sweep", "--suite", "tiny", *argv, "--out", str(tmp_path / "o"), "--cache", str(tmp_path / "c")]) == 2
    err = capsys.readouterr().err
    assert needle in err and err.count("\n") == 1 and not (tmp_path / "c").exists()


@pytest.mark.parametrize("argv, needle", [
    (["--axis", "fps", "--values", "30,0.001"], "--values '30,0.001': 0.001 is outside the fps axis's range; accepted: "
                                                "numbers from 10 to 240 Hz"),
    (["--axis", "fps", "--values", "30,inf"], "accepted: numbers from 10 to 240 Hz"),
    (["--axis", "init", "--values", "1,nan"], "--values '1,nan': nan is outside the init axis's range; accepted: "
                                              "numbers from 0 to 10"),
    (["--axis", "init", "--values", "0,-1"], "accepted: numbers from 0 to 10"),
    (["--axis", "init", "--values", "1,1e9"], "accepted: numbers from 0 to 10"),
    (["--axis", "noise", "--values", "0.01,nan"], "accepted: numbers from 0 to 0.1 m"),
    (["--axis", "mass", "--values", "0,-1"], "--values '0,-1': -1 is not a mass index"),
    (["--axis", "noise", "--values", ",".join(str(i / 1e7) for i in range(100_001))],
     "--values: 100,001 values, more than the 100,000 accepted"),
])
def test_every_sweep_value_is_checked_before_any_work_naming_values(tiny, tmp_path, capsys, monkeypatch, argv, needle):
    import time

    def work(*args, **kwargs):
        raise AssertionError("the sweep started its work")

    monkeypatch.setattr("benchmark.suites.evaluate.evaluate", work)
    t0 = time.perf_counter()
    assert main(["sweep", "--suite", "tiny", *argv, "--out", str(tmp_path / "o"), "--cache", str(tmp_path / "c")]) == 2
    assert time.perf_counter() - t0 < 5
    err = capsys.readouterr().err
    assert needle in err and err.count("\n") == 1 and not list(tmp_path.iterdir())


def test_an_infinite_aggregate_is_drawn_at_the_axis_top_without_warnings():
    import warnings

    import numpy as np

    from benchmark.suites.sweep import _capped

    v, lo, hi = np.array([1.0, np.inf]), np.array([0.5, 2.0]), np.array([1.5, np.inf])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        cv, clo, chi, beyond = _capped(v, lo, hi)
        yerr = [cv - clo, chi - cv]
    assert beyond.tolist() == [False, True] and cv[1] == chi[1] == 2.0 + 0.15 * 2.0
    assert np.isfinite(yerr).all() and (np.array(yerr) >= 0).all()
