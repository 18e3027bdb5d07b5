import json
import os
import subprocess

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from benchmark.atomic import write_marker
from benchmark.errors import DatasetError
from benchmark.paper.dataset import DatasetSpec, generate, load_dataset
from benchmark.paper.dataset.build import _with_meta
from benchmark.paper.dataset.cli import parse_ints
from benchmark.world.scenario import episode_name

CALLS = []


def cheap_build(sc, spec):
    """A stand-in world for the bookkeeping tests: three rows per episode."""
    CALLS.append(episode_name(sc))
    if len(CALLS) == 3 and os.environ.get("FSV_TEST_INTERRUPT") == "1":
        raise KeyboardInterrupt
    n = 3
    t = pa.table(dict(episode=[episode_name(sc)] * n, user=[sc.user] * n, frame=np.arange(n), p1=np.full(n, sc.seed, float)))
    return _with_meta(t, sc, spec, ["thumb"], dict(frames=n, rows=n), status="ok")


def test_resume_after_interrupt_neither_duplicates_nor_loses(tmp_path, monkeypatch):
    spec = DatasetSpec(tasks=("lift",), users=(0, 1), seeds=(0, 1, 2))
    CALLS.clear()
    monkeypatch.setenv("FSV_TEST_INTERRUPT", "1")
    write_marker(tmp_path)  # a killed run's dataset folder: marked when it was made
    (tmp_path / "episodes").mkdir()
    dead = subprocess.Popen(["true"])
    dead.wait()
    (tmp_path / "episodes" / f".tmp-lift-u0-g0-m0-s2.parquet.{dead.pid}.abcd1234.parquet").write_bytes(b"half")  # a killed run's
    with pytest.raises(KeyboardInterrupt):
        generate(spec, tmp_path, workers=1, progress=False, build=cheap_build)
    files = sorted(p.name for p in (tmp_path / "episodes").iterdir())
    assert files == ["lift-u0-g0-m0-s0.parquet", "lift-u0-g0-m0-s0.seconds.json", "lift-u0-g0-m0-s1.parquet",
                     "lift-u0-g0-m0-s1.seconds.json"]  # debris gone, nothing half-written
    monkeypatch.setenv("FSV_TEST_INTERRUPT", "0")
    man = generate(spec, tmp_path, workers=1, progress=False, build=cheap_build)
    assert CALLS == [episode_name(sc) for sc in spec.scenarios()[:3]] + [episode_name(sc) for sc in spec.scenarios()[2:]]
    assert sorted(man["episode"]) == sorted(episode_name(sc) for sc in spec.scenarios())
    assert man["rows"].sum() == 18
    df = load_dataset(tmp_path, user=1)
    assert len(df) == 9 and set(df["user"]) == {1}
    again = generate(spec, tmp_path, workers=1, progress=False, build=cheap_build)  # nothing left to do
    assert len(CALLS) == 7 and len(again) == 6


def test_resume_with_another_spec_is_refused(tmp_path):
    generate(DatasetSpec(seeds=(0,)), tmp_path, workers=1, progress=False, build=cheap_build)
    with pytest.raises(DatasetError, match="another spec"):
        generate(DatasetSpec(seeds=(0, 1)), tmp_path, workers=1, progress=False, build=cheap_build)


def test_resume_of_a_dataset_of_another_world_is_refused(tmp_path):
    import json

    generate(DatasetSpec(seeds=(0,)), tmp_path, workers=1, progress=False, build=cheap_build)
    header = json.loads((tmp_path / "dataset.json").read_text())
    header["world"] = "0" * 64  # as if the simulation had changed since
    (tmp_path / "dataset.json").write_text(json.dumps(header))
    with pytest.raises(DatasetError, match="another world"):
        generate(DatasetSpec(seeds=(0,)), tmp_path, workers=1, progress=False, build=cheap_build)


def test_ray_without_ray_installed_says_how_to_get_it(tmp_path):
    try:
        import ray  # noqa: F401
        pytest.skip("ray is installed")
    except ImportError:
        pass
    with pytest.raises(DatasetError, match=r"fsv-bench\[ray\]"):
        generate(DatasetSpec(seeds=(0, 1)), tmp_path, ray_address="auto", progress=False, build=cheap_build)


def test_bad_spec_and_ranges():
    assert parse_ints("0,2,5-7") == (0, 2, 5, 6, 7)
    with pytest.raises(DatasetError, match="'a-b'"):
        parse_ints("a-b")
    with pytest.raises(DatasetError, match="users"):
        DatasetSpec(users=(-1,))
    with pytest.raises(DatasetError, match="kinematics source"):
        DatasetSpec(kinematics="magic")


# --- the real world: short episodes -------------------------------------------------------------

def test_targets_split_the_tactile_forces_and_features_follow_the_truth(learn_oracle_dataset):
    from benchmark.paper.dataset import finger_names_of

    spec, out, man = learn_oracle_dataset
    assert list(man["status"]) == ["ok", "ok"] and man["rows"].min() > 20
    assert set(man["kinematics"]) == {"oracle"} and set(man["contacts"]) == {"oracle"}
    df = load_dataset(out)
    names = finger_names_of(df)
    act = df[[f"active_{n}" for n in names]].to_numpy()
    meas = df[[f"f_meas_{n}" for n in names]].to_numpy()
    np.testing.assert_array_equal(meas, df[[f"f_true_{n}" for n in names]].to_numpy())  # noise-free sensors
    nom = df[[f"f_nom_{n}" for n in names]].to_numpy()
    internal = df[[f"f_int_{n}" for n in names]].to_numpy()
    # oracle kinematics, box off the table: the true forces are a feasible total, so eq. 9 splits them exactly
    air = (df["pos_z"] > 0.03 + 0.005).to_numpy()
    assert air.sum() > 20
    np.testing.assert_allclose((nom + internal)[act & air[:, None]], meas[act & air[:, None]], atol=2e-3)
    assert np.all(np.linalg.norm(internal[air], axis=1) > 1.0)  # humans over-grip: a real squeeze in the air
    assert np.all(df["net_gap_n"] <= spec.max_gap_n)
    assert np.all(act.sum(axis=1) >= 2)
    from benchmark.paper.table2 import object_models

    acc = df[["acc_x", "acc_y", "acc_z"]].to_numpy()
    om, g = object_models(out)[df["episode"][0]]
    first = (df["episode"] == df["episode"][0]).to_numpy()
    np.testing.assert_allclose(df["p1"][first], om.mass_kg * np.linalg.norm(acc[first] - g, axis=1), rtol=1e-9)
    assert om.mass_kg == pytest.approx(0.30)  # masses.yaml entry 0


def test_pool_output_equals_in_process_output(learn_oracle_dataset, tmp_path):
    import pandas as pd

    spec, out, _ = learn_oracle_dataset
    man = generate(spec, tmp_path, workers=2, progress=False)
    assert sorted(man["episode"]) == ["lift-u0-g0-m0-s0", "lift-u0-g0-m0-s1"]
    pd.testing.assert_frame_equal(load_dataset(tmp_path), load_dataset(out))


def test_tracker_source_uses_the_pipelines_contacts_and_poses(tracked_lift):
    """contacts="tracker" renders and tracks each episode exactly as fsv-bench / run_pipeline do."""
    import json

    from benchmark.paper.dataset import build_episode, finger_names_of

    ep, est = tracked_lift
    spec = DatasetSpec(duration_s=ep.scenario.duration_s, contacts="tracker")
    assert spec.scenarios() == [ep.scenario]
    table = build_episode(ep.scenario, spec)
    meta = json.loads(table.schema.metadata[b"fsv"])
    assert meta["contacts"] == "tracker" and meta["tracking"]["frames"] == len(ep.truth.t)
    df = table.to_pandas()
    assert len(df) > 20
    rows = df["frame"].to_numpy()
    names = finger_names_of(df)
    tracked = est.tracking.contacts
    np.testing.assert_array_equal(df[[f"active_{n}" for n in names]].to_numpy(), tracked.active[rows])
    for k, n in enumerate(names):
        for a, ax in enumerate("xyz"):
            np.testing.assert_array_equal(df[f"point_{ax}_{n}"], tracked.point[rows, k, a])
            np.testing.assert_array_equal(df[f"true_point_{ax}_{n}"], ep.truth.contact_point[rows, k, a])
    # differentiated from the tracked poses as the method does
    np.testing.assert_array_equal(df[["acc_x", "acc_y", "acc_z"]].to_numpy(), est.kinematics.acc[rows])
    assert meta["tracking"]["contact_err_mm_std"] > 0  # the tracker's contacts, not the truth's


def test_plausibility_rule_on_a_constructed_frame(learn_oracle_dataset):
    from benchmark.scores.samples import nominal_excess_n

    nominal = [[3.0, 2.0, 9.0, 0.0], [3.0, 2.0, 1.0, 0.0]]
    measured = [[10.0, 5.0, np.nan, np.nan], [10.0, 0.5, 4.0, np.nan]]
    active = [[True, True, True, False], [True, True, True, False]]
    # frame 0: vision pushes 9 N with a finger whose sensor reads nothing; frame 1: index 1.5 N above its reading
    np.testing.assert_allclose(nominal_excess_n(nominal, measured, active), [9.0, 1.5])
    assert nominal_excess_n([[1.0, 1.0]], [[0.0, 0.0]], [[False, False]])[0] == -np.inf
    spec, out, _ = learn_oracle_dataset
    everything = load_dataset(out)
    # oracle contacts and kinematics: the true forces explain the motion, so the least forces never exceed them
    assert len(load_dataset(out, max_excess_n=1.5)) == len(everything)
    strict = load_dataset(out, max_excess_n=-0.5)  # nominal at least 0.5 N below every reading
    assert 0 < len(strict) < len(everything)


# --- integrity: digests, damaged, truncated and renamed files ------------------------------------


def _flip(path, offset, n=4):
    data = bytearray(path.read_bytes())
    for i in range(offset, offset + n):
        data[i] ^= 0xFF
    path.write_bytes(bytes(data))


def _content_offset(path, column: str) -> int:
    """An offset inside the stored values of ``column`` (4 bytes before its chunk's end: page data,
    not a header or the statistics, whose damage would leave the table's content as it was)."""
    chunk = next(c for c in (pq.ParquetFile(path).metadata.row_group(0).column(i) for i in range(pq.ParquetFile(
        path).metadata.num_columns)) if c.path_in_schema == column)
    start = chunk.dictionary_page_offset if chunk.has_dictionary_page else chunk.data_page_offset
    return start + chunk.total_compressed_size - 8


def _small(tmp_path, seeds=(0, 1, 2)):
    spec = DatasetSpec(seeds=seeds)
    generate(spec, tmp_path, workers=1, progress=False, build=cheap_build)
    return spec


def test_every_table_carries_its_digest_and_the_manifest_the_files_bytes(tmp_path):
    import hashlib
    import json

    import pyarrow.parquet as pq

    from benchmark.sealed_table import table_sha256

    _small(tmp_path)
    man = pq.read_table(tmp_path / "manifest.parquet")
    assert json.loads(man.schema.metadata[b"fsv"])["sha256"] == table_sha256(man)
    for row in man.to_pylist():
        path = tmp_path / row["file"]
        assert row["sha256"] == hashlib.sha256(path.read_bytes()).hexdigest()
        table = pq.read_table(path)
        assert json.loads(table.schema.metadata[b"fsv"])["sha256"] == table_sha256(table)


def test_dataset_json_records_the_provenance_and_later_runs(tmp_path):
    import json

    from fsv.provenance import provenance

    spec = _small(tmp_path, seeds=(0,))
    header = json.loads((tmp_path / "dataset.json").read_text())
    assert header["provenance"] == provenance() and "resumed_with" not in header
    header["provenance"]["python"]["version"] = "0.0.0"  # as if made elsewhere
    (tmp_path / "dataset.json").write_text(json.dumps(header))
    generate(spec, tmp_path, workers=1, progress=False, build=cheap_build)
    generate(spec, tmp_path, workers=1, progress=False, build=cheap_build)
    header = json.loads((tmp_path / "dataset.json").read_text())
    assert header["provenance"]["python"]["version"] == "0.0.0" and header["resumed_with"] == [provenance()]


def test_a_dataset_of_the_version_without_digests_is_not_resumed(tmp_path):
    import json

    (tmp_path / "dataset.json").write_text(json.dumps(dict(format="fsv-bench-dataset", version=1, spec=DatasetSpec().as_dict())))
    with pytest.raises(DatasetError, match="version 1; this fsv-bench writes version 3"):
        generate(DatasetSpec(), tmp_path, workers=1, progress=False, build=cheap_build)


@pytest.fixture()
def oracle_copy(learn_oracle_dataset, tmp_path):
    """A copy of the small simulated dataset that a test may damage."""
    import shutil

    spec, out, _ = learn_oracle_dataset
    shutil.copytree(out, tmp_path / "d")
    return spec, tmp_path / "d"


def test_four_flipped_bytes_in_an_episode_file_are_refused_naming_it(oracle_copy):
    import pyarrow.parquet as pq

    from benchmark.errors import DatasetFileError
    from benchmark.paper.dataset import read_episode_file

    spec, out = oracle_copy
    path = out / "episodes" / "lift-u0-g0-m0-s1.parquet"
    chunk = pq.ParquetFile(path).metadata.row_group(0).column(20)  # a float column's values
    _flip(path, chunk.data_page_offset + chunk.total_compressed_size // 2)
    with pytest.raises(DatasetFileError, match=str(path)):
        load_dataset(out)
    with pytest.raises(DatasetFileError, match=f"{path} is (corrupt: its content|truncated or corrupt)"):
        read_episode_file(str(path))  # without the manifest: the file's own digest sees it
    assert len(load_dataset(out, seed=0)) > 20  # the other episode is fine


def test_a_flip_that_leaves_the_content_intact_is_seen_by_the_manifest(oracle_copy):
    """Some bytes (e.g. the magic number, column statistics) change nothing a reader gets: the
    content digest cannot see them there, the SHA-256 of the bytes in the manifest does."""
    from benchmark.errors import DatasetFileError
    from benchmark.paper.dataset import read_episode_file

    spec, out = oracle_copy
    path = out / "episodes" / "lift-u0-g0-m0-s0.parquet"
    _flip(path, 0)  # "PAR1" at the start: readers use the footer's copy
    _, meta, _ = read_episode_file(str(path))  # the content is intact
    assert meta["episode"] == "lift-u0-g0-m0-s0"
    with pytest.raises(DatasetFileError, match=f"{path} is corrupt: its bytes do not match the SHA-256 in the manifest"):
        load_dataset(out)


def test_a_damaged_manifest_is_refused_and_rebuilt_on_resume(tmp_path, capsys):
    from benchmark.errors import DatasetFileError

    spec = _small(tmp_path)
    man = tmp_path / "manifest.parquet"
    _flip(man, _content_offset(man, "sha256"))  # (a flip at a third of the file could land in statistics)
    with pytest.raises(DatasetFileError, match=str(man)):
        load_dataset(tmp_path)
    CALLS.clear()
    generate(spec, tmp_path, workers=1, progress=False, build=cheap_build)
    assert CALLS == [] and f"generate: {man}" in capsys.readouterr().err
    assert len(load_dataset(tmp_path)) == 9


def test_resume_rebuilds_a_truncated_episode_file_and_says_so(tmp_path, capsys):
    spec = _small(tmp_path)
    path = tmp_path / "episodes" / "lift-u0-g0-m0-s1.parquet"
    path.write_bytes(path.read_bytes()[: path.stat().st_size // 2])
    CALLS.clear()
    man = generate(spec, tmp_path, workers=1, progress=False, build=cheap_build)
    err = capsys.readouterr().err
    assert f"generate: {path} is truncated or corrupt" in err and "rebuilding it" in err
    assert CALLS == ["lift-u0-g0-m0-s1"] and len(man) == 3
    assert sorted(load_dataset(tmp_path)["p1"].unique()) == [0.0, 1.0, 2.0]


def test_an_episode_file_copied_over_another_is_detected_and_rebuilt(tmp_path, capsys):
    import shutil

    from benchmark.errors import DatasetFileError
    from benchmark.paper.dataset import read_episode_file

    spec = _small(tmp_path)
    a, b = (tmp_path / "episodes" / f"lift-u0-g0-m0-s{s}.parquet" for s in (0, 2))
    shutil.copyfile(a, b)
    with pytest.raises(DatasetFileError, match=f"{b} holds episode 'lift-u0-g0-m0-s0'.*renamed or copied"):
        read_episode_file(str(b))
    with pytest.raises(DatasetFileError, match=str(b)):
        load_dataset(tmp_path)
    CALLS.clear()
    generate(spec, tmp_path, workers=1, progress=False, build=cheap_build)
    assert CALLS == ["lift-u0-g0-m0-s2"] and f"{b} holds episode 'lift-u0-g0-m0-s0'" in capsys.readouterr().err
    df = load_dataset(tmp_path, seed=2)
    assert set(df["p1"]) == {2.0} and set(df["episode"]) == {"lift-u0-g0-m0-s2"}


def test_an_episode_of_another_scenario_under_the_right_name_is_rebuilt(tmp_path, capsys):
    import shutil

    generate(DatasetSpec(seeds=(0,), duration_s=1.0), tmp_path / "one", workers=1, progress=False, build=cheap_build)
    spec = DatasetSpec(seeds=(0,), duration_s=2.0)
    generate(spec, tmp_path / "two", workers=1, progress=False, build=cheap_build)
    name = "episodes/lift-u0-g0-m0-s0.parquet"
    shutil.copyfile(tmp_path / "one" / name, tmp_path / "two" / name)
    (tmp_path / "two" / "manifest.parquet").unlink()  # as after an interrupted run: the file must speak for itself
    CALLS.clear()
    generate(spec, tmp_path / "two", workers=1, progress=False, build=cheap_build)
    assert CALLS == ["lift-u0-g0-m0-s0"] and "made with another scenario" in capsys.readouterr().err
    assert len(load_dataset(tmp_path / "two")) == 3


def test_a_local_ray_cluster_makes_the_same_dataset_as_the_local_pool(learn_oracle_dataset, ray_cluster, tmp_path):
    """In this process, on a pool of two worker processes and on a local Ray cluster: the same
    episode files, byte for byte."""
    import pandas as pd

    spec, out, _ = learn_oracle_dataset
    pool = generate(spec, tmp_path / "pool", workers=2, progress=False)
    for f in pool["file"]:
        assert (tmp_path / "pool" / f).read_bytes() == (out / f).read_bytes(), f
    man = generate(spec, tmp_path / "ray", ray_address=ray_cluster, progress=False)
    assert sorted(man["episode"]) == ["lift-u0-g0-m0-s0", "lift-u0-g0-m0-s1"] and (man["status"] == "ok").all()
    pd.testing.assert_frame_equal(load_dataset(tmp_path / "ray"), load_dataset(out))
    import json

    import pyarrow.parquet as pq

    for f in man["file"]:  # the episode files are the same bytes; only the timing beside them differs
        assert (tmp_path / "ray" / f).read_bytes() == (out / f).read_bytes(), f
        assert "seconds" not in json.loads(pq.read_table(tmp_path / "ray" / f).schema.metadata[b"fsv"])
    assert (man["seconds"] > 0).all() and np.isfinite(man["seconds"]).all()


def test_a_bad_ray_address_fails_within_seconds(tmp_path):
    import time

    spec = DatasetSpec(tasks=("lift",), seeds=(0,), duration_s=1.5, kinematics="oracle", contacts="oracle")
    t0 = time.perf_counter()
    with pytest.raises(DatasetError, match="'127.0.0.1:9': no Ray cluster answers there"):
        generate(spec, tmp_path / "d", ray_address="127.0.0.1:9", progress=False)
    assert time.perf_counter() - t0 < 10, time.perf_counter() - t0
    assert not (tmp_path / "d").exists()  # refused before any work
    with pytest.raises(DatasetError, match="expected 'auto', 'host:port'"):
        generate(spec, tmp_path / "d", ray_address="nowhere", progress=False)


@pytest.mark.parametrize("argv, needle", [
    (["--tasks", "nope"], "unknown task 'nope'; accepted: lift"),
    (["--users", "x"], "--users 'x': expected non-negative integers and ranges like '0,2,5-7'"),
    (["--split", "cohort"], "--split 'cohort': accepted: train, dev, test"),
    (["--design", "pairs"], "design source must be one of ('grid', 'people'), got 'pairs'"),
    (["--duration", "0.1"], "duration 0.1 s is too short for task 'lift'; accepted: >= 1.0 s"),
])
def test_generate_refuses_a_bad_grid_before_any_work_and_writes_nothing(tmp_path, capsys, argv, needle):
    from benchmark.commands.cli import main

    out = tmp_path / "data"
    assert main(["generate", "--out", str(out), *argv]) == 2
    err = capsys.readouterr().err
    assert needle in err and err.count("\n") == 1 and not out.exists()


def _dead_pid() -> int:
    import subprocess
    import sys

    proc = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True)
    return int(proc.stdout)


def test_a_stale_claim_of_a_dead_run_is_taken_over(tmp_path):
    import json
    import socket

    spec = DatasetSpec(tasks=("lift",), seeds=(0, 1))
    write_marker(tmp_path)  # a killed run's dataset folder: marked when it was made
    (tmp_path / "episodes").mkdir(parents=True)
    claim = tmp_path / "episodes" / "lift-u0-g0-m0-s0.claim"
    claim.write_text(json.dumps({"host": socket.gethostname(), "pid": _dead_pid()}))  # a killed run's claim
    CALLS.clear()
    man = generate(spec, tmp_path, workers=1, progress=False, build=cheap_build)
    assert sorted(CALLS) == ["lift-u0-g0-m0-s0", "lift-u0-g0-m0-s1"] and (man["status"] == "ok").all()
    assert not list((tmp_path / "episodes").glob("*.claim"))


def test_concurrent_runs_share_the_work_instead_of_repeating_it(tmp_path, monkeypatch):
    """An episode claimed by another live run is left to it; this run waits for its file."""
    import json
    import socket
    import threading
    import time

    import benchmark.paper.dataset.claims as claims
    from benchmark.paper.dataset.build import _run_one
    from benchmark.paper.dataset.files import _write_sealed

    monkeypatch.setattr(claims, "CLAIM_POLL_S", 0.05)
    spec = DatasetSpec(tasks=("lift",), seeds=(0, 1, 2))
    (tmp_path / "d" / "episodes").mkdir(parents=True)
    write_marker(tmp_path / "d")  # another run's dataset folder: marked when it was made
    other = tmp_path / "d" / "episodes" / "lift-u0-g0-m0-s1.claim"
    other.write_text(json.dumps({"host": socket.gethostname(), "pid": os.getppid()}))  # a live "other run"
    CALLS.clear()
    result = {}
    run = threading.Thread(target=lambda: result.update(man=generate(spec, tmp_path / "d", workers=1, progress=False,
                                                                     build=cheap_build)))
    run.start()
    deadline = time.time() + 30
    while sorted(CALLS) != ["lift-u0-g0-m0-s0", "lift-u0-g0-m0-s2"] and time.time() < deadline:
        time.sleep(0.05)
    time.sleep(0.3)
    assert run.is_alive()  # waiting for the other run's episode
    sc = next(s for s in spec.scenarios() if s.seed == 1)  # the other run finishes its episode
    _write_sealed(_run_one(sc, spec, lambda s, p: cheap_build(s, p)), str(tmp_path / "d" / "episodes" / "lift-u0-g0-m0-s1.parquet"))
    other.unlink()
    run.join(30)
    assert not run.is_alive()
    assert CALLS.count("lift-u0-g0-m0-s1") == 1  # made once, by the other run
    assert sorted(result["man"]["episode"]) == ["lift-u0-g0-m0-s0", "lift-u0-g0-m0-s1", "lift-u0-g0-m0-s2"]


def test_generate_shows_every_tracked_frame_across_the_worker_processes(tmp_path, capsys):
    """The tracker source reports each tracked frame from the workers to one progress bar."""
    spec = DatasetSpec(tasks=("lift",), seeds=(0, 1), duration_s=1.5, kinematics="oracle")
    man = generate(spec, tmp_path, workers=2, progress=True)
    assert (man["status"] == "ok").all()
    err = capsys.readouterr().err
    assert "tracked: 100%" in err and "92/92" in err  # 2 episodes x 46 frames


def test_a_corrupt_dataset_header_is_refused_naming_the_file(tmp_path, capsys):
    from benchmark.commands.cli import main
    from benchmark.paper.dataset.files import read_header

    header = tmp_path / "d" / "dataset.json"
    header.parent.mkdir()
    header.write_text('{"format": "fsv-bench-dataset"\n "version": 2}')
    assert main(["generate", "--out", str(tmp_path / "d"), "--tasks", "lift", "--seeds", "0"]) == 2
    err = capsys.readouterr().err
    assert f"{header} is not a readable dataset header (made by `fsv-bench generate`): Expecting ','" in err
    assert err.count("\n") == 1 and header.read_text().startswith('{"format"')  # left as it was
    header.write_text("[1, 2]")
    with pytest.raises(DatasetError, match=f"{header} is not a dataset header"):
        read_header(tmp_path / "d")


def test_generate_from_the_training_split_draws_its_people_grasps_and_views(tmp_path, capsys):
    from benchmark.commands.cli import main
    from benchmark.suites.splits import split_of
    from benchmark.world.scenario import Scenario

    out = tmp_path / "train"
    # person 1003's own grasp is one the training sets store (a grasp no set stores is drawn and
    # searched for where the data is made: test_grasp_families)
    argv = ["generate", "--out", str(out), "--split", "train", "--users", "3", "--grasps", "3", "--views", "7-8",
            "--duration", "1.5", "--kinematics", "oracle", "--contacts", "oracle", "--workers", "1", "--no-progress"]
    assert main(argv) == 0
    names = sorted(p.name for p in (out / "episodes").glob("*.parquet"))
    assert names == ["lift-u1003-g1003-m0-s0-v1007.parquet", "lift-u1003-g1003-m0-s0-v1008.parquet"]
    assert split_of(Scenario(user=1003, grasp=1003, view=1008)) == "train"
    header = json.loads((out / "dataset.json").read_text())
    assert header["spec"]["users"] == [1003] and header["spec"]["grasps"] == [1003] and header["spec"]["views"] == [1007, 1008]
    # a dataset of the paper's view alone keeps the header it had before views existed
    assert "views" not in DatasetSpec().as_dict()


def test_the_people_design_gives_each_person_their_own_grasp_and_view_and_rotates_the_masses():
    spec = DatasetSpec(tasks=("lift", "place", "rotate"), users=(1000, 1001), masses=(0, 2, 5), seeds=(7, 8),
                       design="people")
    scs = spec.scenarios()
    assert len(scs) == 2 * 3 * 2
    assert all(sc.grasp == sc.user and sc.view == sc.user for sc in scs)
    masses = {(sc.user, sc.task, sc.seed): sc.mass for sc in scs}
    assert masses[1000, "lift", 7] == 0 and masses[1000, "place", 7] == 2 and masses[1000, "rotate", 8] == 0
    assert masses[1001, "lift", 7] == 2 and masses[1001, "rotate", 7] == 0
    for task in ("lift", "place", "rotate"):  # every task meets every mass
        assert {m for (u, t, s), m in masses.items() if t == task} == {0, 2, 5}
    assert spec.as_dict()["design"] == "people" and "design" not in DatasetSpec().as_dict()
    with pytest.raises(DatasetError, match="design source must be one of"):
        DatasetSpec(design="pairs")


def _per_finger(df, fmt, names):
    return np.stack([df[[fmt.format(a, n) for a in "xyz"]].to_numpy(float) for n in names], axis=1)


def test_rows_all_hold_every_frame_with_the_truths_3d_forces_and_table_wrench(direct_dataset):
    """The 3D force's normal part is f_true_; with the truth's kinematics, the table's wrench and the
    fingers' resultant are Newton–Euler's m R^T (a - g) and I alpha + omega x I omega in the object
    frame (measured: 6e-15 N and 1e-16 N m)."""
    from benchmark.paper.dataset import finger_names_of
    from benchmark.paper.table2 import object_models

    _, out = direct_dataset
    df = load_dataset(out / "data", rows="all")
    assert len(df) == 2 * 61 and df["paper_rule"].sum() < len(df)  # 2 s at 30 fps, every frame with kinematics
    names = finger_names_of(df)
    F = _per_finger(df, "F_true_{}_{}", names)
    normal = _per_finger(df, "normal_{}_{}", names)  # the truth's contacts: the truth's normals
    np.testing.assert_allclose(np.einsum("tki,tki->tk", F, normal), df[[f"f_true_{n}" for n in names]], atol=1e-12)
    assert (F[~df[[f"true_active_{n}" for n in names]].to_numpy()] == 0).all()
    R = df[[f"rot_{i}{j}" for i in range(3) for j in range(3)]].to_numpy().reshape(-1, 3, 3)
    obj = lambda name: np.einsum("tji,tj->ti", R, df[[f"{name}_{a}" for a in "xyz"]].to_numpy())
    models = object_models(out / "data")
    for ep in df["episode"].unique():
        m, g = models[ep]
        e = (df["episode"] == ep).to_numpy()
        force = df.loc[e, ["env_F_x", "env_F_y", "env_F_z"]].to_numpy() + F[e].sum(axis=1)
        np.testing.assert_allclose(force, m.mass_kg * np.einsum("tji,tj->ti", R[e], df.loc[e, ["acc_x", "acc_y", "acc_z"]]
                                                                 .to_numpy() - g), atol=1e-9)
        w, al, I = obj("omega")[e], obj("alpha")[e], m.inertia
        points = _per_finger(df[e], "true_point_{}_{}", names)
        torque = df.loc[e, ["env_T_x", "env_T_y", "env_T_z"]].to_numpy() + np.cross(points, F[e]).sum(axis=1)
        np.testing.assert_allclose(torque, al @ I.T + np.cross(w, w @ I.T), atol=1e-10)
    resting = df["env_F_z"].to_numpy() > 0
    assert resting.sum() > 10 and (df.loc[resting, "pos_z"] < 0.031).all()  # the table holds the box before the lift
    paper = df["paper_rule"].to_numpy()
    f_nom = df[[f"f_nom_{n}" for n in names]].to_numpy()
    assert np.isnan(f_nom[~paper]).all() and np.isfinite(f_nom[paper]).all()


def test_the_paper_rows_of_a_dataset_of_every_frame_are_the_paper_dataset(direct_dataset, tmp_path):
    from dataclasses import replace

    import pandas as pd

    spec, out = direct_dataset

    generate(replace(spec, rows="paper"), tmp_path, workers=1, progress=False)
    paper, every = load_dataset(tmp_path), load_dataset(out / "data")  # rows="paper" by default
    pd.testing.assert_frame_equal(paper, every)
    assert paper["paper_rule"].all() and len(load_dataset(out / "data", rows="all")) > len(paper)
    with pytest.raises(DatasetError, match="made with another spec"):  # resuming is refused with other rows
        generate(replace(spec, rows="paper"), out / "data", workers=1, progress=False, build=cheap_build)
    with pytest.raises(DatasetError, match="rows source must be one of"):
        DatasetSpec(rows="some")
    assert spec.as_dict()["rows"] == "all"
    assert "rows" not in replace(spec, rows="paper").as_dict()
