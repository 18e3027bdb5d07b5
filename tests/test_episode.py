"""Episode files: a versioned npz + JSON format that round-trips exactly and refuses bad files."""

import io
import json
import zipfile
import zlib

import numpy as np
import pytest

from benchmark.archive import FAST_DEFLATE_LEVEL
from benchmark.camera.episode_file import FORMAT, VERSION, depth_arrays, load_episode, save_episode
from benchmark.errors import EpisodeFileError
from fsv import Calibration, DepthVideo


@pytest.fixture(scope="module")
def saved(lift_episode, tmp_path_factory):
    ep = lift_episode[0]
    return ep, save_episode(ep, tmp_path_factory.mktemp("ep") / "lift")


def test_round_trip_is_exact(saved):
    ep, path = saved
    assert path.suffix == ".npz"
    back = load_episode(path)
    assert back.scenario == ep.scenario
    for name, value in ep.truth.as_dict().items():
        got = getattr(back.truth, name)
        assert np.asarray(got).dtype == np.asarray(value).dtype, name
        np.testing.assert_array_equal(got, value, err_msg=name)
    np.testing.assert_array_equal(back.object_model.inertia, ep.object_model.inertia)
    assert back.object_model.mass_kg == ep.object_model.mass_kg
    assert back.hand_model.joint_names == ep.hand_model.joint_names
    np.testing.assert_array_equal(back.hand_model.geom_fromto, ep.hand_model.geom_fromto)
    assert back.depth is None and back.calib is None and back.labels is None


def test_rendered_parts_round_trip(saved, tmp_path):
    ep, _ = saved
    T = len(ep.truth.t)
    depth = DepthVideo(depth_m=np.random.default_rng(0).uniform(0, 1, (T, 4, 5)).astype(np.float32), fps=30)
    calib = Calibration(K=np.diag([200.0, 200.0, 1.0]), T_world_cam=np.eye(4), width=5, height=4)
    labels = np.zeros((T, 4, 5), np.uint8)
    labels[:, 1, 2] = 11
    back = load_episode(save_episode(ep.with_depth(depth, calib, labels), tmp_path / "r.npz"))
    np.testing.assert_allclose(back.depth.depth_m, depth.depth_m, atol=0.6e-4)  # stored as uint16 of 0.1 mm
    np.testing.assert_array_equal(back.calib.K, calib.K)
    assert (back.calib.width, back.calib.height) == (5, 4)
    np.testing.assert_array_equal(back.labels, labels)


def test_missing_file(tmp_path):
    with pytest.raises(EpisodeFileError, match="no episode file"):
        load_episode(tmp_path / "nothing.npz")


def test_truncated_file(saved, tmp_path):
    _, path = saved
    bad = tmp_path / "trunc.npz"
    bad.write_bytes(path.read_bytes()[: path.stat().st_size // 2])
    with pytest.raises(EpisodeFileError, match="truncated or corrupt"):
        load_episode(bad)


def test_foreign_files(tmp_path):
    text = tmp_path / "notes.npz"
    text.write_text("hello")
    with pytest.raises(EpisodeFileError, match="truncated or corrupt"):
        load_episode(text)
    other = tmp_path / "other.npz"
    np.savez(other, x=np.zeros(3))
    with pytest.raises(EpisodeFileError, match="not an fsv-bench episode"):
        load_episode(other)


def _rewrite_meta(path, dest, **changes):
    with np.load(path) as z:
        arrays = {k: z[k] for k in z.files}
    meta = json.loads(bytes(arrays["meta.json"]).decode())
    meta.update(changes)
    arrays["meta.json"] = np.frombuffer(json.dumps(meta).encode(), np.uint8)
    np.savez_compressed(dest, **arrays)
    return dest


def test_other_version_and_format(saved, tmp_path):
    _, path = saved
    with pytest.raises(EpisodeFileError, match=f"version 99.*reads version 2 or {VERSION}"):
        load_episode(_rewrite_meta(path, tmp_path / "v99.npz", version=99))
    with pytest.raises(EpisodeFileError, match="not an fsv-bench episode"):
        load_episode(_rewrite_meta(path, tmp_path / "fmt.npz", format="something-else"))
    assert FORMAT == "fsv-bench-episode"


def test_inconsistent_content(saved, tmp_path):
    _, path = saved
    with np.load(path) as z:
        arrays = {k: z[k] for k in z.files if k != "truth/box_acc"}
    np.savez_compressed(tmp_path / "part.npz", **arrays)
    with pytest.raises(EpisodeFileError, match="missing or inconsistent"):
        load_episode(tmp_path / "part.npz")


def test_write_is_atomic_and_leaves_no_temporaries(saved, tmp_path):
    ep, _ = saved
    p = save_episode(ep, tmp_path / "a.npz")
    save_episode(ep, p)  # overwrite in place
    assert sorted(x.name for x in tmp_path.iterdir()) == ["a.npz"]
    assert zipfile.is_zipfile(p)


def test_rendered_depth_of_the_default_sensor_round_trips_bit_exactly(rendered_lift_episode, tmp_path):
    """The default sensor quantises to 1 mm, so the file stores whole millimetres exactly."""

    ep = rendered_lift_episode
    arrays = depth_arrays(ep)
    assert arrays["depth_counts"].dtype == np.uint16 and arrays["depth_quantum_m"] == 0.001
    back = load_episode(save_episode(ep, tmp_path / "lift.npz"))
    np.testing.assert_array_equal(back.depth.depth_m, ep.depth.depth_m)
    np.testing.assert_array_equal(back.labels, ep.labels)
    np.testing.assert_array_equal(back.calib.T_world_cam, ep.calib.T_world_cam)
    assert back.depth.fps == ep.depth.fps
    raw = ep.depth.depth_m.nbytes + ep.labels.nbytes
    assert (tmp_path / "lift.npz").stat().st_size < raw / 3  # compact: uint16 + deflate


def test_the_depth_counts_are_deflated_at_the_fast_level(rendered_lift_episode, tmp_path):
    """The largest entry is deflated at FAST_DEFLATE_LEVEL (a third of the default level's time for a
    2 % larger file), the labels at the default level."""
    path = save_episode(rendered_lift_episode, tmp_path / "lift.npz")
    counts = depth_arrays(rendered_lift_episode)["depth_counts"]
    with zipfile.ZipFile(path) as z:
        stored, npy = z.getinfo("render/depth_counts.npy"), z.read("render/depth_counts.npy")
        labels = z.getinfo("render/labels.npy")
        label_npy = z.read("render/labels.npy")
    assert np.array_equal(np.lib.format.read_array(io.BytesIO(npy)), counts)
    fast, default = _deflated_size(npy, FAST_DEFLATE_LEVEL), _deflated_size(npy, 6)
    assert default < 0.99 * fast  # the two levels are told apart by their sizes
    assert stored.compress_size == fast
    assert labels.compress_size == _deflated_size(label_npy, 6)


def _deflated_size(data: bytes, level: int) -> int:
    c = zlib.compressobj(level, zlib.DEFLATED, -15)  # raw deflate, as zip stores it
    return len(c.compress(data) + c.flush())


def test_depth_beyond_uint16_at_0_1_mm_falls_back_to_1_cm(saved, tmp_path):
    depth = np.full((2, 3, 4), 7.3456, dtype=np.float32)  # > 6.5535 m
    calib = Calibration(K=np.eye(3), T_world_cam=np.eye(4), width=4, height=3)
    ep = saved[0].with_depth(DepthVideo(depth_m=depth, fps=30), calib, None)
    back = load_episode(save_episode(ep, tmp_path / "far.npz"))
    np.testing.assert_allclose(back.depth.depth_m, depth, atol=0.005 + 1e-6)
    assert back.labels is None


# --- digests: every array and the JSON are checked on load ---------------------------------------


def _entry_span(path, name):
    """(start, end) of an entry's compressed bytes in the zip file."""
    with zipfile.ZipFile(path) as z:
        info = z.getinfo(name)
    raw = path.read_bytes()
    name_len = int.from_bytes(raw[info.header_offset + 26:info.header_offset + 28], "little")
    extra_len = int.from_bytes(raw[info.header_offset + 28:info.header_offset + 30], "little")
    start = info.header_offset + 30 + name_len + extra_len
    return start, start + info.compress_size


@pytest.mark.parametrize("entry", ["truth/contact_force.npy", "hand/geom_fromto.npy", "meta.json.npy"])
def test_flipped_bytes_name_the_file_and_the_array(saved, tmp_path, entry):
    _, path = saved
    start, end = _entry_span(path, entry)
    data = bytearray(path.read_bytes())
    for i in range((start + end) // 2, (start + end) // 2 + 4):
        data[i] ^= 0xFF
    bad = tmp_path / "flipped.npz"
    bad.write_bytes(bytes(data))
    with pytest.raises(EpisodeFileError) as e:
        load_episode(bad)
    assert str(bad) in str(e.value) and repr(entry[:-len(".npy")]) in str(e.value)


def test_flipped_bytes_in_the_middle_of_the_file_are_refused(saved, tmp_path):
    _, path = saved
    data = bytearray(path.read_bytes())
    mid = len(data) // 2
    data[mid:mid + 4] = bytes(b ^ 0xFF for b in data[mid:mid + 4])
    (tmp_path / "mid.npz").write_bytes(bytes(data))
    with pytest.raises(EpisodeFileError, match=r"mid\.npz is (truncated or corrupt \(entry '\w+/\w+'\)|corrupt: array)"):
        load_episode(tmp_path / "mid.npz")


def _rewrite(path, dest, arrays=None, meta_changes=None):
    """The file's entries, some replaced, written again as a valid zip with the original digests."""
    with np.load(path) as z:
        entries = {k: z[k] for k in z.files}
    entries.update(arrays or {})
    meta = json.loads(bytes(entries["meta.json"]).decode())
    for section, values in (meta_changes or {}).items():
        meta[section].update(values)
    entries["meta.json"] = np.frombuffer(json.dumps(meta).encode(), np.uint8)
    np.savez_compressed(dest, **entries)
    return dest


def test_a_changed_array_in_a_valid_zip_is_refused_by_its_digest(saved, tmp_path):
    _, path = saved
    with np.load(path) as z:
        force = z["truth/contact_force"].copy()
    force[3, 0, 2] = np.nextafter(force[3, 0, 2], np.inf)  # one ulp
    bad = _rewrite(path, tmp_path / "ulp.npz", arrays={"truth/contact_force": force})
    with pytest.raises(EpisodeFileError, match=r"ulp\.npz is corrupt: array 'truth/contact_force' does not match its SHA-256"):
        load_episode(bad)
    bad = _rewrite(path, tmp_path / "int.npz", arrays={"truth/contact_force": force.astype(np.float32)})
    with pytest.raises(EpisodeFileError, match="'truth/contact_force' does not match"):
        load_episode(bad)


def test_a_changed_scalar_in_meta_json_is_refused(saved, tmp_path):
    _, path = saved
    bad = _rewrite(path, tmp_path / "mass.npz", meta_changes={"object": {"mass_kg": 0.31}})
    with pytest.raises(EpisodeFileError, match=r"mass\.npz is corrupt: entry 'meta.json' does not match its SHA-256"):
        load_episode(bad)


def test_an_array_that_meta_json_does_not_list_is_refused(saved, tmp_path):
    _, path = saved
    bad = _rewrite(path, tmp_path / "extra.npz", arrays={"truth/extra": np.zeros(3)})
    with pytest.raises(EpisodeFileError, match="array 'truth/extra' is not listed in meta.json"):
        load_episode(bad)


def test_every_array_has_a_digest_in_meta_json(saved):
    from fsv.digest import array_sha256, tree_sha256

    _, path = saved
    with np.load(path) as z:
        meta = json.loads(bytes(z["meta.json"]).decode())
        assert set(meta["array_sha256"]) == set(z.files) - {"meta.json"}
        assert all(meta["array_sha256"][k] == array_sha256(z[k], k) for k in meta["array_sha256"])
    assert meta["meta_sha256"] == tree_sha256({k: v for k, v in meta.items() if k != "meta_sha256"})


def test_a_version_2_file_still_reads_and_version_3_keeps_the_labels(rendered_lift_episode, tmp_path):
    """Version 2 (before the colour and the annotations) is read; version 3 round-trips the labels."""
    import dataclasses

    from benchmark.archive import write_archive
    from benchmark.camera.episode_file import FORMAT, _sections

    ep = rendered_lift_episode
    back = load_episode(save_episode(ep, tmp_path / "v3.npz"))
    for stream, labels in ep.annotations.streams.items():
        np.testing.assert_array_equal(back.annotations.streams[stream].keypoints_uv, labels.keypoints_uv)
        np.testing.assert_array_equal(back.annotations.streams[stream].keypoint_visibility, labels.keypoint_visibility)
    np.testing.assert_array_equal(back.annotations.keypoints_world, ep.annotations.keypoints_world)
    old = dataclasses.replace(ep, annotations=None)
    sections = _sections(old)
    meta = {"scenario": dataclasses.asdict(old.scenario), "sections": list(sections),
            **{name: scalars for name, (_, scalars) in sections.items()}}
    arrays = {f"{name}/{k}": v for name, (arrs, _) in sections.items() for k, v in arrs.items()}
    v2 = load_episode(write_archive(tmp_path / "v2.npz", FORMAT, 2, meta, arrays))
    assert v2.annotations is None and v2.colour is None and v2.streams == ("depth",)
    np.testing.assert_array_equal(v2.depth.depth_m, ep.depth.depth_m)


def _quantise_numpy(depth):
    """quantise_depth's NumPy path, as it was before its one-pass kernel."""
    from benchmark.camera.episode_file import DEPTH_QUANTA_M
    from benchmark.camera.sensor import dequantise

    for i, q in enumerate(DEPTH_QUANTA_M):
        counts = np.rint(depth.astype(np.float64) / q)
        if counts.max(initial=0) > np.iinfo(np.uint16).max:
            continue
        if i > 0 or np.array_equal(dequantise(counts, q), depth):
            break
    return counts.astype(np.uint16), q


@pytest.mark.filterwarnings("ignore:invalid value encountered in cast")  # NumPy's path on negative, NaN depth
def test_the_one_pass_quantiser_gives_the_numpy_paths_counts(rendered_lift_episode):
    """The renderer's depth goes through one numba pass (0.09 s against 0.32 s for a 10 s lift);
    whatever it does not take (off the 1 mm grid, beyond 65.535 m, negative, NaN) goes the old way."""
    from benchmark.camera.episode_file import quantise_depth

    d = rendered_lift_episode.depth.depth_m
    noisy = d + np.float32(3e-4) * (d > 0)
    cases = {"on the grid": d, "strided": d[:, ::2], "off the grid": noisy, "far": d * np.float32(70),
             "negative": -d, "nan": np.where(d > 0, d, np.float32("nan")), "empty": np.zeros((0, 2), np.float32)}
    quanta = {}
    for name, depth in cases.items():
        counts, q = quantise_depth(depth)
        expected, q_expected = _quantise_numpy(depth)
        assert q == q_expected and counts.dtype == np.uint16 and np.array_equal(counts, expected), name
        quanta[name] = q
    assert quanta["on the grid"] == 0.001 and quanta["off the grid"] == 0.0001 and quanta["far"] == 0.01
