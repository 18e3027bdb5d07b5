"""The learned method's learning curve (benchmark.commands.direct_curve): its people, its models,
its table, its refusals before any work; and training on several datasets at once."""

import json

import pytest
from model_files import trained_bits

from benchmark.commands.direct_curve import COLUMNS, curve_markdown, main, model_file, people_of_all, train_models
from benchmark.errors import DatasetError
from benchmark.paper import direct_training
from benchmark.paper.dataset import DatasetSpec, generate
from benchmark.paper.direct_training import train_job, train_on
from benchmark.suites import SUITES
from fsv.errors import InputError
from fsv.learn import DirectConfig
from fsv.learn.direct import read_direct_state


def _agg(value):
    cell = {"value": value, "ci_low": value - 1, "ci_high": value + 1}
    return {m: {"median": cell, "mean": cell, "p90": cell} for m, _, _ in COLUMNS}


def _dataset(folder, users, rows="all"):
    folder.mkdir()
    spec = {"users": users, "rows": rows}
    (folder / "dataset.json").write_text(json.dumps({"format": "fsv-bench-dataset", "version": 3, "spec": spec}))
    return folder


def test_the_table_has_a_row_per_number_of_people_and_the_reference_below():
    rows = [{"people": 40, "episodes": 480, "samples": 130000, "aggregate": _agg(2.0)},
            {"people": 80, "episodes": 960, "samples": 260000, "aggregate": _agg(1.5)}]
    table = curve_markdown(SUITES["dev"], rows, _agg(1.0), DirectConfig(window=2))
    assert f"Scored on `dev` v{SUITES['dev'].version} (48 episodes" in table
    assert "| 40 | 480 | 130000 | 2 [1, 3] |" in table and "| 80 | 960 | 260000 | 1.5 [0.5, 2.5] |" in table
    assert "| reference | | | 1 [0, 2] |" in table
    assert "hidden 128,128, window 2, at most 60 epochs" in table and "per-contact MAE [N] (mean)" in table and "net force, p90 [N] (p90)" in table
    assert sum(line.startswith("|") for line in table.splitlines()) == 2 + 2 + 1  # heading, rule, 2 rows, reference


def test_people_are_taken_folder_after_folder_and_a_person_in_two_is_refused(tmp_path):
    a, b = _dataset(tmp_path / "a", [1000, 1001]), _dataset(tmp_path / "b", [1002, 1003, 1004])
    assert people_of_all([a, b]) == [1000, 1001, 1002, 1003, 1004]
    assert people_of_all([b, a]) == [1002, 1003, 1004, 1000, 1001]
    c = _dataset(tmp_path / "c", [1004, 1005])
    with pytest.raises(DatasetError, match=r"person 1004 is in --data .*b too"):
        people_of_all([a, b, c])


def test_bad_values_are_refused_in_one_line_before_any_work(tmp_path, capsys):
    a, b = _dataset(tmp_path / "a", [1000, 1001]), _dataset(tmp_path / "b", [1002])
    paper = _dataset(tmp_path / "paper", [1003], rows="paper")
    out = tmp_path / "out"
    cases = [(["--data", str(a), "--data", str(b), "--people", "2,4"], "--people 2,4: the datasets have 3 people; "
              "accepted: 1 to 3"),
             (["--data", str(a), "--people", "2", "--workers", "0"], "--workers 0: accepted: 1 or more"),
             (["--data", str(a), "--data", str(paper), "--people", "1"], "fsv-bench generate --rows all"),
             (["--data", str(a), "--data", str(a), "--people", "1"], "person 1000 is in --data"),
             (["--data", str(a), "--people", "1", "--suite", "nope"], "nope"),
             (["--data", str(a), "--people", "1", "--window", "-1"], "--window")]
    for argv, message in cases:
        try:
            code = main(argv + ["--out", str(out)])
        except SystemExit as e:  # the parser's own refusals
            code = e.code
        assert code == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and message in err, (argv, err)
        assert not out.exists()


def test_the_models_are_trained_largest_first_on_the_first_people(monkeypatch, tmp_path):
    seen = []

    def job(job):
        datasets, users, out, config = job
        seen.append((datasets, users, out, config))
        return {"samples": len(users)}

    monkeypatch.setattr(direct_training, "train_job", job)
    a, b = _dataset(tmp_path / "a", [1000, 1001]), _dataset(tmp_path / "b", [1002, 1003])
    meta = train_models([a, b], [1000, 1001, 1002, 1003], [1, 4, 2], tmp_path, config={"window": 2})
    assert all(c == {"window": 2} for *_, c in seen)
    assert [(len(u), pathlib_name(o)) for _, u, o, _ in seen] == [(4, "direct-people-4.npz"), (2, "direct-people-2.npz"),
                                                               (1, "direct-people-1.npz")]
    # a model reads only the folders that hold its people: the second folder has none of the first two
    assert seen[1][1] == [1000, 1001] and [d for d, *_ in seen] == [[str(a), str(b)], [str(a)], [str(a)]]
    assert meta == {1: {"samples": 1}, 4: {"samples": 4}, 2: {"samples": 2}} and list(meta) == [1, 4, 2]
    assert model_file(160) == "direct-people-160.npz"


def pathlib_name(path: str) -> str:
    return path.rsplit("/", 1)[-1]


@pytest.fixture(scope="module")
def second_direct_dataset(tmp_path_factory):
    """A third 2 s lift with every frame (seed 2), in a dataset of its own."""
    out = tmp_path_factory.mktemp("direct2") / "data"
    generate(DatasetSpec(tasks=("lift",), seeds=(2,), duration_s=2.0, kinematics="oracle", contacts="oracle",
                         rows="all"), out, workers=1, progress=False)
    return out


def test_training_on_several_datasets_takes_every_episode_and_one_dataset_gives_train_directs_bits(
        direct_dataset, second_direct_dataset):
    _, out = direct_dataset
    config = DirectConfig(hidden=(16, 16), epochs=3)
    one = train_on([out / "data"], config)
    one.save(out.parent / "one.npz")
    assert trained_bits(out.parent / "one.npz") == trained_bits(out / "model.npz")
    both = train_on([out / "data", second_direct_dataset], config)
    m = both.metadata
    assert m["episodes"] == 3 and m["samples"] + m["held_out_samples"] == 3 * 61 and len(m["dataset"]) == 2
    picked = train_on([out / "data", second_direct_dataset], config, where={"seed": [0, 2]})
    assert picked.metadata["episodes"] == 2 and picked.metadata["selection"] == {"seed": [0, 2]}
    with pytest.raises(InputError, match=r"episode lift-u0-g0-m0-s0 is in another dataset too"):
        train_on([out / "data", out / "data"], config)


def test_a_curve_job_trains_the_shipped_models_network_on_the_people_and_saves_it(direct_dataset, tmp_path):
    _, out = direct_dataset
    summary = train_job(([str(out / "data")], [0], str(tmp_path / "m.npz"), {}))
    assert summary["episodes"] == 2 and summary["samples"] == 61 and summary["held_out_samples"] == 61
    assert summary["parameters"] == 27_157 and 1 <= summary["best_epoch"] <= DirectConfig().epochs  # 128-128, 5 fingers
    state = read_direct_state(tmp_path / "m.npz")
    assert state["metadata"]["selection"] == {"user": [0]} and state["metadata"]["command"].startswith("direct-curve")
    wide = train_job(([str(out / "data")], [0], str(tmp_path / "w.npz"), {"window": 2, "hidden": (8,)}))
    assert wide["parameters"] == (61 + 2 * 2 * 9) * 8 + 8 + 8 * 21 + 21  # window 2: 36 more inputs
