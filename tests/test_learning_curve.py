"""The learning curve (benchmark.commands.learning_curve): its table, and its refusals before any work."""

import json

from benchmark.commands import learning_curve
from benchmark.commands.learning_curve import (
    COLUMNS,
    curve_markdown,
    main,
    model_file,
    people_of,
    train_model,
    train_models,
)
from benchmark.suites import SUITES


def _agg(value):
    return {m: {"median": {"value": value, "ci_low": value - 1, "ci_high": value + 1}} for m, _ in COLUMNS}


def test_the_table_has_a_row_per_number_of_people_and_protocol():
    rows = [{"people": 5, "episodes": 60, "samples": 9000, "aggregate": {"blind": _agg(20.0), "calibrated": _agg(15.0)}},
            {"people": 40, "episodes": 480, "samples": 90000, "aggregate": {"blind": _agg(12.5), "calibrated": _agg(9.0)}}]
    table = curve_markdown(SUITES["dev"], rows)
    assert f"Scored on `dev` v{SUITES['dev'].version} (48 episodes" in table
    assert "| 5 | 60 | 9000 | blind | 20 [19, 21] |" in table
    assert "| 40 | 480 | 90000 | calibrated | 9 [8, 10] |" in table
    assert sum(line.startswith("| 5 |") or line.startswith("| 40 |") for line in table.splitlines()) == 4


def test_people_are_the_datasets_in_order_and_too_many_are_refused_before_any_work(tmp_path, capsys):
    (tmp_path / "d").mkdir()
    (tmp_path / "d" / "dataset.json").write_text(json.dumps({"format": "fsv-bench-dataset", "version": 2,
                                                             "spec": {"users": [1000, 1001, 1002]}}))
    assert people_of(tmp_path / "d") == [1000, 1001, 1002]
    assert main(["--data", str(tmp_path / "d"), "--people", "2,5", "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--people 2,5: the dataset has 3 people; accepted: 1 to 3" in err
    assert not (tmp_path / "out").exists()
    assert main(["--data", str(tmp_path / "d"), "--people", "2", "--workers", "0", "--out", str(tmp_path / "out")]) == 2
    assert "--workers 0: accepted: 1 or more" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_each_number_of_people_trains_a_user_blind_model_and_one_with_grip_inputs(monkeypatch, tmp_path):
    from types import SimpleNamespace

    from benchmark.paper import training

    seen = []
    monkeypatch.setattr(training, "run", lambda args: seen.append(args) or SimpleNamespace(metadata={"grip": args.grip}))
    assert train_model("d", [1000, 1001], None, tmp_path / model_file(2, "blind")) == {"grip": None}
    assert train_model("d", [1000, 1001], "g.json", tmp_path / model_file(2, "calibrated")) == {"grip": "g.json"}
    assert [a.out for a in seen] == [str(tmp_path / "people-2-blind.npz"), str(tmp_path / "people-2.npz")]
    assert all(a.users == "1000,1001" and a.folds == 0 and a.amount_loss == "relative" for a in seen)


def test_the_models_are_trained_largest_first_and_returned_per_number_and_protocol(monkeypatch, tmp_path):
    seen = []
    monkeypatch.setattr(learning_curve, "train_model",
                        lambda data, users, grip, out: seen.append((len(users), grip, out.name)) or {"n": len(users), "grip": grip})
    meta = train_models("d", [1000, 1001, 1002, 1003], [1, 4], "g.json", tmp_path)
    assert seen == [(4, None, "people-4-blind.npz"), (4, "g.json", "people-4.npz"),
                    (1, None, "people-1-blind.npz"), (1, "g.json", "people-1.npz")]
    assert meta == {1: {"blind": {"n": 1, "grip": None}, "calibrated": {"n": 1, "grip": "g.json"}},
                    4: {"blind": {"n": 4, "grip": None}, "calibrated": {"n": 4, "grip": "g.json"}}}


def test_grip_lines_fitted_from_recordings_must_cover_every_training_person(monkeypatch, tmp_path, capsys):
    import pytest

    from benchmark.errors import DatasetError
    from benchmark.paper import calibration

    def run(args):  # the real command's options, each at its default (a new option must not break this call)
        assert args.data == ["rec"] and args.out == str(tmp_path / "g.json") and args.force is False
        print("user 1000: ...")
        return {1000: object()}

    monkeypatch.setattr(calibration, "run", run)
    learning_curve.fit_calibration(["rec"], tmp_path / "g.json", [1000], quiet=True)
    assert capsys.readouterr().out == ""
    with pytest.raises(DatasetError, match=r"person 1001 has no recording there \(1 of the 2 training people"):
        learning_curve.fit_calibration(["rec"], tmp_path / "g.json", [1000, 1001])


def test_a_grip_file_and_recordings_together_are_refused_before_any_work(tmp_path, capsys):
    (tmp_path / "d").mkdir()
    (tmp_path / "d" / "dataset.json").write_text(json.dumps({"format": "fsv-bench-dataset", "version": 2,
                                                             "spec": {"users": [1000, 1001]}}))
    assert main(["--data", str(tmp_path / "d"), "--people", "2", "--grip", "g.json", "--calibration", "rec",
                 "--out", str(tmp_path / "out")]) == 2
    assert "--grip g.json and --calibration: accepted: one of them" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_the_training_jobs_pickle_for_the_pool_when_the_command_runs_as_main(monkeypatch, tmp_path):
    """`python -m benchmark.commands.learning_curve` runs the module as __main__, whose functions a
    spawned worker cannot look up: the job function must be the importable module's."""
    import inspect
    import pickle
    import types

    source = inspect.getsource(learning_curve).replace('if __name__ == "__main__":', "if False:")
    as_main = types.ModuleType("__main__")
    exec(compile(source, learning_curve.__file__, "exec"), as_main.__dict__)
    passed = []
    monkeypatch.setattr(as_main, "run_jobs", lambda fn, jobs, workers: passed.append(fn) or enumerate([{}] * len(jobs)))
    as_main.train_models("d", [1000], [1], None, tmp_path, workers=2)
    assert pickle.loads(pickle.dumps(passed[0])) is learning_curve._train_job


def test_recordings_without_a_training_person_are_one_line_and_exit_2(monkeypatch, tmp_path, capsys):
    from benchmark.errors import DatasetError

    (tmp_path / "d").mkdir()
    (tmp_path / "d" / "dataset.json").write_text(json.dumps({"format": "fsv-bench-dataset", "version": 2,
                                                             "spec": {"users": [1000, 1001]}}))

    def missing(recordings, out, people, quiet=False):
        raise DatasetError("--calibration rec: person 1001 has no recording there")

    monkeypatch.setattr(learning_curve, "fit_calibration", missing)
    assert main(["--data", str(tmp_path / "d"), "--people", "2", "--calibration", "rec",
                 "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "person 1001 has no recording there" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["d"]
