"""fsv.learn.direct: the end-to-end network's predictions, its zeroing rules and its file."""

import zipfile

import numpy as np
import pytest
from test_direct_inputs import G, frames, model

from fsv import InputError
from fsv.learn import DirectConfig, DirectForceModel, direct_inputs, load_direct
from fsv.learn.direct import default_direct_path, read_direct_state
from fsv.learn.direct_inputs import input_names

NAMES = ("thumb", "index")


def random_model(seed=0, hidden=(8, 8), window=0, off_table_m=0.02) -> DirectForceModel:
    rng = np.random.default_rng(seed)
    n_in, n_out = len(input_names(NAMES, window)), 3 * len(NAMES) + 6
    sizes = [n_in, *hidden, n_out]
    layers = [(rng.normal(size=(o, i)) / np.sqrt(i), rng.normal(size=o)) for i, o in zip(sizes[:-1], sizes[1:])]
    return DirectForceModel(DirectConfig(hidden=hidden, window=window, off_table_m=off_table_m), NAMES,
                            rng.normal(size=n_in), rng.uniform(0.5, 2, n_in), rng.normal(size=n_out),
                            rng.uniform(0.5, 2, n_out), layers, {"note": "random"})


def test_inactive_fingers_get_no_force_and_a_box_off_the_table_no_table_wrench():
    m = random_model()
    valid = np.array([False, True, True, True, True])
    kin, con = frames(valid=valid, z=0.03)
    p = m.predict(kin, con, model(), G)
    assert p.force.shape == (5, 2, 3) and p.table.shape == (5, 6)
    assert np.isnan(p.force[0]).all() and np.isnan(p.table[0]).all()
    assert (p.force[1:, 1] == 0).all() and (np.abs(p.force[1:, 0]) > 0).all()  # the index finger is not in contact
    assert p.on_table[1:].all() and (np.abs(p.table[1:]) > 0).all()  # resting: height 0
    raw = m.predict_inputs(direct_inputs(kin, con, model(), G)[0][1:])
    np.testing.assert_array_equal(p.force[1:, 0], raw[:, :3])
    np.testing.assert_array_equal(p.table[1:], raw[:, 6:])
    kin, con = frames(z=0.03 + 0.021)  # 21 mm up: clearly off the table (> 20 mm)
    p = m.predict(kin, con, model(), G)
    assert not p.on_table.any() and (p.table == 0).all()
    kin, con = frames(z=0.03 + 0.019)
    assert m.predict(kin, con, model(), G).on_table.all()


def test_the_file_round_trips_bit_for_bit_and_records_its_digest_and_provenance(tmp_path):
    m = random_model()
    m.save(tmp_path / "m.npz")
    back = load_direct(tmp_path / "m.npz")
    assert back.config == m.config and back.finger_names == NAMES and back.num_parameters == m.num_parameters
    for (Wa, ba), (Wb, bb) in zip(m.layers, back.layers):
        assert np.array_equal(Wa, Wb) and np.array_equal(ba, bb)
    kin, con = frames()
    a, b = m.predict(kin, con, model(), G), back.predict(kin, con, model(), G)
    assert np.array_equal(a.force, b.force) and np.array_equal(a.table, b.table)
    state = read_direct_state(tmp_path / "m.npz")
    assert len(state["sha256"]) == 64 and "provenance" in back.metadata and back.metadata["note"] == "random"
    assert back.state()["sha256"] == state["sha256"]  # the provenance read back, not renewed


def _rewrite(src, dst, member, change):
    with zipfile.ZipFile(src) as zin, zipfile.ZipFile(dst, "w") as zout:
        for item in zin.infolist():
            data = zin.read(item.filename)
            zout.writestr(item, change(data) if item.filename == member else data)


def test_a_changed_weight_a_foreign_file_or_none_are_refused_naming_the_file(tmp_path):
    random_model().save(tmp_path / "m.npz")

    def flip(data: bytes) -> bytes:  # the last byte of the array: a weight, not the .npy header
        return data[:-1] + bytes([data[-1] ^ 0x10])

    _rewrite(tmp_path / "m.npz", tmp_path / "bad.npz", "layer.1.weight.npy", flip)
    with pytest.raises(InputError, match=r"bad.npz' is corrupt: its content has SHA-256"):
        load_direct(tmp_path / "bad.npz")
    (tmp_path / "text.npz").write_text("not a model")
    with pytest.raises(InputError, match="text.npz' is not a readable direct force model"):
        load_direct(tmp_path / "text.npz")
    with pytest.raises(InputError, match="no direct force model at"):
        load_direct(tmp_path / "missing.npz")
    assert default_direct_path().endswith("fsv/data/direct_forces.npz")


def test_layers_that_do_not_fit_the_config_are_refused():
    m = random_model()
    with pytest.raises(InputError, match="the layers have shapes"):
        DirectForceModel(DirectConfig(hidden=(9, 8)), NAMES, m.x_mean, m.x_std, m.y_mean, m.y_std, m.layers)
    with pytest.raises(InputError, match="x_std must hold"):
        DirectForceModel(m.config, NAMES, m.x_mean, np.zeros_like(m.x_std), m.y_mean, m.y_std, m.layers)


@pytest.mark.parametrize("kw, needle", [
    (dict(hidden=()), "hidden must be a non-empty tuple"), (dict(epochs=0), "epochs must be an integer >= 1"),
    (dict(off_table_m=float("nan")), "off_table_m must be a number > 0 m"), (dict(val_fraction=1.0), "in \\[0, 1\\)"),
    (dict(window=99), "window must be an integer"), (dict(lr=-1), "lr must be a number > 0"),
])
def test_bad_configs_are_refused_naming_the_field(kw, needle):
    with pytest.raises(InputError, match=needle):
        DirectConfig(**kw)
