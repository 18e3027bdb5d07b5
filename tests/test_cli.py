"""fsv-bench: simulate, save, summarise; bad input is one line, status 2, nothing written."""

import json

import numpy as np
import pytest

from benchmark.atomic import OUTPUT_MARKER, write_marker
from benchmark.camera.episode_file import load_episode
from benchmark.commands.cli import main
from benchmark.commands.entry import run


@pytest.fixture(scope="module")
def pictured_lift(tmp_path_factory):
    """``fsv-bench --task lift --noise 0.005 --duration 1.5 --seed 2 --no-gif``, with its pictures:
    ``(folder, printed lines, exit status)``."""
    import contextlib
    import io

    out = tmp_path_factory.mktemp("pictured") / "run"
    printed = io.StringIO()
    with contextlib.redirect_stdout(printed):
        code = main(PICTURED_LIFT + ["--out", str(out)])
    return out, printed.getvalue().splitlines(), code


PICTURED_LIFT = ["--task", "lift", "--noise", "0.005", "--duration", "1.5", "--seed", "2", "--quiet", "--no-gif"]


def test_run_writes_episode_and_summary(pictured_lift):
    out, lines, code = pictured_lift
    text = "\n".join(lines)
    assert "Newton-Euler residual" in text and "grip while held" in text
    assert "user 0 (u0-average, hand 190 x 85 mm), grasp 0 (g0-four-centred)" in text
    summary = json.loads((out / "summary.json").read_text())
    options = json.loads((out / "options.json").read_text())["options"]  # what a later run to this folder must match
    assert options["seed"] == 2 and options["duration"] == 1.5 and options["protocol"] == "blind" and "out" not in options
    verdict = summary["verdict"]  # the smoke suite's gates on this episode; the exit status follows them
    assert len(verdict["gates"]) == 9 and "p90 net_force_err_n_rms <= 0.5" in [g["name"] for g in verdict["gates"]]
    assert code == (0 if verdict["verdict"] == "pass" else 1)
    assert verdict["method"]["tracker"] == "reference tracker" and f"verdict: {verdict['verdict'].upper()}" in \
        text.replace("verdict: pass", "verdict: PASS")
    # one set of gates in the printout: the verdict's, each with its limit beside the episode's value
    assert "gates hold;" not in text and "gates NOT met" not in text and "gates" not in summary["tracking"]
    # one name per quantity: the tracking block's box error is the verdict's metric of that name
    assert summary["tracking"]["box_pos_err_mm"] == verdict["metrics"]["box_pos_err_mm"]
    assert not [k for k in summary["tracking"] if k.endswith("_median")]
    lines = text.splitlines()
    first = next(i for i, line in enumerate(lines) if line.startswith("verdict: "))
    gate_lines = lines[first + 1:first + 10]
    assert [line.split()[1] for line in gate_lines] == [g["name"].split()[1] for g in verdict["gates"]]
    assert all(line.split()[0] == ("pass" if g["passed"] else "FAIL") for line, g in zip(gate_lines, verdict["gates"]))
    assert "(limit <= 50 %)" in gate_lines[-1] and "learned_rel_err_pct" in gate_lines[-1]
    assert "(limit <= 0.5 N, a suite's 90th percentile)" in gate_lines[6] and "(limit <= 0.3 N)" in gate_lines[5]
    assert "(limit <= 8 mm)" in gate_lines[0]
    person, grasp = summary["scenario"].pop("person"), summary["scenario"].pop("grasp_spec")
    assert summary["scenario"] == {"task": "lift", "user": 0, "grasp": 0, "mass": 0, "sensor": "ds325",
                                   "hand_surface": "skin", "grip_control": "per-digit", "noise_m": 0.005, "seed": 2, "frames": 46, "fps": 30.0}
    assert person["name"] == "u0-average" and not person["drawn"] and person["anatomy"]["hand_length_m"] == 0.19
    assert grasp["name"] == "g0-four-centred" and grasp["family"] == "width-four"
    assert summary["world"]["ne_force_residual_n"] < 0.01
    assert summary["world"]["lift_height_m"] > 0.05
    assert set(summary["timing_s"]) >= {"simulate", "total"}
    from fsv.provenance import provenance

    prov = summary["provenance"]  # where the numbers came from
    now = provenance()
    assert prov["fsv_bench"] == now["fsv_bench"] and prov["dependencies"] == now["dependencies"]
    assert prov["dependencies"]["mujoco"] and prov["dependencies"]["threadpoolctl"]
    assert prov["cpu"] == now["cpu"] and prov["blas"] == now["blas"]
    ep = load_episode(out / "episode.npz")
    assert len(ep.truth.t) == 46
    assert np.isfinite(ep.truth.contact_force).all()


def test_a_broken_tracker_fails_the_verdict_with_exit_1_naming_the_gates(tmp_path, capsys):
    out = tmp_path / "run"
    code = main(["--task", "lift", "--duration", "1.5", "--quiet", "--no-pictures", "--out", str(out),
                 "--tracker", "external_stages:FrozenTracker"])
    err = capsys.readouterr().err
    assert code == 1 and "median box_pos_err_mm <= 8" in err and "median contact_recall >= 0.85" in err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["verdict"]["verdict"] == "fail" and summary["tracking"]["tracker"] == "frozen tracker (a broken example)"
    assert summary["tracking"]["contact_recall"] == 0.0


@pytest.mark.parametrize("argv, needle", [
    (["--tracker", "external_stages:Nope"], "external_stages has no attribute 'Nope'"),
    (["--kinematics", "central", "--differentiator", "gaussian"], "--kinematics central and --differentiator gaussian"),
    (["--internal-model", "missing.npz"], "--internal-model missing.npz: no internal-force model"),
    (["--task", "juggle"], "'juggle'; accepted: lift"),
    (["--user", "-9"], "user must be a non-negative integer, got -9"),
    (["--grasp", "-1"], "grasp must be a non-negative integer, got -1"),
    (["--mass", "42"], "mass 42 does not exist; accepted: 0 (light)"),
    (["--noise", "-0.5"], "got -0.5"),
    (["--duration", "-3"], "duration must be > 0 and <= 120 seconds, got -3.0"),
    (["--duration", "ten"], "invalid float value: 'ten'"),
    (["--sensor", "kinect"], "sensor must be one of ds325, kinect-v1, ideal, got 'kinect'"),
    (["--hand-surface", "mesh"], "hand surface must be one of capsules, skin, skin-rigid, got 'mesh'"),
    (["--grip-control", "fist"], "grip control must be one of whole-hand, per-digit, got 'fist'"),
])
def test_bad_input_is_one_line_status_2_and_writes_nothing(tmp_path, capsys, argv, needle):
    out = tmp_path / "never"
    try:
        code = main(argv + ["--out", str(out), "--quiet"])
    except SystemExit as e:  # argparse's own errors
        code = e.code
    assert code == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and needle in err
    assert not out.exists()


def test_render_stage_writes_the_depth_preview_and_its_summary_block(pictured_lift):
    from PIL import Image

    from benchmark.commands.pictures.depth_preview import COLOUR_BAR_HEIGHT

    out, lines, _ = pictured_lift
    assert "render: 46 depth frames 320x240 at 30 Hz, noise 0.005 m" in "\n".join(lines)  # 1.5 s at 30 Hz, --noise
    block = json.loads((out / "summary.json").read_text())["render"]
    assert block["frames"] == 46 and block["preview"] == ["depth_preview.png"]
    assert 0.5 < block["valid_fraction"] < 1 and block["box_pixels_median"] > 1000
    with Image.open(out / "depth_preview.png") as png:
        assert png.size == (6 * 320 + 5 * 4, 240 + COLOUR_BAR_HEIGHT)  # frames above a colour bar in metres
    assert not (out / "depth.gif").exists()  # --no-gif
    ep = load_episode(out / "episode.npz")
    assert ep.depth.depth_m.shape == (46, 240, 320) and ep.labels.shape == (46, 240, 320)


def _with_render_stage(monkeypatch, exc):
    """Replaces the render stage of the main command by one that raises ``exc`` (after simulating)."""
    import dataclasses

    import benchmark.commands.cli as cli

    def boom(record, options):
        raise exc

    stages = [dataclasses.replace(s, run=boom) if s.name == "render" else s for s in cli.STAGES]
    monkeypatch.setattr(cli, "STAGES", stages)


def test_a_failing_stage_exits_1_with_one_line(tmp_path, capsys, monkeypatch):
    from benchmark.errors import RenderError

    _with_render_stage(monkeypatch, RenderError("no OpenGL context"))
    code = main(["--task", "lift", "--duration", "1.5", "--quiet", "--out", str(tmp_path / "run")])
    assert code == 1
    err = capsys.readouterr().err
    assert err == "fsv-bench: failed: no OpenGL context\n"
    assert not (tmp_path / "run" / "summary.json").exists()


def test_ctrl_c_exits_130_and_leaves_the_previous_output_as_it_was(tmp_path, capsys, monkeypatch):
    out = tmp_path / "run"
    out.mkdir()
    (out / "summary.json").write_text('{"previous": true}')
    write_marker(out)  # an earlier run's output (of other options: --force)
    _with_render_stage(monkeypatch, KeyboardInterrupt())
    code = main(["--task", "lift", "--duration", "1.5", "--quiet", "--force", "--out", str(out)])
    assert code == 130
    assert "interrupted" in capsys.readouterr().err
    assert [p.name for p in tmp_path.iterdir()] == ["run"]
    assert sorted(p.name for p in out.iterdir()) == sorted([OUTPUT_MARKER, "summary.json"])
    assert (out / "summary.json").read_text() == '{"previous": true}'


@pytest.mark.parametrize("argv, needle", [
    (["--noise", "5"], "noise must be a standard deviation in metres in [0, 0.1], got 5.0"),
    (["--duration", "1e9"], "duration must be > 0 and <= 120 seconds, got 1000000000.0"),
    (["--internal-model", "FILE"], "--internal-model FILE"),
    (["--out", "FILE"], "exists and is not a folder"),
    (["--out", "FILE/sub"], "is not a folder"),
    (["--out", "OUT"], "a folder with files that fsv-bench did not write"),  # a folder of the user's: kept
])
def test_bad_input_exits_2_in_seconds_with_one_line_and_touches_nothing(tmp_path, capsys, argv, needle):
    import time

    existing = tmp_path / "file.txt"
    existing.write_text("keep")
    out = tmp_path / "out"
    argv = [a.replace("FILE", str(existing)).replace("OUT", str(out)) for a in argv]
    out.mkdir()
    (out / "summary.json").write_text("old")
    if "--out" not in argv:
        argv += ["--out", str(out)]
    t0 = time.perf_counter()
    assert main(["--task", "lift", "--quiet", *argv]) == 2
    assert time.perf_counter() - t0 < 5
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and needle.replace("FILE", str(existing)) in err
    assert existing.read_text() == "keep" and (out / "summary.json").read_text() == "old"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file.txt", "out"]


def test_the_kinect_preset_runs_end_to_end_and_is_recorded(tmp_path, capsys):
    import json

    out = tmp_path / "kinect"
    code = main(["--task", "lift", "--sensor", "kinect-v1", "--duration", "1.5", "--quiet", "--no-pictures", "--out", str(out)])
    assert code in (0, 1)  # the verdict may fail on a 1.5 s episode; the run itself completes
    summary = json.loads((out / "summary.json").read_text())
    assert summary["scenario"]["sensor"] == "kinect-v1"
    assert summary["tracking"]["box_pos_err_mm"] < 10
    tr = summary["tracking"]  # the frame rate without the first frame and without compiling
    assert tr["first_frame_s"] > 0 and tr["frames_per_s_after_first"] > 0 and tr["compile_s"] >= 0
    assert "first_frame" not in tr["stage_ms_per_frame"]
    assert "frames/s after the first frame, which took" in capsys.readouterr().out


def test_a_drawn_person_grasp_and_view_run_end_to_end_and_are_described(tmp_path):
    """Issue 32's command (`--user 123 --grasp 17 --view 5`), on a 1.5 s lift."""
    import json

    out = tmp_path / "drawn"
    code = main(["--task", "lift", "--user", "123", "--grasp", "17", "--view", "5", "--noise", "0.01",
                 "--duration", "1.5", "--quiet", "--no-pictures", "--out", str(out)])
    assert code in (0, 1)  # the verdict may fail on a 1.5 s episode; the run itself completes
    summary = json.loads((out / "summary.json").read_text())
    sc = summary["scenario"]
    assert (sc["user"], sc["grasp"], sc["person"]["name"], sc["person"]["drawn"]) == (123, 17, "p123-f", True)
    assert 0.15 < sc["person"]["anatomy"]["hand_length_m"] < 0.22  # measured 0.181 m
    assert sc["grasp_spec"]["name"] == "d17-width-tripod" and set(sc["grasp_spec"]["spots"]) == {"thumb", "index", "middle"}
    view = summary["render"]["view"]
    assert view["index"] == 5 and 0.3 < view["distance_m"] < 0.8  # measured 0.488 m, elevation 57 deg
    assert summary["tracking"]["box_pos_err_mm"] < 10


def test_summary_json_is_strict_even_where_a_metric_has_nothing_to_score(tmp_path):
    out = tmp_path / "run"
    main(["--task", "lift", "--duration", "1.5", "--quiet", "--no-pictures", "--out", str(out),
          "--tracker", "external_stages:FrozenTracker"])  # no contacts: contact errors are undefined
    summary = json.loads((out / "summary.json").read_text(),
                         parse_constant=lambda c: pytest.fail(f"non-strict JSON token {c}"))
    assert summary["tracking"]["contact_err_mm_std"] is None


@pytest.mark.parametrize("exc, code, needle", [(KeyboardInterrupt(), 130, "interrupted; the complete episodes are kept"),
                                                ("benchmark", 1, "failed: the box fell")])
def test_subcommands_exit_130_on_ctrl_c_and_1_on_failure(monkeypatch, capsys, exc, code, needle):
    import benchmark.paper.dataset.cli as dataset
    from benchmark.errors import SimulationError

    err = SimulationError("the box fell") if exc == "benchmark" else exc

    def run(args):
        raise err

    monkeypatch.setattr(dataset, "run", run)
    assert main(["generate", "--out", "unused"]) == code
    assert needle in capsys.readouterr().err


def _interrupted_run(args):
    raise KeyboardInterrupt


def test_every_sub_command_says_what_ctrl_c_left_and_train_does_not_promise_a_resume(tmp_path, monkeypatch, capsys):
    """Every sub-command said "complete files are kept, run the same command to resume", which
    `train` (one model file, trained from the start) and `compare` do not do."""
    from benchmark.commands import cli, entry

    lines = {name: entry.subcommand_module(name).INTERRUPTED for name in cli.ALL_SUBCOMMANDS}
    assert all(isinstance(line, str) and line for line in lines.values())
    assert "resume" not in " ".join(lines.values())
    module = entry.subcommand_module("train")
    monkeypatch.setattr(module, "run", _interrupted_run)
    code = cli.run_subcommand(["train", "--data", str(tmp_path), "--out", str(tmp_path / "model.npz")], module)
    assert (code, capsys.readouterr().err) == (
        130, "fsv-bench train: interrupted; --out is as it was (the same command again trains from the start)\n")



def test_the_console_script_ends_the_main_command_after_its_output_is_complete(tmp_path):
    """The main command skips the interpreter's teardown once it has returned (``entry.main_command_done``):
    its output folder is complete and its last lines reach the console."""
    import os
    import subprocess
    import sys

    from benchmark.commands.entry import main_command_done

    assert main_command_done(["--task", "lift"]) and main_command_done([])
    assert not main_command_done(["eval", "--suite", "smoke"])
    out = tmp_path / "run"
    proc = subprocess.run([sys.executable, "-m", "benchmark.commands.entry", "--task", "lift", "--duration", "1.5",
                           "--quiet", "--no-gif", "--out", str(out)], capture_output=True, text=True, timeout=300,
                          env={**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)})
    summary = json.loads((out / "summary.json").read_text())
    assert proc.returncode == (0 if summary["verdict"]["verdict"] == "pass" else 1), proc.stderr
    assert proc.stdout.rstrip().splitlines()[-1].startswith(f"summary: {out / 'summary.json'} (")  # flushed
    assert (out / "episode.npz").exists() and not [p for p in tmp_path.iterdir() if p.name != "run"]
    for picture in ("depth_preview.png", "tracking_overlay.png", "fig4_kinematics.png", "forces_fig5.png"):
        assert (out / picture).stat().st_size > 10_000, picture  # drawn beside the stages, done before the exit


def test_help_lists_the_task_names(capsys):
    from benchmark.world.tasks import TASKS

    with pytest.raises(SystemExit):
        main(["--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "task name: " + ", ".join(TASKS) in text


@pytest.mark.parametrize("name", sorted(__import__("benchmark.commands.cli", fromlist=["ALL_SUBCOMMANDS"]).ALL_SUBCOMMANDS))
def test_a_subcommands_help_shows_no_docstring_markup(name, capsys):
    with pytest.raises(SystemExit):
        run([name, "--help"])
    out = capsys.readouterr().out
    description = out.split("\n\n")[1]
    assert "``" not in description and ":func:" not in description and ":mod:" not in description, description
    assert description.startswith(f"fsv-bench {name}") or description[:1].isupper(), description


def test_a_person_grasp_or_view_of_the_test_split_is_noted_before_any_work(tmp_path, capsys, monkeypatch):
    import benchmark.commands.cli as cli

    class Started(Exception):
        pass

    def refuse(out):
        raise Started

    monkeypatch.setattr(cli, "staging_folder", refuse)
    with pytest.raises(Started):
        main(["--user", "700", "--grasp", "650", "--view", "620", "--out", str(tmp_path / "run")])
    err = capsys.readouterr().err
    assert "note: user 700, grasp 650, view 620 are of the test split (500-999" in err and "dev split (100-499)" in err
    with pytest.raises(Started):
        main(["--user", "17", "--grasp", "17", "--view", "517", "--out", str(tmp_path / "run")])
    assert "note: view 517 is of the test split" in capsys.readouterr().err
    with pytest.raises(Started):
        main(["--user", "17", "--out", str(tmp_path / "run")])
    assert "test split" not in capsys.readouterr().err


def test_the_learning_block_names_a_model_only_for_the_learned_stage_not_for_a_label_that_reads_like_it(
        tmp_path, pictured_lift):
    out = tmp_path / "run"
    main(["--task", "lift", "--duration", "1.5", "--quiet", "--no-pictures", "--out", str(out),
          "--internal", "external_stages:NominalAsLearned"])
    learning = json.loads((out / "summary.json").read_text())["learning"]
    assert learning["program"] == "learned internal forces (an impostor)"
    assert "model" not in learning and "internal_model" not in learning
    learning = json.loads((pictured_lift[0] / "summary.json").read_text())["learning"]
    assert learning["internal_model"] == "fsv/data/internal_forces_blind.npz" and not learning["model"]["grip_inputs"]


def test_no_pictures_draws_none_and_changes_no_number_of_the_run(tmp_path, capsys, pictured_lift):
    """``--no-pictures`` (for batch runs and CI, and the tests that do not look at pictures): no
    PNG or GIF, every number and digest of the run with its pictures, no line or block naming a
    picture, and the same options (a presentation option: the same default folder)."""
    drawn, drawn_lines, _ = pictured_lift
    out = tmp_path / "run"
    main(PICTURED_LIFT[:-1] + ["--no-pictures", "--out", str(out)])
    lines = capsys.readouterr().out.splitlines()
    pictures = {"depth_preview.png", "tracking_overlay.png", "fig4_kinematics.png", "forces_fig5.png"}
    assert {p.name for p in drawn.iterdir()} >= pictures  # the control: the run with pictures drew them
    assert not [p.name for p in out.iterdir() if p.suffix in (".png", ".gif")]
    with_, without = (json.loads((d / "summary.json").read_text()) for d in (drawn, out))
    assert without["digests"] == with_["digests"]
    assert json.loads((out / "options.json").read_text()) == json.loads((drawn / "options.json").read_text())
    assert without["render"].pop("preview") == [] and with_["render"].pop("preview") == ["depth_preview.png"]
    assert without["forces"].pop("plot") is None and with_["forces"].pop("plot") == "forces_fig5.png"
    assert without["tracking"].pop("overlay") is None and with_["tracking"].pop("overlay") == "tracking_overlay.png"
    assert "plot" not in without["kinematics_info"]["files"] and with_["kinematics_info"]["files"].pop("plot")
    for summary in (with_, without):
        summary.pop("timing_s"), summary["world"].pop("steps_per_s")  # the speeds differ from run to run
        for key in ("frames_per_s", "frames_per_s_after_first", "first_frame_s", "compile_s", "stage_ms_per_frame"):
            summary["tracking"].pop(key)
    assert without == with_
    assert not [line for line in lines if any(name in line for name in pictures)]
    assert len(lines) == len(drawn_lines) and sum(a != b for a, b in zip(lines, drawn_lines)) >= 4


def test_output_read_only_in_part_ends_the_command_without_a_traceback():
    """``fsv-bench reproduce --list | true``: the reader closes the pipe before anything is written
    (``| head -1`` does after its line); the command ends quietly, status 0."""
    import os
    import subprocess
    import sys

    run = subprocess.run(f"{sys.executable} -m benchmark.commands.entry reproduce --list | true; "
                         "echo status ${PIPESTATUS[0]} >&2", shell=True, executable="/bin/bash",
                         capture_output=True, text=True, timeout=120,
                         env={**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)})
    assert "Traceback" not in run.stderr and "BrokenPipe" not in run.stderr, run.stderr
    assert run.stderr.strip() == "status 0", run.stderr


def test_the_pictures_library_is_preloaded_before_the_first_stage_runs(monkeypatch):
    """The main command imports matplotlib (in a thread) before its first stage, so that every child it
    forks later inherits it: the render stage's child (the depth preview, beside the tracker) imported it
    again when the import began after the first stage (measured: 0.1 s of CPU a run); with
    ``--no-pictures`` it is not imported."""
    import argparse
    import dataclasses

    from benchmark.commands import cli

    calls = []

    class Recorder:
        def preload(self, *modules):
            calls.append(("preload", modules))

    @dataclasses.dataclass(frozen=True)
    class Record:
        out: str = "out"
        background: object = None

    class Result:
        pictures, later = ("a picture",), ()

        def updates(self):
            return {}

    def stage(name):
        def run(record, args):
            calls.append(("stage", name))
            return Result()
        run.name = name
        return run

    monkeypatch.setattr(cli, "STAGES", [stage("simulate"), stage("render")])
    monkeypatch.setattr(cli, "complete", lambda result, out, background: None)
    cli.run_stages(Record(), argparse.Namespace(no_pictures=False), Recorder())
    assert calls == [("preload", ("matplotlib.pyplot",)), ("stage", "simulate"), ("stage", "render")]
    calls.clear()
    cli.run_stages(Record(), argparse.Namespace(no_pictures=True), Recorder())
    assert calls == [("stage", "simulate"), ("stage", "render")]
