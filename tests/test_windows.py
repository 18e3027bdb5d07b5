import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from frames_data import make_tiny

from benchmark.errors import DatasetError
from benchmark.paper.dataset.shards import read_shard

pytestmark = pytest.mark.xdist_group("frames-data")  # one worker renders frames_data's episodes once

DOCS = Path(__file__).resolve().parents[1] / "docs" / "data.md"


@pytest.fixture(scope="module")
def torch():
    """PyTorch, imported by the tests that use it: at this module's top (itself or through
    :mod:`benchmark.paper.dataset.windows`) it cost every xdist worker's collection 1.3 s of the
    suite's 3.5 s, though one worker runs these tests."""
    import torch  # lazy: torch (1.3 s) off the collection

    return torch


@pytest.fixture(scope="module")
def windows(torch):
    """:mod:`benchmark.paper.dataset.windows` (it imports torch)."""
    from benchmark.paper.dataset import windows  # lazy: torch (1.3 s) off the collection

    return windows


@pytest.fixture(scope="module")
def tiny(tmp_path_factory):
    out = tmp_path_factory.mktemp("frames")
    make_tiny(out)
    return out


def test_windows_cover_each_shard_and_read_the_shards_values(tiny, torch, windows):
    data = windows.FrameWindows(tiny, window=8, stride=4, streams=("depth", "colour"))
    assert len(data) == 2 * 6 and data.items[:3] == [(0, 0), (0, 4), (0, 8)] and data.num_fingers == 5  # 31 frames
    item = data[8]  # the second shard's window starting at frame 8
    assert item["episode"] == "lift-u0-g0-m0-s1" and item["start"] == 8
    s = read_shard(tiny / "episodes" / "lift-u0-g0-m0-s1.h5")
    assert torch.equal(item["depth"], torch.from_numpy(s["depth/frames"][8:16]))
    assert torch.equal(item["colour"], torch.from_numpy(s["colour/frames"][8:16]).permute(0, 3, 1, 2))
    assert np.array_equal(item["force"].numpy(), s["depth/contact_force_cam"][8:16].astype(np.float32))
    assert torch.equal(item["active"], torch.from_numpy(s["labels/contact_active"][8:16]))
    world = windows.FrameWindows(tiny, window=8, stride=4, force_frame="world")[8]
    assert np.array_equal(world["force"].numpy(), s["labels/contact_force_world"][8:16].astype(np.float32))
    assert "colour" not in world and float(item["force"].abs().max()) > 1.0


def test_collate_stacks_windows_into_a_batch(tiny, torch, windows):
    data = windows.FrameWindows(tiny, window=4, streams=("depth", "colour"))
    loader = torch.utils.data.DataLoader(data, batch_size=3, collate_fn=windows.collate_windows)
    batch = next(iter(loader))
    assert batch["depth"].shape == (3, 4, 240, 320) and batch["depth"].dtype == torch.float32
    assert batch["colour"].shape == (3, 4, 3, 480, 640) and batch["colour"].dtype == torch.uint8
    assert batch["force"].shape == (3, 4, 5, 3) and batch["active"].shape == (3, 4, 5)
    assert batch["keypoints_uv"].shape == (3, 4, 21, 2) and batch["depth_labels"].shape == (3, 4, 240, 320)
    assert batch["episode"] == ["lift-u0-g0-m0-s0"] * 3 and batch["start"] == [0, 4, 8]
    with pytest.raises(DatasetError, match="window must be"):
        windows.FrameWindows(tiny, window=0)
    with pytest.raises(DatasetError, match="force_frame 'hand'"):
        windows.FrameWindows(tiny, force_frame="hand")


def test_the_docs_training_loop_runs_as_written(tiny, tmp_path):
    blocks = re.findall(r"```python\n(.*?)```", DOCS.read_text(), re.S)
    loop = [b for b in blocks if "FrameWindows(" in b and "loss.backward()" in b]
    assert len(loop) == 1 and len(loop[0].strip().splitlines()) <= 26
    (tmp_path / "data").mkdir()
    (tmp_path / "data" / "frames").symlink_to(tiny)
    script = tmp_path / "loop.py"
    script.write_text(loop[0])
    r = subprocess.run([sys.executable, str(script)], cwd=tmp_path, capture_output=True, text=True, timeout=300,
                       env={"PYTHONPATH": str(Path(__file__).resolve().parents[1]), "PATH": "/usr/bin:/bin"})
    assert r.returncode == 0, r.stderr
    assert re.fullmatch(r"14 windows, last batch: mean squared force error \d+\.\d\d N\^2\n", r.stdout)
