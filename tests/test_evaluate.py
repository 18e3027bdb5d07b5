"""fsv-bench eval: suites scored with intervals and a verdict; bad input exits 2, failed gates 1."""

import dataclasses
import json

import pytest
from tiny_suite import TINY

from benchmark.commands.cli import main
from benchmark.paper.dataset.cli import parse_ints
from benchmark.suites import SUITES, Gate, Suite
from benchmark.world.assets import validate
from benchmark.world.scenario import Scenario


@pytest.fixture
def tiny(monkeypatch):
    monkeypatch.setitem(SUITES, "tiny", TINY)
    return TINY


@pytest.mark.parametrize("name", sorted(SUITES))
def test_every_registered_suite_is_valid(name):
    suite = SUITES[name]
    assert suite.version >= 1 and suite.description and suite.gates
    for sc in suite.scenarios:
        validate(sc)  # task, user, grasp, mass exist; duration suits the task
    from benchmark.scores.metrics import METRICS

    assert all(g.metric in METRICS for g in suite.gates)


def test_eval_writes_scores_report_junit_and_the_second_run_renders_nothing(tiny, tmp_path, capsys):
    out, cache = tmp_path / "out", tmp_path / "cache"
    assert main(["eval", "--suite", "tiny", "--out", str(out), "--cache", str(cache), "--quiet"]) == 0
    first = json.loads((out / "scores.json").read_text(), parse_constant=lambda c: pytest.fail(f"non-strict JSON {c}"))
    assert first["rendered"] == 1 and first["verdict"] == "pass"
    assert first["suite"] == {"name": "tiny", "version": 1, "description": "one short lift, for the tests"}
    ep = first["episodes"][0]
    assert ep["episode"] == "lift-u0-g0-m0-s21" and 0 < ep["box_pos_err_mm"] < 6  # lab knowledge: measured 3.8
    agg = first["aggregate"]["box_pos_err_mm"]["median"]
    assert agg["n"] == 1 and agg["ci_low"] == agg["value"] == agg["ci_high"] == ep["box_pos_err_mm"]
    assert "provenance" in first and (out / "report.md").read_text().startswith("# tiny (version 1)")
    assert not (out / "pictures").exists()  # without --pictures, none (tests/test_pictures_episodes.py: with it)
    junit = (out / "junit.xml").read_text()
    assert junit.count("<testcase") == 2 and "<failure" not in junit
    report = (out / "report.md").read_text()
    assert "every gate holds" in report
    # the trivial baselines ran on the same episode: the skill against the best of each metric's stage
    base = first["baselines"]
    # blind (the default protocol): no grip line, which is a person's calibration and nothing else
    assert set(base) == {"static", "zero-kinematics", "gravity-forces", "no-internal"}
    assert base["static"]["stage"] == "tracker" and base["no-internal"]["stage"] == "internal"
    static_box = base["static"]["aggregate"]["box_pos_err_mm"]["median"]["value"]
    assert static_box > 10 * ep["box_pos_err_mm"]  # no vision
    skill_row = next(line for line in report.splitlines() if line.startswith("| this method |")).split(" | ")
    assert float(skill_row[1]) == pytest.approx(1 - ep["box_pos_err_mm"] / static_box, abs=0.006)
    capsys.readouterr()
    assert main(["eval", "--suite", "tiny", "--out", str(out), "--cache", str(cache), "--quiet"]) == 0
    second = json.loads((out / "scores.json").read_text())
    assert second["rendered"] == 0  # the episode came from the cache
    assert second["baselines"] == first["baselines"]
    assert [{k: v for k, v in e.items() if k not in ("seconds", "rendered")} for e in second["episodes"]] == \
           [{k: v for k, v in e.items() if k not in ("seconds", "rendered")} for e in first["episodes"]]
    assert "(0 rendered" in capsys.readouterr().out


def test_a_failing_gate_exits_1_names_it_and_fails_its_junit_case(tiny, tiny_cache, tmp_path, capsys):
    gates = tmp_path / "gates.json"
    gates.write_text(json.dumps([{"metric": "box_pos_err_mm", "op": "<=", "limit": 0.001},
                                 {"metric": "contact_recall", "op": ">=", "limit": 0.5}]))
    out = tmp_path / "out"
    code = main(["eval", "--suite", "tiny", "--out", str(out), "--gates", str(gates), "--cache", str(tiny_cache), "--quiet"])
    assert code == 1
    err = capsys.readouterr().err
    assert "1 gate(s) failed: median box_pos_err_mm <= 0.001" in err
    junit = (out / "junit.xml").read_text()
    assert junit.count("<failure") == 1 and 'failures="1"' in junit
    assert json.loads((out / "scores.json").read_text())["verdict"] == "fail"


@pytest.mark.parametrize("argv, needle", [
    (["--suite", "nope"], "--suite 'nope': no such suite; accepted: smoke"),
    (["--suite", "smoke", "--gates", "missing.json"], "--gates missing.json: not a non-empty JSON list"),
])
def test_bad_input_exits_2_with_one_line_before_any_work(tmp_path, capsys, argv, needle, monkeypatch):
    monkeypatch.chdir(tmp_path)
    out = tmp_path / "out"
    assert main(["eval", *argv, "--out", str(out), "--cache", str(tmp_path / "cache")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and needle in err
    assert not out.exists() and not (tmp_path / "cache").exists()


def test_gates_file_with_an_unknown_metric_is_refused(tmp_path, capsys):
    gates = tmp_path / "g.json"
    gates.write_text(json.dumps([{"metric": "speed", "op": "<=", "limit": 1}]))
    assert main(["eval", "--suite", "smoke", "--gates", str(gates), "--out", str(tmp_path / "o")]) == 2
    assert "unknown metric 'speed'; accepted: box_pos_err_mm" in capsys.readouterr().err


@pytest.mark.parametrize("text, needle", [
    ('[{"metric": "box_pos_err_mm", "op": "<=", "limit": 9, "statistics": "mean"}]',
     "entry 0: unknown key 'statistics'; accepted: metric, op, limit, statistic"),
    ("[]", "not a non-empty JSON list"),
    ("{}", "not a non-empty JSON list"),
    ('[{"metric": "box_pos_err_mm", "op": "<=", "limit": NaN}]', "entry 0: limit must be a finite number, got nan"),
    ('[{"metric": "box_pos_err_mm", "op": "<=", "limit": Infinity}]', "limit must be a finite number, got inf"),
    ('[{"metric": "box_pos_err_mm", "op": "<=", "limit": "2"}]', "entry 0: limit must be a number, got '2'"),
    ('[{"metric": "box_pos_err_mm", "op": "<", "limit": 2}]', "entry 0: Gate.op must be '<=' or '>='"),
    ('[{"metric": "box_pos_err_mm", "op": "<=", "limit": 2, "statistic": "max"}]', "Gate.statistic must be"),
    ('[{"metric": "box_pos_err_mm", "limit": 2}]', "entry 0: missing key 'op'"),
    ('[{"metric": "box_pos_err_mm", "op": "<=", "limit": 2}, 3]', "entry 1 is not an object"),
])
def test_a_bad_gates_file_exits_2_in_seconds_before_any_work(tmp_path, capsys, text, needle):
    import time

    gates = tmp_path / "g.json"
    gates.write_text(text)
    t0 = time.perf_counter()
    assert main(["eval", "--suite", "smoke", "--gates", str(gates), "--out", str(tmp_path / "o"),
                 "--cache", str(tmp_path / "cache")]) == 2
    assert time.perf_counter() - t0 < 5
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and needle in err, err
    assert not (tmp_path / "o").exists() and not (tmp_path / "cache").exists()


def test_two_worker_processes_give_the_same_scores_as_one(tmp_path):
    from benchmark.suites.evaluate import evaluate

    suite = Suite(name="pair", version=1, scenarios=(Scenario(task="lift", seed=22, duration_s=1.5),
                                                     Scenario(task="lift", user=1, seed=23, duration_s=1.5)),
                  gates=(Gate("box_pos_err_mm", "<=", 1.5),), description="two short lifts")
    one = evaluate(suite, cache=tmp_path, progress=False, workers=1)
    two = evaluate(suite, cache=tmp_path, progress=False, workers=2)
    assert one["rendered"] == 2 and two["rendered"] == 0
    strip = lambda rows: [{k: v for k, v in r.items() if k not in ("seconds", "rendered")} for r in rows]
    assert strip(two["episodes"]) == strip(one["episodes"])
    assert two["aggregate"] == one["aggregate"]


def test_a_replaced_differentiator_changes_the_kinematics_scores_and_is_labelled(tiny, tmp_path):
    """The example Savitzky-Golay differentiator, loaded by module:attribute, on an episode from the cache."""
    from benchmark.method import MethodSpec
    from benchmark.suites.evaluate import evaluate_many

    cache = tmp_path / "cache"
    ref, savgol = evaluate_many(TINY, [MethodSpec(), MethodSpec(differentiator="examples.savgol:SavitzkyGolay")],
                                cache=cache, progress=False)
    assert ref["rendered"] == 1 and savgol["rendered"] == 0  # one episode rendered for both methods
    assert savgol["stages"]["differentiator"] == "Savitzky-Golay (window 21 frames, order 3)"
    assert "differentiator: Savitzky-Golay" in savgol["method"]
    a, b = ref["episodes"][0], savgol["episodes"][0]
    assert a["box_pos_err_mm"] == b["box_pos_err_mm"]  # the same tracking
    assert a["acc_err_rms"] != b["acc_err_rms"] and 0 < b["acc_err_rms"] < 5  # measured 0.53 (reference 0.29)


def test_a_broken_external_tracker_exits_1_naming_the_failed_gates(tiny, tiny_cache, tmp_path, capsys):
    out = tmp_path / "out"
    code = main(["eval", "--suite", "tiny", "--out", str(out), "--cache", str(tiny_cache), "--quiet",
                 "--tracker", "external_stages:FrozenTracker"])
    captured = capsys.readouterr()
    assert code == 1
    assert "frozen tracker (a broken example)" in captured.out
    assert "gate(s) failed: median box_pos_err_mm <= 8" in captured.err
    scores = json.loads((out / "scores.json").read_text())
    assert scores["stages"]["tracker"] == "frozen tracker (a broken example)" and scores["verdict"] == "fail"


@pytest.mark.parametrize("argv, needle", [
    (["--tracker", "external_stages:Nope"], "--tracker 'external_stages:Nope': external_stages has no attribute 'Nope'"),
    (["--differentiator", "median"], "--differentiator 'median': accepted: algebraic, central, gaussian, module:attribute or path/to/file.py:attribute"),
    (["--oracle", "forces"], "--oracle 'forces': accepted: contacts, kinematics"),
    (["--internal-model", "missing.npz"], "--internal-model missing.npz: no internal-force model"),
])
def test_a_bad_method_exits_2_before_any_work(tiny, tmp_path, capsys, argv, needle):
    out = tmp_path / "out"
    assert main(["eval", "--suite", "tiny", "--out", str(out), "--cache", str(tmp_path / "cache"), *argv]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and needle in err
    assert not (tmp_path / "cache").exists() and not out.exists()


def test_a_suite_seen_by_another_sensor_is_its_own_suite(tmp_path, capsys):
    from benchmark.commands.cli import main
    from benchmark.suites import get_suite

    smoke = get_suite("smoke")
    assert get_suite("smoke", "ds325") is smoke  # its own sensor: the suite itself
    kinect = get_suite("smoke", "kinect-v1")
    assert kinect.name == "smoke-kinect-v1" and kinect.version == smoke.version and kinect.gates == smoke.gates
    assert [sc.sensor for sc in kinect.scenarios] == ["kinect-v1"] * len(smoke.scenarios)
    assert [dataclasses.replace(sc, sensor="ds325") for sc in kinect.scenarios] == list(smoke.scenarios)
    assert main(["eval", "--suite", "smoke", "--sensor", "sonar", "--out", str(tmp_path / "o"),
                 "--cache", str(tmp_path / "c")]) == 2
    err = capsys.readouterr().err
    assert "--sensor 'sonar': no such sensor; accepted: ds325, kinect-v1, ideal" in err and err.count("\n") == 1
    assert not (tmp_path / "c").exists() and not (tmp_path / "o").exists()


def test_a_suite_with_another_grip_control_is_its_own_suite_named_after_it(tmp_path, capsys):
    from benchmark.commands.cli import main
    from benchmark.suites import get_suite
    from benchmark.world.scenario import episode_name

    smoke = get_suite("smoke")
    assert get_suite("smoke", grip_control="per-digit") is smoke  # the suite's own control
    hand = get_suite("smoke", "kinect-v1", "capsules", "whole-hand")
    assert hand.name == "smoke-kinect-v1-capsules-whole-hand" and hand.gates == smoke.gates
    assert {(sc.sensor, sc.hand_surface, sc.grip_control) for sc in hand.scenarios} == {("kinect-v1", "capsules", "whole-hand")}
    assert episode_name(hand.scenarios[0]) == episode_name(smoke.scenarios[0]) + "-capsules-whole-hand"
    assert main(["eval", "--suite", "smoke", "--grip-control", "fist", "--out", str(tmp_path / "o"),
                 "--cache", str(tmp_path / "c")]) == 2
    err = capsys.readouterr().err
    assert "--grip-control 'fist': accepted: whole-hand, per-digit" in err and err.count("\n") == 1
    assert not (tmp_path / "c").exists() and not (tmp_path / "o").exists()


def test_the_paper_suites_hold_the_paper_protocols_episodes():
    """table1 and table2 are the episodes of the table1 and table2 commands' protocols (one source each)."""
    from benchmark.paper.table1 import SIX_AXIS_TASKS
    from benchmark.reproduce import DATASETS, RESULTS

    t1 = SUITES["table1"].scenarios
    assert {(sc.task, sc.seed) for sc in t1} == {(t, s) for t in SIX_AXIS_TASKS for s in (0, 1, 2)} and len(t1) == 18
    table1_command = next(r for r in RESULTS if r.name == "table1").commands[0]
    assert table1_command[table1_command.index("--seeds") + 1] == "0,1,2"
    grid = dict(zip(DATASETS["table2"][::2], DATASETS["table2"][1::2]))
    assert grid == {"--tasks": "lift", "--grasps": "0,1", "--masses": "1,4", "--seeds": "0-5", "--users": "0,4"}
    assert {(sc.user, sc.grasp, sc.mass, sc.seed) for sc in SUITES["table2"].scenarios} == \
           {(u, g, m, s) for u in (0, 4) for g in (0, 1) for m in (1, 4) for s in range(6)}


def test_dev_is_the_standard_design_on_its_own_split_and_seeds_no_reported_suite_uses():
    from benchmark.suites.splits import split_of

    std, dev = SUITES["standard"].scenarios, SUITES["dev"].scenarios
    design = lambda scs: [(sc.task, sc.duration_s, sc.noise_m, sc.sensor) for sc in scs]
    assert design(dev) == design(std) and len(dev) == 48
    assert {split_of(sc) for sc in std} == {"test"} and {split_of(sc) for sc in dev} == {"dev"}
    assert [sc.user for sc in std] == list(range(500, 548)) and [sc.user for sc in dev] == list(range(100, 148))
    assert [sc.seed for sc in dev] == list(range(500, 548))
    reported = {sc.seed for name in ("standard", "smoke", "table1", "table2") for sc in SUITES[name].scenarios}
    assert not reported & {sc.seed for sc in dev}
    assert [sc.mass for sc in dev] != [sc.mass for sc in std]  # drawn by its own generator
    assert SUITES["dev"].gates == SUITES["standard"].gates
    assert [sc.seed for sc in std] == list(range(300, 348))  # the headline's seeds did not move


def test_the_grip_calibration_recording_uses_seeds_no_suite_and_no_training_grid_uses():
    """A user's grip is measured on recordings of their own, never scored and never trained on."""
    from benchmark.method.grip_file import read_calibration
    from benchmark.reproduce import DATASETS

    seeds = lambda name: set(parse_ints(dict(zip(DATASETS[name][::2], DATASETS[name][1::2]))["--seeds"]))
    used = {sc.seed for suite in SUITES.values() for sc in suite.scenarios}
    recordings = [name for name in DATASETS if name.startswith("calibration")]
    for name in DATASETS:
        if name not in recordings:
            used |= seeds(name)
    assert seeds("calibration") == {900} and not seeds("calibration") & used
    for name in recordings:
        assert seeds(name) <= {900, 901} and not seeds(name) & used
    # every user of users.yaml, the training people and the people of the dev and standard suites
    people = {sc.user for name in ("dev", "standard") for sc in SUITES[name].scenarios}
    assert sorted(read_calibration()) == sorted({0, 1, 2, 3, 4} | set(range(1000, 1040)) | people)


def test_a_local_ray_cluster_gives_the_scores_of_the_local_run(tiny, ray_cluster, tiny_cache):
    from benchmark.suites.evaluate import evaluate

    cache = tiny_cache
    local = evaluate(TINY, cache=cache, progress=False)
    on_ray = evaluate(TINY, cache=cache, progress=False, ray_address=ray_cluster)
    drop = ("seconds", "rendered")
    assert [{k: v for k, v in r.items() if k not in drop} for r in on_ray["episodes"]] == \
           [{k: v for k, v in r.items() if k not in drop} for r in local["episodes"]]
    assert on_ray["rendered"] == 0  # the Ray worker found the episode in the shared cache


def test_eval_on_a_bad_ray_address_exits_2_within_seconds(tiny, tmp_path, capsys):
    import time

    t0 = time.perf_counter()
    code = main(["eval", "--suite", "tiny", "--out", str(tmp_path / "o"), "--cache", str(tmp_path / "c"),
                 "--ray-address", "127.0.0.1:9"])
    assert code == 2 and time.perf_counter() - t0 < 10
    assert "'127.0.0.1:9': no Ray cluster answers there" in capsys.readouterr().err
    assert not (tmp_path / "c").exists() and not (tmp_path / "o").exists()
