import hashlib
import time

import numpy as np
import pytest
from frames_data import cached_episode

from benchmark.errors import DatasetError, DatasetFileError
from benchmark.paper.dataset.shards import content_sha256, open_shard, read_shard, verify_shard, write_shard
from benchmark.world.scenario import Scenario
from fsv.rotation import quat_to_rot

pytestmark = pytest.mark.xdist_group("frames-data")  # one worker renders frames_data's episodes once


@pytest.fixture(scope="module")
def episode():
    return cached_episode(Scenario(task="lift", duration_s=1.0), ("depth", "colour"))


@pytest.fixture(scope="module")
def shard(episode, tmp_path_factory):
    path = tmp_path_factory.mktemp("shard") / "lift-u0-g0-m0-s0.h5"
    data = write_shard(episode, streams=("depth", "colour"), split="cohort",
                       privileged=dict(person={"name": "u0", "share": [0.3, 0.7]}, grasp={"family": "width-four"}))
    path.write_bytes(data)
    return path, data, time.time()


def test_the_content_digest_written_from_memory_is_the_one_read_back(episode, shard):
    """The writer hashes the frames from the arrays it wrote; read back from the file (what a
    reader's check does), the same digest, for raw and JPEG colour; it differs once one value does."""
    jpeg = write_shard(episode, streams=("depth", "colour"), colour_encoding="jpeg")
    for data in (shard[1], jpeg):
        with open_shard(None, data) as f:
            assert f.attrs["content_sha256"] == content_sha256(f)
            frames = f["depth/frames"][()]
            frames[0, 0, 0] += 1
            assert content_sha256(f, {"/depth/frames": frames}) != content_sha256(f)


def test_a_shard_holds_the_episodes_values_bit_for_bit(episode, shard):
    s = read_shard(shard[0])
    tr, ann = episode.truth, episode.annotations
    assert s["depth/frames"].dtype == np.float32 and np.array_equal(s["depth/frames"], episode.depth.depth_m)
    assert np.array_equal(s["depth/labels"], episode.labels) and np.array_equal(s["colour/labels"], episode.colour_labels)
    assert np.array_equal(s["colour/frames"], episode.colour.rgb)
    assert np.array_equal(s["labels/contact_force_object"], tr.contact_force)
    assert np.array_equal(s["labels/hand_qpos"], tr.hand_qpos) and np.array_equal(s["labels/box_acc"], tr.box_acc)
    assert np.array_equal(s["labels/contact_active"], tr.contact_active)
    assert np.array_equal(s["labels/keypoints_world"], ann.keypoints_world)
    for stream in ("depth", "colour"):
        assert np.array_equal(s[f"{stream}/contact_force_cam"], ann.streams[stream].contact_force_cam)
        assert np.array_equal(s[f"{stream}/keypoints_uv"], ann.streams[stream].keypoints_uv, equal_nan=True)
    assert np.array_equal(s["depth/K"], episode.calib.K) and np.array_equal(s["colour/K"], episode.colour.calib.K)
    # the world-frame force is R(q) f_object: checked against fsv's own rotation of the quaternion
    R = np.stack([quat_to_rot(q) for q in tr.box_quat])
    expect = np.einsum("tij,tkj->tki", R, tr.contact_force)
    assert np.abs(s["labels/contact_force_world"] - expect).max() < 1e-9 * max(1.0, np.abs(expect).max())
    assert np.abs(tr.contact_force).max() > 1.0  # the fingers do push: the check above is not of zeros
    assert s["privileged"] == {"person": {"name": "u0", "share": [0.3, 0.7]}, "grasp": {"family": "width-four"}}
    assert s["attrs"]["split"] == "cohort" and s["depth/frames"].shape == (31, 240, 320)


def test_the_depth_is_stored_as_lossless_millimetres_and_the_bytes_do_not_depend_on_the_time(episode, shard):
    import h5py

    with h5py.File(shard[0]) as f:
        assert f["depth/frames"].dtype == np.uint16 and f["depth/frames"].attrs["encoding"] == "uint16-mm"
        assert f["depth/frames"].chunks == (1, 240, 320) and f["depth/frames"].compression == "gzip"
    while int(time.time()) <= int(shard[2]):  # HDF5 keeps whole seconds: write again in a later second
        time.sleep(0.05)
    again = write_shard(episode, streams=("depth", "colour"), split="cohort",
                        privileged=dict(person={"name": "u0", "share": [0.3, 0.7]}, grasp={"family": "width-four"}))
    assert hashlib.sha256(again).hexdigest() == hashlib.sha256(shard[1]).hexdigest()


def test_jpeg_colour_is_much_smaller_and_close(episode):
    raw = write_shard(episode, streams=("depth", "colour"))
    jpeg = write_shard(episode, streams=("depth", "colour"), colour_encoding="jpeg")
    depth_only = len(write_shard(episode))
    assert (len(raw) - depth_only) > 8 * (len(jpeg) - depth_only)
    import io

    import h5py

    from benchmark.paper.dataset.shards import decode_colour

    with h5py.File(io.BytesIO(jpeg)) as f:
        rgb = decode_colour(f["colour/frames"])
    err = np.abs(rgb.astype(int) - episode.colour.rgb.astype(int))
    assert rgb.shape == episode.colour.rgb.shape and 0 < err.mean() < 4.0
    with pytest.raises(DatasetError, match="png"):
        write_shard(episode, streams=("depth", "colour"), colour_encoding="png")


def test_a_flipped_byte_is_refused_naming_the_file(shard, tmp_path):
    path, data, _ = shard
    assert verify_shard(path)["episode"] == "lift-u0-g0-m0-s0"
    bad = bytearray(data)
    bad[len(bad) // 2] ^= 0xFF  # inside the colour frames' chunks
    (tmp_path / path.name).write_bytes(bytes(bad))
    with pytest.raises(DatasetFileError, match="lift-u0-g0-m0-s0.h5"):
        verify_shard(tmp_path / path.name)
    with pytest.raises(DatasetFileError, match="SHA-256 in the index"):
        verify_shard(tmp_path / path.name, sha256=hashlib.sha256(data).hexdigest()[::-1])
    (tmp_path / "other.h5").write_bytes(data)
    with pytest.raises(DatasetFileError, match="renamed or copied"):
        verify_shard(tmp_path / "other.h5")
