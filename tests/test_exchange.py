"""fsv-bench export / score: camera inputs out, estimates in; the file round trip equals in-process scores."""

import json
import zipfile

import numpy as np
import pytest
from tiny_suite import TINY

from benchmark.commands.cli import main
from benchmark.exchange import load_camera_input
from benchmark.suites import SUITES


@pytest.fixture
def tiny(monkeypatch):
    monkeypatch.setitem(SUITES, "tiny", TINY)
    return TINY


@pytest.mark.parametrize("knowledge, protocol", [("exact", "calibrated"), ("lab", "blind")])
def test_export_then_score_equals_the_in_process_scores(tiny, tiny_cache, tmp_path, capsys, knowledge, protocol):
    from benchmark.method import MethodSpec, method_label
    from benchmark.suites.evaluate import evaluate
    from examples.estimates_from_files import write_estimates

    cache, inputs, estimates = tiny_cache, tmp_path / "inputs", tmp_path / "estimates"
    spec = MethodSpec(differentiator="central", knowledge=knowledge, protocol=protocol)
    in_process = evaluate(TINY, spec=spec, cache=cache, progress=False)
    assert main(["export", "--suite", "tiny", "--out", str(inputs), "--cache", str(cache), "--quiet",
                 "--knowledge", knowledge, "--protocol", protocol]) == 0
    index = json.loads((inputs / "suite.json").read_text())
    assert [e["episode"] for e in index["episodes"]] == ["lift-u0-g0-m0-s21"]
    with zipfile.ZipFile(inputs / "lift-u0-g0-m0-s21.npz") as z:  # camera inputs only, no truth
        sections = {n.split("/")[0] for n in z.namelist() if n != "meta.json.npy"}
    # grip: measured on other recordings, given under the calibrated protocol only
    assert sections == {"camera", "init", "object", "hand"} | ({"grip"} if protocol == "calibrated" else set())
    assert index["protocol"] == protocol and f"--protocol {protocol}" in index["estimates"]
    given = load_camera_input(inputs / "lift-u0-g0-m0-s21.npz")[1]["knowledge"]
    assert given["knowledge"] == knowledge and "error" not in json.dumps(given)  # what was given, never the truth
    write_estimates(inputs, estimates, spec.build(), method_label(spec))
    capsys.readouterr()
    code = main(["score", "--suite", "tiny", "--estimates", str(estimates), "--out", str(tmp_path / "scores"),
                 "--cache", str(cache), "--quiet", "--knowledge", knowledge, "--protocol", protocol])
    assert code == (1 if in_process["verdict"] == "fail" else 0)  # the same verdict from files
    from_files = json.loads((tmp_path / "scores" / "scores.json").read_text())
    drop = ("seconds", "rendered")
    assert [{k: v for k, v in r.items() if k not in drop} for r in from_files["episodes"]] == \
           [{k: v for k, v in r.items() if k not in drop} for r in in_process["episodes"]]
    assert from_files["aggregate"] == in_process["aggregate"] and from_files["rendered"] == 0
    assert from_files["stages"]["differentiator"].startswith("central differentiation")
    if knowledge == "lab":  # estimates made under one knowledge are refused under the other, naming both
        capsys.readouterr()
        assert main(["score", "--suite", "tiny", "--estimates", str(estimates), "--out", str(tmp_path / "s2"),
                     "--cache", str(cache), "--quiet", "--knowledge", "exact"]) == 2
        assert "made from camera inputs with --knowledge lab, scored with --knowledge exact" in capsys.readouterr().err


def test_camera_file_round_trips_the_inputs(tiny, tiny_cache, tmp_path):
    from benchmark.exchange import save_camera_input
    from benchmark.method import camera_input
    from benchmark.suites.evaluate import cached_episode

    ep, _ = cached_episode(TINY, TINY.scenarios[0], tiny_cache)
    a = camera_input(ep, protocol="calibrated")
    path = save_camera_input(a, tmp_path / "x.npz", episode="x", suite=TINY, rng_seed=[1, 2])
    b, meta = load_camera_input(path)
    assert np.array_equal(a.depth.depth_m, b.depth.depth_m) and np.array_equal(a.calib.K, b.calib.K)
    assert np.array_equal(a.init.joints, b.init.joints) and a.object_model.mass_kg == b.object_model.mass_kg
    assert b.hand_model.finger_names == a.hand_model.finger_names and meta["rng_seed"] == [1, 2]
    from benchmark.method.grip_file import user_grip

    assert a.grip == user_grip(TINY.scenarios[0].user) and b.grip == a.grip and a.grip.samples > 0
    import dataclasses

    blind = save_camera_input(dataclasses.replace(a, grip=None), tmp_path / "y.npz", episode="y", suite=TINY,
                              rng_seed=[1, 2])
    assert load_camera_input(blind)[0].grip is None


def _write(path, arrays, meta):
    entries = {**arrays, "meta.json": np.frombuffer(json.dumps(meta).encode(), np.uint8)}
    np.savez(path, **entries)


@pytest.mark.parametrize("case, needle", [
    ("missing", "1 of 1 episodes have no estimates file (first: lift-u0-g0-m0-s21.npz)"),
    ("format", "is not an fsv-bench estimates file (format 'other'"),
])
def test_missing_or_foreign_estimates_exit_2_naming_the_file(tiny, tmp_path, capsys, case, needle):
    est = tmp_path / "est"
    est.mkdir()
    if case == "format":
        _write(est / "lift-u0-g0-m0-s21.npz", {}, {"format": "other", "version": 1})
    code = main(["score", "--suite", "tiny", "--estimates", str(est), "--out", str(tmp_path / "o"),
                 "--cache", str(tmp_path / "cache")])
    err = capsys.readouterr().err
    assert code == 2 and needle in err and err.count("\n") == 1
    assert not (tmp_path / "o").exists()


def test_an_estimates_file_of_the_wrong_shape_names_the_array(tiny, tmp_path):
    from benchmark.exchange import EstimatesFileError, load_estimate

    t = np.arange(5) / 30.0
    names = ["thumb", "index"]
    _write(tmp_path / "e.npz", {"box/pos": np.zeros((4, 3))},
           {"format": "fsv-bench-estimates", "version": 1, "finger_names": names})
    with pytest.raises(EstimatesFileError, match=r"box/pos has shape \(4, 3\), expected \(5, 3\)"):
        load_estimate(tmp_path / "e.npz", t=t, finger_names=tuple(names))


def _valid_arrays(T: int = 5, K: int = 2) -> dict:
    """A physical estimates file's arrays: the box at rest, finger 0 in contact from frame 1."""
    active = np.zeros((T, K), bool)
    active[1:, 0] = True
    normal = np.zeros((T, K, 3))
    normal[:, 0] = [0.0, 1.0, 0.0]
    return {"box/pos": np.zeros((T, 3)), "box/rot": np.repeat(np.eye(3)[None], T, 0),
            "contacts/active": active, "contacts/sliding": np.zeros((T, K), bool),
            "contacts/point": np.zeros((T, K, 3)), "contacts/normal": normal,
            **{f"kinematics/{f}": np.zeros((T, 3)) for f in ("vel", "acc", "omega", "alpha")},
            "kinematics/valid": np.ones(T, bool)}


def _bent(arrays: dict, name: str, change) -> dict:
    out = {k: np.array(v) for k, v in arrays.items()}
    change(out[name])
    return out


@pytest.mark.parametrize("name, change, needle", [
    ("box/rot", lambda a: a.__imul__(5.0), r"box/rot at frame 0 is not a rotation \(max \|R\^T R - I\| = 24"),
    ("box/rot", lambda a: a[3].__setitem__((2, 2), -1.0), r"box/rot at frame 3 is not a rotation .*det = -1"),
    ("box/pos", lambda a: a[2].__setitem__(0, np.nan), "box/pos at frame 2 is not finite"),
    ("contacts/normal", lambda a: a[4, 0].__imul__(2.0), "contacts/normal at frame 4 is not a unit vector"),
    ("contacts/sliding", lambda a: a[0].__setitem__(1, True), "contacts/sliding at frame 0 marks a finger that is not active"),
    ("contacts/point", lambda a: a[2, 0].__setitem__(1, np.inf), "contacts/point at frame 2 is not finite for an active"),
    ("kinematics/acc", lambda a: a[1].__setitem__(2, np.nan), "kinematics/acc at frame 1 is not finite where"),
])
def test_estimates_that_are_not_physical_are_refused_naming_the_array_and_frame(tmp_path, name, change, needle):
    from benchmark.exchange import EstimatesFileError, load_estimate

    t, names = np.arange(5) / 30.0, ("thumb", "index")
    meta = {"format": "fsv-bench-estimates", "version": 1, "finger_names": list(names)}
    _write(tmp_path / "ok.npz", _valid_arrays(), meta)
    assert load_estimate(tmp_path / "ok.npz", t=t, finger_names=names).box.rot.shape == (5, 3, 3)
    _write(tmp_path / "bad.npz", _bent(_valid_arrays(), name, change), meta)
    with pytest.raises(EstimatesFileError, match=needle) as e:
        load_estimate(tmp_path / "bad.npz", t=t, finger_names=names)
    assert str(tmp_path / "bad.npz") in str(e.value)


def test_nan_kinematics_where_invalid_and_nan_forces_are_accepted(tmp_path):
    from benchmark.exchange import load_estimate

    t, names = np.arange(5) / 30.0, ("thumb", "index")
    arrays = _valid_arrays()
    arrays["kinematics/valid"][:2] = False
    arrays["kinematics/acc"][:2] = np.nan
    arrays["nominal/force"] = np.full((5, 2, 3), np.nan)
    arrays["nominal/env_wrench"] = np.zeros((5, 6))
    arrays["nominal/status"] = np.full(5, 4, np.int8)
    _write(tmp_path / "e.npz", arrays, {"format": "fsv-bench-estimates", "version": 1, "finger_names": list(names)})
    est = load_estimate(tmp_path / "e.npz", t=t, finger_names=names)
    assert np.isnan(est.nominal.force).all() and not est.kinematics.valid[:2].any()


def test_an_estimates_file_renamed_to_another_episode_is_refused(tiny, tmp_path, capsys):
    est = tmp_path / "est"
    est.mkdir()
    _write(est / "lift-u0-g0-m0-s21.npz", _valid_arrays(),
           {"format": "fsv-bench-estimates", "version": 1, "episode": "lift-u0-g0-m0-s22", "finger_names": ["thumb"]})
    code = main(["score", "--suite", "tiny", "--estimates", str(est), "--out", str(tmp_path / "o"),
                 "--cache", str(tmp_path / "cache")])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1
    assert "meta.json names episode 'lift-u0-g0-m0-s22', not 'lift-u0-g0-m0-s21'" in err
    assert not (tmp_path / "o").exists() and not (tmp_path / "cache").exists()  # refused before any work


def test_a_cached_episode_copied_under_another_name_is_not_used(tmp_path, capsys):
    import shutil

    from benchmark.suites import Suite
    from benchmark.suites.evaluate import cached_episode, episode_identity, episode_key
    from benchmark.world.scenario import Scenario, episode_name

    a, b = (Scenario(task="lift", seed=s, duration_s=2.0) for s in (31, 32))
    suite = Suite(name="pair", version=1, scenarios=(a, b), gates=(), description="two short episodes")
    cache = tmp_path / "cache"
    ep_b, made = cached_episode(suite, b, cache)
    assert made and cached_episode(suite, b, cache)[1] is False  # the second time from the cache
    path_a = cache / "pair" / f"{episode_name(a)}-{episode_key(suite, a)}.npz"
    path_b = cache / "pair" / f"{episode_name(b)}-{episode_key(suite, b)}.npz"
    shutil.copyfile(path_b, path_a)  # seed 32 under seed 31's name
    ep_a, made = cached_episode(suite, a, cache)
    assert made and ep_a.scenario == a and "a renamed or copied file" in capsys.readouterr().err
    assert episode_identity(suite, a)["scenario"]["seed"] == 31


def test_check_says_whether_an_estimates_file_will_be_accepted(tiny, tiny_cache, tmp_path, capsys):
    meta = {"format": "fsv-bench-estimates", "version": 1, "episode": "lift-u0-g0-m0-s21", "finger_names": ["thumb", "index"]}
    _write(tmp_path / "ok.npz", _valid_arrays(), meta)
    assert main(["check", str(tmp_path / "ok.npz")]) == 0
    assert "ok.npz: ok: episode 'lift-u0-g0-m0-s21', 5 frames, 2 fingers" in capsys.readouterr().out
    _write(tmp_path / "bad.npz", _bent(_valid_arrays(), "box/rot", lambda a: a.__imul__(5.0)), meta)
    assert main(["check", str(tmp_path / "bad.npz")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "bad.npz: box/rot at frame 0 is not a rotation" in err
    # against the episode's camera inputs: its frames and fingers differ from this file's
    assert main(["export", "--suite", "tiny", "--out", str(tmp_path / "in"), "--cache", str(tiny_cache), "--quiet"]) == 0
    capsys.readouterr()
    assert main(["check", str(tmp_path / "ok.npz"), "--inputs", str(tmp_path / "in" / "lift-u0-g0-m0-s21.npz")]) == 2
    assert "finger_names ['thumb', 'index'] do not match the episode's" in capsys.readouterr().err


def test_hdf5_files_round_trip_to_the_same_scores_as_npz(tiny, tiny_cache, tmp_path, capsys):
    import h5py

    from benchmark.method import MethodSpec, method_label
    from examples.estimates_from_files import write_estimates

    cache, spec = tiny_cache, MethodSpec(differentiator="central")
    scores = {}
    for fmt in ("npz", "hdf5"):
        inputs, est = tmp_path / f"in-{fmt}", tmp_path / f"est-{fmt}"
        assert main(["export", "--suite", "tiny", "--out", str(inputs), "--cache", str(cache), "--quiet",
                     "--format", fmt]) == 0
        write_estimates(inputs, est, spec.build(), method_label(spec))
        code = main(["score", "--suite", "tiny", "--estimates", str(est), "--out", str(tmp_path / f"s-{fmt}"),
                     "--cache", str(cache), "--quiet", "--format", fmt])
        assert code in (0, 1)
        scores[fmt] = json.loads((tmp_path / f"s-{fmt}" / "scores.json").read_text())
    with h5py.File(tmp_path / "in-hdf5" / "lift-u0-g0-m0-s21.h5", "r") as f:  # plain HDF5, readable anywhere
        assert f["camera/depth_counts"].dtype == np.uint16 and f["camera/depth_counts"].ndim == 3
        assert json.loads(bytes(f["meta.json"][()]).decode())["episode"] == "lift-u0-g0-m0-s21"
    drop = ("seconds", "rendered")
    assert [{k: v for k, v in r.items() if k not in drop} for r in scores["hdf5"]["episodes"]] == \
           [{k: v for k, v in r.items() if k not in drop} for r in scores["npz"]["episodes"]]
    assert scores["hdf5"]["aggregate"] == scores["npz"]["aggregate"]


def test_a_folder_of_hdf5_estimates_scored_as_npz_is_told_to_give_format_hdf5(tmp_path):
    from benchmark.exchange.score import estimate_paths
    from benchmark.suites import get_suite
    from benchmark.world.scenario import episode_name

    suite = get_suite("smoke")
    for sc in suite.scenarios:
        (tmp_path / f"{episode_name(sc)}.h5").write_bytes(b"")
    with pytest.raises(ValueError, match=r"holds every episode's <episode>\.h5: give --format hdf5"):
        estimate_paths(suite, tmp_path)
    (tmp_path / f"{episode_name(suite.scenarios[0])}.h5").unlink()  # not every episode: no such hint
    with pytest.raises(ValueError) as refused:
        estimate_paths(suite, tmp_path)
    assert "--format" not in str(refused.value)
