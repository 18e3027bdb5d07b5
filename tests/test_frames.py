import json
import os
import subprocess
import sys

import pandas as pd
import pytest
from frames_data import CALLS, make_tiny, tiny_spec

from benchmark.errors import DatasetError, DatasetFileError
from benchmark.paper.dataset import DatasetSpec
from benchmark.paper.dataset.frames import INDEX_COLUMNS, check_frames, check_training_people, read_index
from benchmark.paper.dataset.shards import read_shard

pytestmark = pytest.mark.xdist_group("frames-data")  # one worker renders frames_data's episodes once


@pytest.fixture(scope="module")
def tiny(tmp_path_factory):
    out = tmp_path_factory.mktemp("frames")
    spec, index = make_tiny(out)
    return out, spec, index


def test_generate_writes_one_verified_shard_per_episode_an_index_a_card_and_croissant(tiny):
    out, spec, index = tiny
    assert list(index.columns) == list(INDEX_COLUMNS) and list(index["episode"]) == ["lift-u0-g0-m0-s0", "lift-u0-g0-m0-s1"]
    assert list(index["frames"]) == [31, 31] and set(index["split"]) == {"cohort"} and set(index["status"]) == {"ok"}
    assert set(index["streams"]) == {"depth,colour"}
    for row in index.itertuples():
        data = (out / row.file).read_bytes()
        import hashlib

        assert len(data) == row.bytes and hashlib.sha256(data).hexdigest() == row.sha256
    pd.testing.assert_frame_equal(read_index(out), index)
    s = read_shard(out / index["file"][1])
    assert s["depth/frames"].shape == (31, 240, 320) and s["colour/frames"].shape == (31, 480, 640, 3)
    assert s["privileged"]["person"]["user"] == 0 and "spots" in s["privileged"]["grasp"]
    assert json.loads(s["attrs"]["scenario"])["seed"] == 1
    assert (out / "README.md").exists() and (out / "croissant.json").exists()
    assert check_frames(out).startswith(f"{out}: ok: frames dataset, 2 shards (2 ok), 62 frames")


def test_resume_builds_nothing_twice_and_rebuilds_a_damaged_shard(tiny, tmp_path, capsys):
    out, spec, index = tiny
    import shutil

    copy = tmp_path / "copy"
    shutil.copytree(out, copy)
    CALLS.clear()
    again = make_tiny(copy)[1]
    assert CALLS == [] and again.equals(index)
    shard = copy / index["file"][0]
    data = bytearray(shard.read_bytes())
    data[len(data) // 3] ^= 0x10
    shard.write_bytes(bytes(data))
    with pytest.raises(DatasetFileError, match="lift-u0-g0-m0-s0.h5"):
        check_frames(copy)
    rebuilt = make_tiny(copy)[1]
    assert CALLS == [(0, ("depth", "colour"))] and "rebuilding it" in capsys.readouterr().err
    assert rebuilt.equals(index)  # the same bytes again
    with pytest.raises(DatasetError, match="another spec"):
        make_tiny(copy, seeds=(0,))


@pytest.mark.parametrize("kw, needle", [(dict(users=(100,)), "user 100 is in the dev split"),
                                        (dict(users=(0,), grasps=(500,)), "grasp 500 is in the test split"),
                                        (dict(views=(0, 499)), "view 499 is in the dev split")])
def test_a_dev_or_test_person_grasp_or_view_is_refused(kw, needle):
    with pytest.raises(DatasetError, match=needle):
        check_training_people(_unchecked(**kw))
    check_training_people(DatasetSpec(users=(0, 4), grasps=(0, 3)))  # the named cohort trains


def _unchecked(**kw):
    """A spec whose grid is not validated against the world (a drawn person or grasp would be planned)."""
    spec = DatasetSpec(tasks=("lift",))
    for key, value in kw.items():
        object.__setattr__(spec, key, value)
    return spec


def test_the_command_refuses_the_dev_split_and_writes_nothing(tmp_path):
    out = tmp_path / "d"
    r = subprocess.run([sys.executable, "-m", "benchmark.commands.entry", "generate", "--frames", "--out", str(out),
                        "--split", "dev", "--users", "3", "--duration", "1"], capture_output=True, text=True,
                       env={**os.environ, "PYTHONPATH": os.getcwd()})
    assert r.returncode == 2 and "user 103 is in the dev split" in r.stderr and not out.exists()


def test_colour_needs_frames_and_a_known_encoding(tmp_path):
    from benchmark.paper.dataset.frames import FramesSpec

    with pytest.raises(DatasetError, match="accepted: raw, jpeg"):
        tiny_spec(encoding="webp")
    with pytest.raises(DatasetError, match="stream 'infrared'"):
        FramesSpec(grid=DatasetSpec(), streams=("depth", "infrared"))
    assert FramesSpec(grid=DatasetSpec(), streams=("colour",)).streams == ("depth", "colour")
