"""The camera's streams end to end: the main command, export, the Node reader and a method that reads colour."""

import contextlib
import io
import json
import multiprocessing
import pathlib
import shutil
import subprocess
import sys

import numpy as np
import pytest
from tiny_suite import TINY

from benchmark.atomic import OUTPUT_MARKER, write_marker
from benchmark.camera.episode_file import load_episode, save_episode
from benchmark.camera.render import render
from benchmark.commands.cli import build_parser, main, method_spec_from_args
from benchmark.commands.digests import colour_digest, stage_digests
from benchmark.commands.pictures.depth_preview import write_colour_preview, write_preview
from benchmark.commands.stages import render as render_stage
from benchmark.commands.stages import track as track_stage
from benchmark.errors import RenderError
from benchmark.exchange import load_camera_input
from benchmark.method import run_method
from benchmark.method.run import camera_input_and_knowledge
from benchmark.suites import SUITES
from benchmark.world.simulate import simulate
from fsv.types import DepthRecording

ROOT = pathlib.Path(__file__).resolve().parents[1]
NODE = shutil.which("node")


@pytest.fixture(scope="module")
def colour_run(tmp_path_factory):
    """``fsv-bench --task lift --duration 1 --streams depth,colour --no-gif`` (the reference method,
    which reads no colour): ``(output folder, the scenarios whose colour was started beside the
    later stages, the printed lines)``."""
    started = []
    real = render_stage._start_colour
    out = tmp_path_factory.mktemp("colour") / "run"
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(render_stage, "_start_colour",
                   lambda record, drawn: started.append(record.scenario) or real(record, drawn))
        buf = io.StringIO()
        with contextlib.redirect_stdout(buf):
            # the verdict of a 1 s lift may fail; the files are what is checked
            assert _colour_run(out) in (0, 1)
    assert not multiprocessing.active_children()  # no worker outlives the command
    return out, started, buf.getvalue().splitlines()


def test_the_main_command_records_colour_keypoints_and_masks_when_asked(colour_run):
    out, _, printed = colour_run
    assert any("31 colour frames 640x480, exposure 16.7 ms" in line for line in printed)
    ep = load_episode(out / "episode.npz")
    assert ep.colour.rgb.shape == (31, 480, 640, 3) and ep.colour.rgb.dtype == np.uint8
    assert ep.colour_labels.shape == (31, 480, 640)
    assert ep.annotations.keypoints_world.shape == (31, 21, 3)
    for stream, (H, W) in (("depth", (240, 320)), ("colour", (480, 640))):
        labels = ep.annotations.streams[stream]
        assert labels.keypoints_uv.shape == (31, 21, 2) and labels.keypoint_visibility.shape == (31, 21)
        assert set(np.unique(labels.keypoint_visibility)) <= {0, 1, 2, 3, 4}
        assert labels.cam_t_m2c.shape == (31, 3) and labels.contact_force_cam.shape == (31, 5, 3)
        # the box centre lies 0.4-0.8 m in front of either camera (BOP's millimetres)
        assert 400 < np.median(labels.cam_t_m2c[:, 2]) < 800
    # the colour camera sits 2.5 cm beside the depth camera: the same box, a few pixels apart, in another image
    assert np.mean(ep.colour_labels == 2) > 0.01 and (ep.labels.shape[1:], ep.colour_labels.shape[1:]) == ((240, 320), (480, 640))
    summary = json.loads((out / "summary.json").read_text())
    assert summary["colour"]["skin_tone_monk"] in range(1, 11) and summary["digests"]["colour"]
    assert json.loads((out / "options.json").read_text())["options"]["streams"] == ["depth", "colour"]
    assert (out / "colour_preview.png").stat().st_size > 10_000


def _colour_run(out, *argv) -> int:
    return main(["--task", "lift", "--duration", "1", "--streams", "depth,colour", "--quiet", "--no-gif",
                 "--out", str(out), *argv])


def test_the_colour_rendered_beside_the_later_stages_has_the_serial_paths_bytes(colour_run, tmp_path):
    """A depth-only method: the colour is rendered in a forked child beside the depth and the
    tracker, and the episode file written by a thread; every byte and digest is the serial path's."""
    out, started, printed = colour_run
    assert len(started) == 1  # taken
    depth_line = next(i for i, line in enumerate(printed) if line.startswith("render: 31 depth frames"))
    assert printed[depth_line + 1].startswith("render: 31 colour frames 640x480")  # in the serial path's place
    # the serial path: both streams rendered at once in this process, then written
    scenario = load_episode(out / "episode.npz").scenario
    episode = render(simulate(scenario), streams=("depth", "colour"))
    serial = save_episode(episode, tmp_path / "serial" / "episode.npz")
    write_colour_preview(episode.colour.rgb, episode.colour.fps, tmp_path / "serial")
    for name in ("episode.npz", "colour_preview.png"):
        assert (out / name).read_bytes() == (serial.parent / name).read_bytes(), name
    summary = json.loads((out / "summary.json").read_text())
    block, _ = render_stage.colour_summary(scenario, episode.colour, out)
    assert summary["colour"] == json.loads(json.dumps(block))
    keys = list(summary)
    assert keys[keys.index("render") + 1] == "colour"  # the block in its place too
    assert summary["digests"]["colour"] == colour_digest(episode.colour)
    assert list(summary["digests"]) == ["truth", "depth", "colour", "tracking", "kinematics", "nominal_forces",
                                        "final_forces"]


def test_a_failure_of_the_colour_beside_the_later_stages_is_one_line_and_leaves_the_output_as_it_was(
        tmp_path, monkeypatch, capsys):
    def broken(episode, **kwargs):
        raise RenderError("planted: the colour renderer failed")

    monkeypatch.setattr(render_stage, "render_colour_stream", broken)  # seen by the forked child
    out = tmp_path / "run"
    out.mkdir()
    write_marker(out)
    (out / "note.txt").write_text("the previous output")
    assert _colour_run(out, "--force", "--no-pictures") == 1
    err = capsys.readouterr().err
    assert err == "fsv-bench: failed: background work failed: colour (RenderError: planted: the colour renderer failed)\n"
    assert sorted(p.name for p in out.iterdir()) == [OUTPUT_MARKER, "note.txt"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run"]  # nothing half-written beside it
    assert not multiprocessing.active_children()


def test_a_method_that_reads_colour_gets_it_rendered_before_tracking(tmp_path, monkeypatch):
    def not_beside(record, drawn):
        raise AssertionError("the colour of a method that reads it was left to render beside the tracker")

    monkeypatch.setattr(render_stage, "_start_colour", not_beside)
    out = tmp_path / "run"
    assert _colour_run(out, "--method", f"{ROOT / 'examples' / 'skin_colour.py'}:method", "--no-pictures") in (0, 1)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["colour"]["frames"] == 31 and summary["digests"]["colour"]
    assert load_episode(out / "episode.npz").colour.num_frames == 31


@pytest.fixture(scope="module")
def depth_only_run(tmp_path_factory):
    """``fsv-bench --task lift --duration 1`` (the reference method, depth only, the GIF too):
    ``(output folder, the depth types handed to the method, the printed lines)``."""
    handed = []
    real = track_stage.run_method
    out = tmp_path_factory.mktemp("depth-only") / "run"
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(track_stage, "run_method",
                   lambda spec, episode, **kw: handed.append(type(kw["inputs"].depth)) or real(spec, episode, **kw))
        buf = io.StringIO()
        with contextlib.redirect_stdout(buf):
            assert main(["--task", "lift", "--duration", "1", "--quiet", "--out", str(out)]) in (0, 1)
    assert not multiprocessing.active_children()
    return out, handed, buf.getvalue().splitlines()


def test_the_depth_rendered_beside_the_tracker_has_the_serial_paths_bits(depth_only_run, tmp_path):
    """A depth-only method: a forked child renders the depth frame after frame while the tracker
    reads each frame once it is there (an ``fsv.types.DepthRecording``); every file, block, line and
    digest is the serial path's (the depth rendered, then tracked, in this process)."""
    out, handed, printed = depth_only_run
    assert handed == [DepthRecording]
    summary = json.loads((out / "summary.json").read_text())
    # the serial path: the depth rendered in this process, its preview drawn, the method run on it
    scenario = load_episode(out / "episode.npz").scenario
    episode = render(simulate(scenario))
    serial = tmp_path / "serial"
    save_episode(episode, serial / "episode.npz")
    write_preview(episode.depth.depth_m, episode.depth.fps, serial)
    for name in ("episode.npz", "depth_preview.png", "depth.gif"):
        assert (out / name).read_bytes() == (serial / name).read_bytes(), name
    block, line = render_stage.render_summary(scenario, episode.depth, episode.labels, out, True)
    assert summary["render"] == json.loads(json.dumps(block)) and line in printed
    assert list(summary).index("render") == list(summary).index("world") + 1  # the block in its place
    spec = method_spec_from_args(build_parser().parse_args([]))
    inputs, _ = camera_input_and_knowledge(episode, 1.0, spec.knowledge, spec.protocol)
    estimate = run_method(spec, episode, inputs=inputs)
    assert summary["digests"] == stage_digests(episode, estimate)  # the depth, the tracking and every later stage


def test_a_failure_of_the_depth_beside_the_tracker_is_one_line_and_leaves_the_output_as_it_was(
        tmp_path, monkeypatch, capsys):
    def broken(episode, **kwargs):
        raise RenderError("planted: the depth renderer failed")

    monkeypatch.setattr(render_stage, "render_depth", broken)  # seen by the forked child
    out = tmp_path / "run"
    out.mkdir()
    write_marker(out)
    (out / "note.txt").write_text("the previous output")
    assert main(["--task", "lift", "--duration", "1", "--quiet", "--no-pictures", "--force", "--out", str(out)]) == 1
    assert capsys.readouterr().err == "fsv-bench: failed: depth failed: RenderError: planted: the depth renderer failed\n"
    assert sorted(p.name for p in out.iterdir()) == [OUTPUT_MARKER, "note.txt"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run"]
    assert not multiprocessing.active_children()


def test_a_depth_only_run_renders_no_colour(depth_only_run):
    out, _, _ = depth_only_run
    ep = load_episode(out / "episode.npz")
    assert ep.colour is None and ep.streams == ("depth",) and "colour" not in ep.annotations.streams
    assert "colour" not in json.loads((out / "summary.json").read_text())["digests"]
    assert not (out / "colour_preview.png").exists()


@pytest.fixture(scope="module")
def colour_inputs(tmp_path_factory, tiny_episode_folder):
    tmp = tmp_path_factory.mktemp("colour")
    shutil.copytree(tiny_episode_folder, tmp / "c")  # the depth episode: its colour is rendered onto it
    with pytest.MonkeyPatch.context() as mp:
        mp.setitem(SUITES, "tiny", TINY)
        assert main(["export", "--suite", "tiny", "--streams", "depth,colour", "--out", str(tmp / "in"),
                     "--cache", str(tmp / "c"), "--quiet"]) == 0
    return tmp


def test_export_writes_the_colour_stream_with_its_own_calibration(colour_inputs):
    index = json.loads((colour_inputs / "in" / "suite.json").read_text())
    assert index["streams"] == ["depth", "colour"] and index["formats"]["camera"] == ["fsv-bench-camera", 2]
    camera, meta = load_camera_input(colour_inputs / "in" / index["episodes"][0]["file"])
    assert meta["streams"] == ["depth", "colour"]
    c = camera.colour
    assert c.rgb.shape == (camera.num_frames, 480, 640, 3) and c.calib.width == 640
    np.testing.assert_allclose(c.t_s, np.arange(camera.num_frames) / 30.0)
    # under lab knowledge the colour calibration is the measured one: near the depth camera, not its pose
    offset = np.linalg.norm(c.calib.T_world_cam[:3, 3] - camera.calib.T_world_cam[:3, 3])
    assert 0.02 < offset < 0.03  # the 2.5 cm between the two cameras (measured: 0.025 m)


@pytest.mark.skipif(NODE is None, reason="Node.js is not installed")
def test_the_nodejs_example_reads_the_colour(colour_inputs):
    run = subprocess.run([NODE, str(ROOT / "examples/js/static_method.mjs"), str(colour_inputs / "in"),
                          str(colour_inputs / "est-js")], capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr
    name, frames, depth_sum, word, size, *means = run.stdout.split()
    camera, _ = load_camera_input(colour_inputs / "in" / f"{name}.npz")
    assert (word, size) == ("colour", "640x480")
    expected = camera.colour.rgb.reshape(-1, 3).mean(axis=0)
    np.testing.assert_allclose([float(m) for m in means], expected, atol=1e-4)


def test_a_method_that_reads_colour_is_scored_through_files(colour_inputs, monkeypatch):
    monkeypatch.setitem(SUITES, "tiny", TINY)
    est = colour_inputs / "est"
    run = subprocess.run([sys.executable, str(ROOT / "examples/skin_colour.py"), str(colour_inputs / "in"), str(est)],
                         capture_output=True, text=True, timeout=300, cwd=ROOT)
    assert run.returncode == 0, run.stderr
    assert main(["score", "--suite", "tiny", "--estimates", str(est), "--out", str(colour_inputs / "s"),
                 "--cache", str(colour_inputs / "c"), "--quiet"]) in (0, 1)
    scores = json.loads((colour_inputs / "s" / "scores.json").read_text())
    name = scores["episodes"][0]["episode"]
    from benchmark.exchange.check import check

    assert check(est / f"{name}.npz", colour_inputs / "in" / f"{name}.npz").endswith("(streams: depth, colour)")
    assert scores["method"] == "reference tracker, contacts confirmed by skin colour"
    row = scores["episodes"][0]
    assert row["contact_precision"] > 0.5 and np.isfinite(row["box_pos_err_mm"])


def test_the_skin_rule_tells_skin_from_the_box_and_the_table():
    sys.path.insert(0, str(ROOT / "examples"))
    from skin_colour import skin_mask

    pixels = np.array([[[224, 172, 140], [141, 85, 36], [240, 240, 235], [60, 140, 60], [30, 30, 30]]], np.uint8)
    # a light and a brown skin, white board, green ink, black: only the skins are skin
    np.testing.assert_array_equal(skin_mask(pixels), [[True, True, False, False, False]])
