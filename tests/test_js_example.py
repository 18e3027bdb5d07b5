"""The Node.js reader and writer (examples/js): a method in a second language through files, scored."""

import json
import pathlib
import shutil
import subprocess

import numpy as np
import pytest
from tiny_suite import TINY

from benchmark.commands.cli import main
from benchmark.suites import SUITES

ROOT = pathlib.Path(__file__).resolve().parents[1]
NODE = shutil.which("node")


@pytest.mark.skipif(NODE is None, reason="Node.js is not installed")
def test_a_nodejs_method_reads_the_camera_inputs_and_its_estimates_are_scored(tmp_path, tiny_cache, monkeypatch, capsys):
    from benchmark.exchange import load_camera_input

    monkeypatch.setitem(SUITES, "tiny", TINY)
    inputs, estimates = tmp_path / "in", tmp_path / "est"
    assert main(["export", "--suite", "tiny", "--out", str(inputs), "--cache", str(tiny_cache), "--quiet"]) == 0
    run = subprocess.run([NODE, str(ROOT / "examples/js/static_method.mjs"), str(inputs), str(estimates)],
                         capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr
    name, frames, depth_sum = run.stdout.split()
    camera, meta = load_camera_input(inputs / f"{name}.npz")
    assert name == meta["episode"] and int(frames) == camera.num_frames
    assert float(depth_sum) == pytest.approx(float(np.sum(camera.depth.depth_m, dtype=np.float64)), rel=1e-9)
    capsys.readouterr()
    assert main(["check", str(estimates / f"{name}.npz"), "--inputs", str(inputs / f"{name}.npz")]) == 0
    assert main(["score", "--suite", "tiny", "--estimates", str(estimates), "--out", str(tmp_path / "s"),
                 "--cache", str(tiny_cache), "--quiet", "--pictures", "worst"]) == 1  # a still box fails the gates
    assert [p.name for p in (tmp_path / "s" / "pictures").iterdir()] == [f"{name}-overlay.png"]  # no forces: no Fig. 5
    scores = json.loads((tmp_path / "s" / "scores.json").read_text())
    assert scores["method"] == "static box (Node.js example)" and scores["episodes"][0]["box_pos_err_mm"] > 10
