"""fsv-bench train-direct (benchmark.paper.direct_training): the end-to-end network from a dataset of every frame."""

import json

import numpy as np
from model_files import trained_bits

from benchmark.commands.entry import run
from benchmark.paper.dataset import DatasetSpec, frames_of, load_dataset
from benchmark.paper.direct_training import direct_samples
from benchmark.paper.table2 import object_models
from fsv.learn import DirectConfig, direct_inputs, load_direct


def test_the_model_records_its_data_and_trains_to_the_same_bits_twice(direct_dataset, tmp_path, capsys):
    spec, out = direct_dataset
    model = load_direct(out / "model.npz")
    m = model.metadata
    assert m["dataset"] == spec.as_dict() and m["episodes"] == 2 and m["command"].startswith("fsv")
    assert m["samples"] == 61 and m["held_out_samples"] == 61 and m["rows_left_out"] == 0  # one episode held out
    assert model.num_parameters == (61 * 16 + 16) + (16 * 16 + 16) + (16 * 21 + 21)  # 5 fingers: 61 inputs, 21 outputs
    assert run(["train-direct", "--data", str(out / "data"), "--out", str(tmp_path / "again.npz"), "--epochs", "3",
                "--hidden", "16,16", "--quiet"]) == 0
    line = capsys.readouterr().out
    assert "1,621 parameters" in line and "on 61 samples of 1 episodes (and 61 samples of 1 episodes held out)" in line and "s on one thread" in line
    assert trained_bits(out / "model.npz") == trained_bits(tmp_path / "again.npz")


def test_the_samples_are_the_inputs_of_each_episodes_frames(direct_dataset):
    _, out = direct_dataset
    df = load_dataset(out / "data", rows="all")
    models = object_models(out / "data")
    config = DirectConfig(window=2)
    samples, names = direct_samples(df, models, config)
    assert samples.x.shape == (122, 61 + 2 * 2 * 9) and samples.y.shape == (122, 21)
    one = (df["episode"] == "lift-u0-g0-m0-s1").to_numpy()
    kin, con = frames_of(df[one])
    x, valid = direct_inputs(kin, con, *models["lift-u0-g0-m0-s1"], window=2)
    assert valid.all()
    np.testing.assert_array_equal(samples.x[one], x)
    active = df[[f"active_{n}" for n in names]].to_numpy()
    np.testing.assert_array_equal(samples.mask[:, :15], np.repeat(active, 3, axis=1))
    np.testing.assert_array_equal(samples.y[:, 15:], df[[f"env_{q}_{a}" for q in "FT" for a in "xyz"]].to_numpy())
    lifted = (df["pos_z"] > 0.03 + 0.02 + 1e-3).to_numpy()  # flat box, 60 mm tall: its bottom > 20 mm up
    assert lifted.sum() > 40 and not samples.mask[lifted, 15:].any() and samples.mask[~lifted, 15:].all()


def test_a_dataset_of_the_papers_rows_is_refused_in_one_line(tmp_path, capsys):
    (tmp_path / "dataset.json").write_text(json.dumps({"format": "fsv-bench-dataset", "spec": DatasetSpec().as_dict()}))
    code = run(["train-direct", "--data", str(tmp_path), "--out", str(tmp_path / "m.npz")])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and "fsv-bench generate --rows all" in err
    assert not (tmp_path / "m.npz").exists()
