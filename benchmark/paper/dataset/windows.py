"""A PyTorch ``Dataset`` of a frames dataset: windows of W consecutive frames, read lazily from the shards.

:class:`FrameWindows` lists every window ``(shard, start)`` of the index's good shards (starts
``0, stride, 2 stride, ...`` while a whole window fits) and reads one window per item: only its
frames' chunks are decompressed. Each process opens a shard once (h5py handles are not shared
across the DataLoader's worker processes: they are opened on first use in each). Imports torch, so
the command line never imports this module.

An item is a dict of tensors (W frames, K fingers, H x W pixels per stream)::

    depth            (W, H, W) float32 [m] (0: no measurement)
    depth_labels     (W, H, W) uint8 label images (0 none, 1 table, 2 box, 9 palm, 10 + k finger k)
    colour           (W, 3, H, W) uint8 sRGB, if the dataset has colour and ``streams`` asks for it
    colour_labels    (W, H, W) uint8
    force            (W, K, 3) float32 [N]: each finger's force on the box in ``force_frame``
                     ("camera": the depth camera's, "world" or "object")
    active           (W, K) bool: finger k touches the box
    keypoints_uv     (W, 21, 2) float32 [px] in the depth image; keypoint_visibility (W, 21) uint8
    box_pos (W, 3) [m], box_rot (W, 3, 3), box_vel (W, 3), box_acc (W, 3), hand_qpos (W, n) float32
    t                (W,) float64 [s]

and ``episode`` (str) and ``start`` (int). :func:`collate_windows` stacks a list of items into a
batch (tensors gain a leading batch axis; ``episode`` and ``start`` become lists).
"""

from __future__ import annotations

import json
import os

import h5py
import numpy as np
import torch

from benchmark.errors import DatasetError
from benchmark.paper.dataset.frames import read_index
from benchmark.paper.dataset.shards import decode_colour, decode_depth

FORCE_FRAMES = {"camera": "depth/contact_force_cam", "world": "labels/contact_force_world",
                "object": "labels/contact_force_object"}
"""Where each frame's forces are in a shard."""
_LABELS = {"box_pos": "labels/box_pos", "box_rot": "labels/box_rot", "box_vel": "labels/box_vel",
           "box_acc": "labels/box_acc", "hand_qpos": "labels/hand_qpos", "keypoints_uv": "depth/keypoints_uv"}


class FrameWindows(torch.utils.data.Dataset):
    """Windows of ``window`` consecutive frames of a frames dataset (``fsv-bench generate --frames``).

    Args:
        root: The dataset folder (with ``index.parquet``).
        window: W, frames per item (>= 1).
        stride: Frames between the starts of consecutive windows of a shard (default ``window``:
            windows that do not overlap).
        streams: The streams to read ("depth" and, if the dataset has it, "colour").
        force_frame: The frame of ``force``: "camera" (the depth camera's), "world" or "object".
        episodes: Only these episodes (names of the index's ``episode`` column); default all.
    """

    def __init__(self, root, window: int = 8, stride: int | None = None, streams: tuple = ("depth",),
                 force_frame: str = "camera", episodes=None):
        if isinstance(window, bool) or int(window) != window or window < 1:
            raise DatasetError(f"window must be an integer >= 1, got {window!r}")
        stride = int(window) if stride is None else stride
        if isinstance(stride, bool) or int(stride) != stride or stride < 1:
            raise DatasetError(f"stride must be an integer >= 1, got {stride!r}")
        if force_frame not in FORCE_FRAMES:
            raise DatasetError(f"force_frame {force_frame!r}: accepted: {', '.join(FORCE_FRAMES)}")
        self.root, self.window, self.stride = os.fspath(root), int(window), int(stride)
        self.streams, self.force_frame = tuple(streams), force_frame
        index = read_index(self.root)
        index = index[index["status"] == "ok"]
        if episodes is not None:
            index = index[index["episode"].isin(list(episodes))]
        for s in self.streams:
            lacking = index[~index["streams"].str.split(",").apply(lambda names: s in names)]
            if s not in ("depth", "colour") or len(lacking):
                raise DatasetError(f"stream {s!r} is not in every shard of {self.root} (e.g. "
                                   f"{lacking['episode'].iloc[0] if len(lacking) else s}); accepted: depth, colour")
        self.index = index.reset_index(drop=True)
        self.items = [(i, start) for i, n in enumerate(self.index["frames"])
                      for start in range(0, int(n) - self.window + 1, self.stride)]
        self._files: dict = {}
        self.num_fingers = len(json.loads(self._file(0).attrs["finger_names"])) if len(self.index) else 0
        """K, the finger slots of the shards (thumb first)."""

    def __len__(self) -> int:
        return len(self.items)

    def _file(self, i: int):
        f = self._files.get(i)
        if f is None:
            f = self._files[i] = h5py.File(os.path.join(self.root, self.index["file"].iloc[i]), "r")
        return f

    def __getstate__(self):  # to a DataLoader worker: without open files
        return {**self.__dict__, "_files": {}}

    def __getitem__(self, item: int) -> dict:
        i, a = self.items[item]
        b = a + self.window
        f = self._file(i)
        d = f["depth/frames"]
        out = {"depth": torch.from_numpy(decode_depth(d[a:b], d.attrs["encoding"])),
               "depth_labels": torch.from_numpy(f["depth/labels"][a:b])}
        if "colour" in self.streams:
            out["colour"] = torch.from_numpy(np.ascontiguousarray(decode_colour(f["colour/frames"], a, b).transpose(0, 3, 1, 2)))
            out["colour_labels"] = torch.from_numpy(f["colour/labels"][a:b])
        out["force"] = torch.from_numpy(f[FORCE_FRAMES[self.force_frame]][a:b].astype(np.float32))
        out["active"] = torch.from_numpy(f["labels/contact_active"][a:b].astype(bool))
        for key, path in _LABELS.items():
            out[key] = torch.from_numpy(f[path][a:b].astype(np.float32))
        out["keypoint_visibility"] = torch.from_numpy(f["depth/keypoint_visibility"][a:b])
        out["t"] = torch.from_numpy(f["labels/t"][a:b])
        out["episode"], out["start"] = str(self.index["episode"].iloc[i]), int(a)
        return out


def collate_windows(items: list) -> dict:
    """A batch of :class:`FrameWindows` items: every tensor stacked on a new leading axis (B, W, ...);
    ``episode`` and ``start`` as lists."""
    if not items:
        raise DatasetError("collate_windows needs at least one item")
    return {key: (torch.stack([it[key] for it in items]) if isinstance(items[0][key], torch.Tensor)
                  else [it[key] for it in items]) for key in items[0]}
