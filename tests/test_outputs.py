"""Nothing fsv-bench did not write is deleted, renamed or replaced, by any command; runs of other
options never share a folder. Each case is refused with one line and status 2 in seconds, before
any work (the expensive work is replaced by a stand-in that fails loudly if it is reached)."""

import json
import os
import pathlib
import subprocess
import time

import pytest

from benchmark.commands import cli
from benchmark.commands.cli import main
from benchmark.errors import RenderError

ROOT = pathlib.Path(__file__).resolve().parents[1]
LEGACY_MARKER = "This folder was written by fsv-bench, which replaces it whole when a command writes here again.\n"


def _dead_pid() -> int:
    proc = subprocess.Popen(["true"])
    proc.wait()
    return proc.pid


def _snapshot(folder: pathlib.Path) -> dict:
    """Every path under ``folder`` (links not followed) with its content or link target."""
    out = {}
    for p in sorted(folder.rglob("*")):
        rel = str(p.relative_to(folder))
        out[rel] = ("link", os.readlink(p)) if p.is_symlink() else ("dir",) if p.is_dir() else p.read_bytes()
    return out


@pytest.fixture
def no_work(monkeypatch):
    """The main command's stages replaced by a failure (exit 1); the folders it staged are recorded."""
    staged = []
    real = cli.staging_folder

    def staging(out):
        staged.append(pathlib.Path(out))
        return real(out)

    def stages(*_):
        raise RenderError("stand-in for the stages")

    monkeypatch.setattr(cli, "staging_folder", staging)
    monkeypatch.setattr(cli, "run_stages", stages)
    return staged


def _refused(argv, capsys, needle: str, before: dict, folder: pathlib.Path) -> str:
    t0 = time.perf_counter()
    try:
        code = main(argv)
    except SystemExit as e:  # refused while the command line is parsed
        code = e.code
    assert code == 2
    assert time.perf_counter() - t0 < 5
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and needle in err, err
    assert _snapshot(folder) == before
    return err


def test_a_symlinked_out_is_refused_naming_the_link_and_its_target(tmp_path, capsys, no_work):
    target = tmp_path / "target"
    target.mkdir()
    (target / ".fsv-bench-output").write_text(LEGACY_MARKER)
    (target / "summary.json").write_text("{}")
    link = tmp_path / "link"
    link.symlink_to(target)
    _refused(["--quiet", "--out", str(link)], capsys, f"--out {link}: is a symbolic link (to {target})",
             _snapshot(tmp_path), tmp_path)
    assert no_work == []


def test_the_working_folder_as_out_is_refused(tmp_path, capsys, monkeypatch, no_work):
    monkeypatch.chdir(tmp_path)
    _refused(["--quiet", "--out", "."], capsys, "--out .: is the working folder", {}, tmp_path)
    assert no_work == []


def test_a_users_backup_and_old_folders_beside_out_are_never_touched(tmp_path, capsys, no_work):
    dead = _dead_pid()
    for name in (f".res.{dead}.backup", ".res.2024.backup", ".res.old"):
        (tmp_path / name).mkdir()
        (tmp_path / name / "data.csv").write_text("precious")
    before = _snapshot(tmp_path)
    assert main(["--quiet", "--out", str(tmp_path / "res")]) == 1  # the stand-in's failure, after staging
    assert no_work == [tmp_path / "res"]
    assert _snapshot(tmp_path) == before  # nothing deleted, nothing renamed into place, the staging folder gone
    _run_folder(tmp_path / "res", cli.run_options(cli.build_parser(), cli.build_parser().parse_args([])))
    before = _snapshot(tmp_path)  # now with p/res, an earlier run's
    assert main(["--quiet", "--out", str(tmp_path / "res")]) == 1
    assert _snapshot(tmp_path) == before


@pytest.mark.parametrize("option", [["--protocol", "calibrated"], ["--knowledge", "exact"], ["--sensor", "kinect-v1"],
                                    ["--noise", "0.02"], ["--duration", "2"], ["--kinematics", "oracle"],
                                    ["--contacts", "oracle"], ["--init-perturbation", "0"],
                                    ["--differentiator", "central"], ["--method", "static"]])
def test_a_run_of_other_options_goes_to_another_default_folder(tmp_path, capsys, monkeypatch, no_work, option):
    monkeypatch.chdir(tmp_path)
    readme = tmp_path / "runs" / "lift-u0-g0-m0-s0"  # the README's run, every option its default
    assert main(["--task", "lift", "--noise", "0.01", "--quiet"]) == 1
    assert no_work == [pathlib.Path("runs/lift-u0-g0-m0-s0")]
    readme.mkdir(parents=True)
    (readme / ".fsv-bench-output").write_text(LEGACY_MARKER)
    (readme / "summary.json").write_text('{"the": "readme run"}')
    assert main(["--task", "lift", "--quiet", *option]) == 1
    assert no_work[1].parent == pathlib.Path("runs") and no_work[1].name.startswith("lift-u0-g0-m0-s0-o")
    assert (readme / "summary.json").read_text() == '{"the": "readme run"}'


def _run_folder(path: pathlib.Path, options) -> pathlib.Path:
    path.mkdir()
    (path / ".fsv-bench-output").write_text(LEGACY_MARKER)
    (path / "summary.json").write_text('{"previous": true}')
    if options is not None:
        (path / "options.json").write_text(json.dumps({"options": options}))
    return path


def test_replacing_a_run_of_other_options_needs_force(tmp_path, capsys, no_work):
    defaults = cli.run_options(cli.build_parser(), cli.build_parser().parse_args([]))
    other = _run_folder(tmp_path / "other", {**defaults, "sensor": "kinect-v1"})
    unknown = _run_folder(tmp_path / "unknown", None)  # an earlier fsv-bench's run: its options unknown
    same = _run_folder(tmp_path / "same", defaults)
    before = _snapshot(tmp_path)
    _refused(["--quiet", "--out", str(other)], capsys, "--sensor 'kinect-v1', now 'ds325'", before, tmp_path)
    _refused(["--quiet", "--out", str(unknown)], capsys, "--force", before, tmp_path)
    assert no_work == []
    assert main(["--quiet", "--out", str(same)]) == 1  # the same options: replaced silently (here, the stand-in fails)
    assert main(["--quiet", "--force", "--out", str(other)]) == 1
    assert no_work == [same, other]


@pytest.mark.parametrize("command, needle", [
    (["train", "--data", "DATA", "--out", "NOTES"], "--out NOTES: exists; give a new file name, or --force"),
    (["train", "--data", "DATA", "--out", "DIR"], "--out DIR: is a folder"),
    (["calibrate", "--data", "DATA", "--out", "NOTES"], "--out NOTES: exists"),
    (["compare", "SMOKE", "SMOKE", "--out", "NOTES"], "--out NOTES: exists"),
    (["table2", "--data", "DATA", "--out", "DIR"], "--out DIR: a folder with files that fsv-bench did not write"),
])
def test_file_and_folder_outputs_refuse_the_users_files_before_any_work(tmp_path, capsys, command, needle):
    notes, folder = tmp_path / "notes.json", tmp_path / "mine"
    notes.write_text('{"mine": true}')
    folder.mkdir()
    (folder / "table2.md").write_text("my table")
    paths = {"NOTES": str(notes), "DIR": str(folder), "DATA": str(tmp_path / "no-data"), "SMOKE": str(ROOT / "results/smoke")}
    argv = [paths.get(a, a) for a in command]
    for k, v in paths.items():
        needle = needle.replace(k, v)
    _refused(argv, capsys, needle, _snapshot(tmp_path), tmp_path)


def test_compare_replaces_a_file_when_forced(tmp_path, capsys):
    notes = tmp_path / "notes.json"
    notes.write_text('{"mine": true}')
    smoke = str(ROOT / "results/smoke")
    assert main(["compare", smoke, smoke, "--force", "--out", str(notes)]) == 0
    assert json.loads(notes.read_text())["suite"]["name"] == "smoke"


def test_generate_refuses_a_users_folder_and_resumes_its_own(tmp_path, capsys, monkeypatch):
    from benchmark.paper.dataset import cli as generate_cli
    from benchmark.paper.dataset.spec import FORMAT

    calls = []
    monkeypatch.setattr(generate_cli, "generate", lambda spec, out, **kw: calls.append(out) or _stop())
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "notes.txt").write_text("mine")
    (mine / f".tmp-notes.txt.{_dead_pid()}.abcd1234.txt").write_text("mine too")
    _refused(["generate", "--out", str(mine), "--no-progress"], capsys,
             f"--out {mine}: a folder with files that fsv-bench did not write", _snapshot(tmp_path), tmp_path)
    assert calls == []
    earlier = tmp_path / "earlier"  # a dataset of an fsv-bench before folders carried a marker: resumed
    earlier.mkdir()
    (earlier / "dataset.json").write_text(json.dumps({"format": FORMAT, "spec": {}}))
    with pytest.raises(_Stop):
        main(["generate", "--out", str(earlier), "--no-progress"])
    assert calls == [str(earlier)]


class _Stop(Exception):
    pass


def _stop():
    raise _Stop


@pytest.mark.parametrize("command", ["eval", "export", "score", "leaderboard", "sweep"])
@pytest.mark.parametrize("cache, out, needle", [
    ("X", "X", "one inside the other"), ("X/cache", "X", "one inside the other"), ("X", "X/out", "one inside the other"),
    ("FILE", "X", "exists and is not a folder"), ("OWNED", "OWNED", "one inside the other"),
])
def test_the_cache_is_refused_before_any_rendering_where_it_meets_the_output(tmp_path, capsys, monkeypatch, command,
                                                                             cache, out, needle):
    from benchmark.suites import evaluate

    monkeypatch.setattr(evaluate, "cached_episode", lambda *a, **k: _stop())
    (tmp_path / "file").write_text("mine")
    (tmp_path / "owned").mkdir()  # an earlier output of fsv-bench's, which the swap would replace, cache and all
    (tmp_path / "owned" / ".fsv-bench-output").write_text(LEGACY_MARKER)
    (tmp_path / "owned" / "smoke").mkdir()
    (tmp_path / "owned" / "smoke" / "lift-u1-g1-m1-s11-0123456789abcdef0123.npz").write_bytes(b"a cached episode")
    paths = {"X": str(tmp_path / "x"), "FILE": str(tmp_path / "file"), "OWNED": str(tmp_path / "owned")}
    cache, out = (paths[p.split("/")[0]] + p[len(p.split("/")[0]):] for p in (cache, out))
    extra = {"score": ["--estimates", str(tmp_path)], "sweep": ["--axis", "noise", "--values", "0.01,0.02"]}.get(command, [])
    _refused([command, "--suite", "smoke", "--quiet", *extra, "--out", out, "--cache", cache], capsys, needle,
             _snapshot(tmp_path), tmp_path)


@pytest.mark.parametrize("module, argv, expensive", [
    ("benchmark.commands.humanness", ["--suite", "smoke", "--quiet"], "suite_humanness"),
    ("benchmark.commands.table1", ["--score", "--seeds", "5"], "episode_set"),
])
def test_the_developer_commands_replace_only_their_own_folders(tmp_path, capsys, monkeypatch, module, argv, expensive):
    import importlib

    mod = importlib.import_module(module)
    monkeypatch.setattr(mod, expensive, lambda *a, **k: _stop())
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "table1.md").write_text("my notes")
    before = _snapshot(tmp_path)
    try:
        code = mod.main([*argv, "--out", str(mine)])
    except SystemExit as e:
        code = e.code
    assert code == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"--out {mine}: a folder with files that fsv-bench did not write" in err
    assert _snapshot(tmp_path) == before
