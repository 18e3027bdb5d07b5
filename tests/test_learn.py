import re

import numpy as np
import pytest

from fsv import InputError
from fsv.learn import LearnConfig, TrainingSet, cross_validate, load, relative_errors_pct, train

K = 4
BASE = np.array([0.6, 0.45, 0.45, 0.3])  # thumb carries the most, the little finger the least


def synthetic(n, seed):
    """A known internal-force rule: the norm grows with the load and the torque; shares depend on
    the finger and on how its normal faces the load (p2)."""
    rng = np.random.default_rng(seed)
    active = rng.random((n, K)) < 0.85
    active[:, 0] = True
    active[active.sum(1) < 2, 1] = True
    p1 = rng.uniform(2, 8, n)
    p3 = rng.uniform(0, 0.3, n)
    p2 = np.where(active, rng.uniform(-1, 1, (n, K)), 0)
    p4 = np.where(active, rng.uniform(-0.08, 0.08, (n, K)), 0)
    x = np.concatenate([p1[:, None], p3[:, None], p2, p4, active.astype(float)], axis=1)
    l2 = 3.0 + 0.8 * p1 + 10 * p3
    raw = np.where(active, BASE * (1 + 0.3 * p2), 0)
    internal = l2[:, None] * raw / np.linalg.norm(raw, axis=1, keepdims=True)
    return TrainingSet(x, internal, active, groups=np.arange(n) // 20)


@pytest.fixture(scope="module")
def model():
    return train(synthetic(1500, 0), LearnConfig(epochs=600, seed=1), finger_names=("thumb", "index", "middle", "ring"))


def test_recovers_a_known_rule(model):
    test = synthetic(1000, 7)
    l2, shares, f = model.predict(test.x, test.active)
    err = relative_errors_pct(f, test.internal, test.active)
    assert err.size > 2000
    assert np.mean(err) < 1.5, np.mean(err)  # the paper: ~10 % on real data
    np.testing.assert_allclose(np.linalg.norm(shares, axis=1), 1.0)
    assert np.all(shares[~test.active] == 0)


def test_training_is_deterministic_and_leaves_global_rng_alone():
    import torch

    data = synthetic(300, 2)
    cfg = LearnConfig(epochs=50, seed=5)
    state = torch.random.get_rng_state()
    a, b = train(data, cfg), train(data, cfg)
    assert torch.equal(state, torch.random.get_rng_state())
    for (wa, ba), (wb, bb) in zip(a.net_decomp[0], b.net_decomp[0]):
        assert wa.tobytes() == wb.tobytes() and ba.tobytes() == bb.tobytes()
    c = train(data, LearnConfig(epochs=50, seed=6))
    assert not np.array_equal(a.net_l2[0][0][0], c.net_l2[0][0][0])


def test_members_average_their_predictions_and_round_trip(tmp_path):
    data, test = synthetic(300, 2), synthetic(50, 8)
    two = train(data, LearnConfig(epochs=40, seed=5, members=2))
    one = train(data, LearnConfig(epochs=40, seed=5))
    assert len(two.net_l2) == len(two.net_decomp) == 2
    l2_two, s_two, _ = two.predict(test.x, test.active)
    l2_one, s_one, _ = one.predict(test.x, test.active)
    # the first member is the single-pair model (same generator, drawn first) ...
    np.testing.assert_array_equal(two.state()["net_l2"][0][0]["weight"], one.state()["net_l2"][0][0]["weight"])
    from fsv.learn import InternalForceModel

    alone = [InternalForceModel(two.config, two.finger_names, two.x_mean, two.x_std, two.l2_mean, two.l2_std, [a], [d])
             for a, d in zip(two.net_l2, two.net_decomp)]
    l2s = [m.predict(test.x, test.active)[0] for m in alone]
    np.testing.assert_array_equal(l2s[0], l2_one)  # ... and the norm is the mean of both members'
    assert np.all(l2s[0] > 0) and np.all(l2s[1] > 0) and np.max(np.abs(l2s[0] - l2s[1])) > 1e-3
    np.testing.assert_allclose(l2_two, (l2s[0] + l2s[1]) / 2, rtol=1e-12)
    shares = sum(m.predict(test.x, test.active)[1] for m in alone)
    np.testing.assert_allclose(s_two, shares / np.linalg.norm(shares, axis=1, keepdims=True), rtol=1e-12)
    two.save(tmp_path / "two.npz")
    for u, v in zip(two.predict(test.x, test.active), load(tmp_path / "two.npz").predict(test.x, test.active)):
        np.testing.assert_array_equal(u, v)


def test_save_load_round_trip_is_bit_exact(model, tmp_path):
    path = tmp_path / "m.npz"
    model.metadata["dataset"] = "synthetic"
    model.save(path)
    back = load(path)
    test = synthetic(200, 9)
    for u, v in zip(model.predict(test.x, test.active), back.predict(test.x, test.active)):
        np.testing.assert_array_equal(u, v)
    assert back.finger_names == ("thumb", "index", "middle", "ring")
    assert back.metadata["dataset"] == "synthetic" and back.config == model.config
    assert [p.name for p in tmp_path.iterdir()] == ["m.npz"]  # no temporary left behind


def test_load_rejects_foreign_files(tmp_path):
    bad = tmp_path / "x.npz"
    bad.write_bytes(b"not a model")
    with pytest.raises(InputError, match="not a readable"):
        load(bad)
    with pytest.raises(InputError, match="no internal-force model"):
        load(tmp_path / "missing.npz")


def test_cross_validation_folds_hold_out_whole_groups():
    cv = cross_validate(synthetic(400, 3), LearnConfig(epochs=150, folds=3))
    assert cv.fold_rel_err_pct.shape == (3,)
    assert np.all(cv.fold_rel_err_pct < 15)
    with pytest.raises(InputError, match="at least 3 groups"):
        cross_validate(synthetic(40, 3), LearnConfig(folds=3))


def test_relative_error_scores_only_forces_of_at_least_one_newton():
    err = relative_errors_pct([[1.1, 5.0, 0.2]], [[1.0, 4.0, 0.5]], [[True, True, True]])
    np.testing.assert_allclose(err, [10.0, 25.0])


def test_bad_inputs_are_named():
    with pytest.raises(InputError, match="2 \\+ 3K = 14"):
        TrainingSet(np.zeros((3, 5)), np.zeros((3, 4)), np.ones((3, 4), bool))
    with pytest.raises(InputError, match="hidden_l2"):
        LearnConfig(hidden_l2=())
    with pytest.raises(InputError, match="folds"):
        LearnConfig(folds=1)
    with pytest.raises(InputError, match="members"):
        LearnConfig(members=0)
    with pytest.raises(InputError, match="amount_loss must be one of squared, relative, got 'l1'"):
        LearnConfig(amount_loss="l1")
    with pytest.raises(InputError, match="relative_floor_n"):
        LearnConfig(relative_floor_n=0.0)


def test_the_relative_loss_predicts_the_weighted_median_and_the_squared_loss_the_mean():
    """Two users grip the same features with 2 N and 6 N alike often: the squared loss's minimiser
    is their mean, 4 N; the relative loss |a_hat - a| / a weighs the 2 N grip three times as much,
    so its minimiser is 2 N (between the two, the cost is ((a_hat - 2) / 2 + (6 - a_hat) / 6) / 2, rising
    from 2 N)."""
    n = 400
    x = np.tile(np.concatenate([[5.0, 0.1], np.zeros(2 * K), np.ones(K)]), (n, 1))  # features alike
    amount = np.where(np.arange(n) % 2 == 0, 2.0, 6.0)
    internal = amount[:, None] * np.full((n, K), 0.5)  # unit share vector, norm = amount
    data = TrainingSet(x, internal, np.ones((n, K), bool))
    squared = train(data, LearnConfig(epochs=300, seed=1))
    relative = train(data, LearnConfig(epochs=300, seed=1, amount_loss="relative"))
    a_sq = squared.predict(x, data.active)[0]
    a_rel = relative.predict(x, data.active)[0]
    assert abs(np.median(a_sq) - 4.0) < 0.05, np.median(a_sq)  # measured 4.000
    assert abs(np.median(a_rel) - 2.0) < 0.05, np.median(a_rel)  # measured 2.000
    assert "train_rel_err_l2" in relative.metadata and "train_mse_l2_std" in squared.metadata
    assert relative.config.amount_loss == "relative"


def test_learned_forces_explain_the_motion_and_follow_the_predictions():
    from fsv import Contacts, Kinematics, ObjectModel
    from fsv.features import grasp_features
    from fsv.forces import FrameStatus
    from fsv.learn import learned_forces, smooth_over_time

    rng = np.random.default_rng(4)
    T, names = 12, ("thumb", "index", "middle")
    point = np.array([[0.0, -0.0555, 0.0], [-0.03, 0.0555, 0.0], [0.03, 0.0555, 0.0]])
    normal = np.array([[0.0, 1, 0], [0.0, -1, 0], [0.0, -1, 0]])
    con = Contacts(names, np.ones((T, 3), bool), np.zeros((T, 3), bool), np.tile(point, (T, 1, 1)),
                   np.tile(normal, (T, 1, 1)), np.zeros((T, 3, 3)))
    obj = ObjectModel(size_m=[0.171, 0.111, 0.06], mass_kg=0.45,
                      inertia=ObjectModel.solid_box_inertia([0.171, 0.111, 0.06], 0.45), friction=0.8)
    kin = Kinematics(np.arange(T) / 30, np.tile([0, 0, 0.2], (T, 1)), np.tile(np.eye(3), (T, 1, 1)), np.zeros((T, 3)),
                     rng.normal(0, 1.0, (T, 3)), rng.normal(0, 0.5, (T, 3)), rng.normal(0, 2.0, (T, 3)), np.ones(T, bool))
    n = 300  # a rule on these three fingers: thumb opposes the two others, grip grows with the load
    x = np.concatenate([rng.uniform(2, 8, (n, 1)), rng.uniform(0, 0.05, (n, 1)), rng.uniform(-1, 1, (n, 6)), np.ones((n, 3))], 1)
    l2 = 2 + x[:, 0]
    internal = l2[:, None] * np.array([2.0, 1.0, 1.0]) / np.sqrt(6)
    model = train(TrainingSet(x, internal, np.ones((n, 3), bool)), LearnConfig(epochs=60), finger_names=names)
    sol, pred = learned_forces(model, kin, con, obj)
    assert np.all(sol.status == int(FrameStatus.OPTIMAL))
    scale = np.linalg.norm(sol.required, axis=1)
    assert np.max(np.linalg.norm(sol.residual, axis=1) / scale) <= 1e-6
    np.testing.assert_allclose(sol.finger_wrench + sol.env_wrench, sol.required, atol=1e-6 * scale.max())
    np.testing.assert_allclose(sol.internal_wrench, 0, atol=1e-6)
    assert pred.min() > 1.0  # the predictions are real grip forces ...
    np.testing.assert_allclose(sol.internal_normal, pred, atol=1e-3)  # ... and the internal parts follow them
    with pytest.raises(InputError, match="fingers"):
        learned_forces(model, kin, Contacts(("a", "b", "c"), con.active, con.sliding, con.point, con.normal, con.slide_dir), obj)
    # the amount is averaged over time, the shares stay per frame; 0 s gives the per-frame predictions
    feats = grasp_features(kin, con, obj)
    amount, shares, per_frame = model.predict(feats.matrix(), con.active)
    _, pred0 = learned_forces(model, kin, con, obj, smoothing_s=0.0)
    np.testing.assert_array_equal(pred0, per_frame)
    _, pred1 = learned_forces(model, kin, con, obj, smoothing_s=0.1)
    expected = smooth_over_time(amount, kin.t, np.ones(T, bool), 0.1)[:, None] * shares
    np.testing.assert_allclose(pred1, expected, rtol=1e-12)
    assert np.std(np.linalg.norm(pred1, axis=1)) < 0.5 * np.std(amount)  # the kinematics' noise is averaged out
    with pytest.raises(InputError, match="smoothing_s"):
        learned_forces(model, kin, con, obj, smoothing_s=-1.0)


def test_smooth_over_time_is_the_windowed_weighted_mean_over_defined_frames():
    from fsv.learn import smooth_over_time

    rng = np.random.default_rng(7)
    T, fps, sigma_s = 90, 30.0, 0.2
    t = np.arange(T) / fps
    v = rng.normal(5.0, 2.0, T)
    defined = np.ones(T, bool)
    defined[[0, 1, 40, 41, 42, 43, 70]] = False
    out = smooth_over_time(v, t, defined, sigma_s)
    dt = t[:, None] - t[None, :]  # the formula, by brute force
    w = np.exp(-0.5 * (dt / sigma_s) ** 2) * (np.abs(dt) <= 4 * sigma_s + 1e-12) * defined[None, :]
    expected = np.where(defined, (w * v[None, :]).sum(axis=1) / w.sum(axis=1), 0.0)
    np.testing.assert_allclose(out, expected, rtol=1e-6)  # SciPy's kernel is the sampled Gaussian, normalised
    np.testing.assert_array_equal(out[~defined], 0.0)
    # a constant stays itself up to the video's edges and the gaps (the window is renormalised)
    np.testing.assert_allclose(smooth_over_time(np.full(T, 3.0), t, defined, sigma_s)[defined], 3.0, rtol=1e-12)
    with pytest.raises(InputError, match="sigma_s"):
        smooth_over_time(v, t, defined, 0.0)
    with pytest.raises(InputError, match="one length"):
        smooth_over_time(v[:-1], t, defined, sigma_s)


# --- model files: digest, corruption, provenance ------------------------------------------------


@pytest.fixture(scope="module")
def small_file(tmp_path_factory):
    m = train(synthetic(200, 4), LearnConfig(epochs=20, seed=3, members=2), finger_names=("thumb", "index", "middle", "ring"))
    path = tmp_path_factory.mktemp("model") / "small.npz"
    m.save(path)
    return path


def _flipped(src, dest, offset, n):
    data = bytearray(src.read_bytes())
    for i in range(offset, offset + n):
        data[i] ^= 0xFF
    dest.write_bytes(bytes(data))
    return dest


def _largest_array_offset(path):
    import zipfile

    with zipfile.ZipFile(path) as z:
        info = max((i for i in z.infolist() if i.filename.startswith("net_")), key=lambda i: i.file_size)
        header = 30 + len(info.filename.encode()) + len(info.extra)  # local header: fixed part, name, extra
        return info.header_offset + header + info.file_size // 2


@pytest.mark.parametrize("where", ["middle", "weights", "header"])
def test_flipped_bytes_are_refused_with_the_files_name(small_file, tmp_path, where):
    """Flips in what is loaded are refused naming the file. The middle of the file may fall on zip
    padding or a header field nothing reads (the file's length varies with its provenance): then the
    file must load to exactly the original model."""
    offset = {"middle": small_file.stat().st_size // 2, "weights": _largest_array_offset(small_file), "header": 300}[where]
    bad = _flipped(small_file, tmp_path / f"flipped-{where}.npz", offset, 32)
    if where == "middle":
        try:
            model = load(bad)
        except InputError as e:
            assert re.search(r"flipped-middle\.npz' (is corrupt|is not a readable)", str(e)), e
        else:
            assert _same_state(model.state(), load(small_file).state())
        return
    with pytest.raises(InputError, match=r"flipped-%s\.npz' (is corrupt|is not a readable)" % where):
        load(bad)


def _same_state(a, b) -> bool:
    if isinstance(a, dict):
        return a.keys() == b.keys() and all(_same_state(a[k], b[k]) for k in a)
    if isinstance(a, (list, tuple)):
        return len(a) == len(b) and all(_same_state(x, y) for x, y in zip(a, b))
    if isinstance(a, np.ndarray):
        return a.dtype == b.dtype and np.array_equal(a, b)
    return a == b


def _rewrite(state, path):
    """Writes a model file's state as it is (a consistent zip, whatever the digest says)."""
    from fsv.learn.model import _to_arrays

    with open(path, "wb") as fh:
        np.savez(fh, **_to_arrays(state))
    return path


def test_an_edited_weight_or_metadata_with_the_old_digest_is_refused(small_file, tmp_path):
    """The zip's CRCs only see damaged bytes; the digest also sees a file rewritten with other content."""
    from fsv.learn import content_sha256, read_state

    st = read_state(small_file)
    assert st["sha256"] == content_sha256(st) and len(st["sha256"]) == 64
    st["net_l2"][1][0]["bias"][0] += 1e-12
    with pytest.raises(InputError, match=r"edited\.npz' is corrupt"):
        load(_rewrite(st, tmp_path / "edited.npz"))
    st = read_state(small_file)
    st["metadata"]["samples"] = 201
    with pytest.raises(InputError, match=r"meta\.npz' is corrupt"):
        load(_rewrite(st, tmp_path / "meta.npz"))
    st = read_state(small_file)
    st["net_decomp"][0][0]["weight"] = st["net_decomp"][0][0]["weight"][:, :-1].copy()
    st["sha256"] = content_sha256(st)
    with pytest.raises(InputError, match=r"shape\.npz' has inconsistent internal-force model data: net_decomp layers"):
        load(_rewrite(st, tmp_path / "shape.npz"))


def test_files_of_other_versions_or_without_a_digest_are_not_read(small_file, tmp_path):
    from fsv.learn import read_state

    st = read_state(small_file)
    st["version"] = 3
    with pytest.raises(InputError, match=r"v3\.npz' is an fsv-internal-forces file of version 3; this fsv reads version 4"):
        load(_rewrite(st, tmp_path / "v3.npz"))
    st["version"] = 4
    del st["sha256"]
    with pytest.raises(InputError, match=r"nodigest\.npz' is corrupt"):
        load(_rewrite(st, tmp_path / "nodigest.npz"))


def test_loading_and_predicting_do_not_import_torch(small_file):
    """A model is applied with NumPy alone: torch (a ~1.4 s import) is needed only to train."""
    import subprocess
    import sys

    code = ("import sys, numpy as np; from fsv.learn import load; m = load(sys.argv[1]); "
            "m.predict(np.zeros((3, 14)), np.ones((3, 4), bool)); print('torch' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code, str(small_file)], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


def test_the_forward_pass_equals_torchs(small_file):
    """fsv.learn.forward on the stored layers equals the torch network they came from."""
    import torch

    from fsv.learn import LearnConfig, forward
    from fsv.learn.nets import _mlp

    m = load(small_file)
    z = np.random.default_rng(0).normal(size=(50, 14))
    for net, hidden, n_out in ((m.net_l2[1], m.config.hidden_l2, 1), (m.net_decomp[0], m.config.hidden_decomp, 4)):
        t = _mlp(14, hidden, n_out, torch.Generator().manual_seed(0))
        with torch.no_grad():
            for lin, (W, b) in zip([x for x in t if isinstance(x, torch.nn.Linear)], net):
                lin.weight.copy_(torch.from_numpy(W))
                lin.bias.copy_(torch.from_numpy(b))
            ref = t(torch.from_numpy(z)).numpy()
        np.testing.assert_allclose(forward(net, z), ref, rtol=1e-12, atol=1e-12)
    assert isinstance(m.config, LearnConfig)


def test_model_files_record_their_provenance_and_keep_it_when_saved_again(small_file, tmp_path):
    from fsv.provenance import provenance

    m = load(small_file)
    assert m.metadata["provenance"]["fsv_bench"] == provenance()["fsv_bench"]
    assert m.metadata["provenance"]["dependencies"]["torch"] == provenance()["dependencies"]["torch"]
    m.metadata["provenance"]["python"]["version"] = "0.0.0"  # as if written elsewhere
    m.save(tmp_path / "again.npz")
    assert load(tmp_path / "again.npz").metadata["provenance"]["python"]["version"] == "0.0.0"


def test_the_shipped_model_carries_a_verified_digest():
    from importlib.resources import files

    from fsv.learn import VERSION, content_sha256, default_model, read_state

    st = read_state(files("fsv").joinpath("data", "internal_forces.npz"))
    assert st["version"] == VERSION and st["sha256"] == content_sha256(st)
    m = default_model()
    assert m.num_fingers == 5 and "provenance" in m.metadata


def test_a_truncated_file_is_reported_on_one_line(small_file, tmp_path):
    bad = tmp_path / "cut.npz"
    bad.write_bytes(small_file.read_bytes()[:5000])
    with pytest.raises(InputError) as e:
        load(bad)
    assert "\n" not in str(e.value) and "cut.npz' is not a readable internal-force model" in str(e.value)


def test_progress_is_reported_once_per_epoch_of_every_network():
    calls = []
    cfg = LearnConfig(epochs=7, seed=5, members=3, folds=2)
    a = train(synthetic(200, 1), cfg, on_epoch=calls.append)
    assert len(calls) == 2 * 3 * 7 and set(calls) == {1}  # ANN_L2 and ANN_decomp, every member, every epoch
    b = train(synthetic(200, 1), cfg)
    x = synthetic(200, 1)
    assert np.array_equal(a.predict(x.x, x.active)[2], b.predict(x.x, x.active)[2])  # the callback changes nothing
    calls.clear()
    cross_validate(synthetic(200, 1), cfg, on_epoch=calls.append)
    assert len(calls) == 2 * 2 * 3 * 7


def _two_grippers(n=400):
    """Two people show the camera the same features; one adds 2 N of internal force, the other 6 N,
    and their grip calibrations say so (baselines 2 and 6 N, no gain)."""
    x = np.tile(np.concatenate([[5.0, 0.1], np.zeros(2 * K), np.ones(K)]), (n, 1))
    firm = np.arange(n) % 2 == 1
    amount = np.where(firm, 6.0, 2.0)
    internal = amount[:, None] * np.full((n, K), 0.5)  # unit share vector, norm = amount
    grip = np.stack([amount, np.zeros(n)], axis=1)
    return TrainingSet(x, internal, np.ones((n, K), bool), grip=grip), firm


def test_grip_inputs_tell_the_people_apart_where_the_features_cannot(tmp_path):
    from fsv.grip import GripCalibration

    data, firm = _two_grippers()
    model = train(data, LearnConfig(epochs=300, seed=1, grip_inputs=True))
    assert model.num_inputs == 2 + 3 * K + 2
    np.testing.assert_allclose(model.grip_mean, [4.0, 0.0])
    a = model.predict(data.x, data.active, data.grip)[0]
    assert np.max(np.abs(a - np.where(firm, 6.0, 2.0))) < 0.05, np.max(np.abs(a - np.where(firm, 6.0, 2.0)))
    one = data.x[:1]
    assert abs(model.predict(one, data.active[:1], GripCalibration(6.0, 0.0))[0][0] - 6.0) < 0.05
    assert abs(model.predict(one, data.active[:1], np.array([2.0, 0.0]))[0][0] - 2.0) < 0.05
    # without a calibration the model assumes its training mean (4 N of baseline): between the two
    middle = model.predict(one, data.active[:1])[0][0]
    assert 2.5 < middle < 5.5, middle
    model.save(tmp_path / "grip.npz")
    back = load(tmp_path / "grip.npz")
    assert back.config.grip_inputs and np.array_equal(back.grip_mean, model.grip_mean)
    np.testing.assert_array_equal(back.predict(data.x, data.active, data.grip)[0], a)
    with pytest.raises(InputError, match="grip must be"):
        model.predict(one, data.active[:1], np.array([1.0, 2.0, 3.0]))


def test_grip_inputs_need_every_samples_calibration():
    data, _ = _two_grippers(40)
    blind = TrainingSet(data.x, data.internal, data.active)
    with pytest.raises(InputError, match="TrainingSet.grip"):
        train(blind, LearnConfig(epochs=2, grip_inputs=True))
    with pytest.raises(InputError, match=r"TrainingSet.grip must be finite with shape \(40, 2\)"):
        TrainingSet(data.x, data.internal, data.active, grip=np.zeros((40, 3)))
    with pytest.raises(InputError, match="grip_inputs must be True or False"):
        LearnConfig(grip_inputs="yes")
    # a blind model ignores a calibration; the subset keeps the calibrations of its samples
    model = train(data, LearnConfig(epochs=2))
    assert model.grip_mean is None and model.num_inputs == 2 + 3 * K
    np.testing.assert_array_equal(model.predict(data.x, data.active, data.grip)[0], model.predict(data.x, data.active)[0])
    np.testing.assert_array_equal(data.subset(np.arange(3)).grip, data.grip[:3])
