"""An episode: one scenario, its truth, and (after rendering) its depth video and calibration."""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from benchmark.errors import EpisodeFileError
from benchmark.scenario import Scenario
from benchmark.truth import Truth
from fsv import Calibration, DepthVideo, HandModel, ObjectModel


@dataclass(frozen=True)
class Episode:
    """One simulated (and possibly rendered) scenario.

    Attributes:
        scenario: What was simulated.
        truth: Ground truth at frame times.
        object_model: The known object model handed to the method.
        hand_model: The known hand model handed to the method.
        depth: Depth video, or None before rendering.
        calib: Camera calibration, or None before rendering.
        labels: Truth-side label image per frame, (T, H, W) uint8 (0 none, 1 table, 2 box,
            10 + k finger k's segments, 9 palm), or None; never handed to `fsv`.
    """

    scenario: Scenario
    truth: Truth
    object_model: ObjectModel
    hand_model: HandModel
    depth: DepthVideo | None = None
    calib: Calibration | None = None
    labels: np.ndarray | None = None

    def with_depth(self, depth: DepthVideo, calib: Calibration, labels: np.ndarray | None) -> "Episode":
        return replace(self, depth=depth, calib=calib, labels=labels)


# --- Rendered part of an episode in the episode file (depth, calibration, labels) -------------

DEPTH_QUANTA_M = (0.001, 0.0001, 0.01)
"""Depth is stored as uint16 multiples of the first of these quanta that represents it: 1 mm when
the depth already lies on the 1 mm grid (the default sensor's quantisation: stored exactly),
otherwise 0.1 mm (up to 6.5 m), otherwise 1 cm."""


def depth_arrays(episode: Episode) -> dict[str, np.ndarray]:
    """The rendered part of an episode as named arrays for the (compressed) episode file.

    Returns:
        {} before rendering; otherwise ``depth_counts`` (T, H, W) uint16 and ``depth_quantum_m``
        (depth = counts * quantum, 0 = no measurement), ``depth_fps``, ``calib_K`` (3, 3),
        ``calib_T_world_cam`` (4, 4), ``calib_size`` (width, height) and, if rendered with
        labels, ``labels`` (T, H, W) uint8.
    """
    if episode.depth is None:
        return {}
    from benchmark.sensor import dequantise

    depth = episode.depth.depth_m
    top = float(depth.max(initial=0.0))
    for i, q in enumerate(DEPTH_QUANTA_M):
        counts = np.rint(depth.astype(np.float64) / q)
        if counts.max(initial=0) > np.iinfo(np.uint16).max:
            continue
        if i > 0 or np.array_equal(dequantise(counts, q), depth):
            break
    else:
        raise EpisodeFileError(f"depth up to {top:.2f} m does not fit uint16 at a quantum of {DEPTH_QUANTA_M[-1]} m")
    out = {
        "depth_counts": counts.astype(np.uint16),
        "depth_quantum_m": np.float64(q),
        "depth_fps": np.float64(episode.depth.fps),
        "calib_K": episode.calib.K,
        "calib_T_world_cam": episode.calib.T_world_cam,
        "calib_size": np.array([episode.calib.width, episode.calib.height], dtype=np.int64),
    }
    if episode.labels is not None:
        out["labels"] = np.asarray(episode.labels, dtype=np.uint8)
    return out


def depth_from_arrays(arrays) -> tuple[DepthVideo | None, Calibration | None, np.ndarray | None]:
    """Inverse of :func:`depth_arrays`: ``(depth, calib, labels)``, all None if not rendered.

    Depth comes back within half a quantum of what was stored (exactly for 1 mm data).
    """
    if "depth_counts" not in arrays:
        return None, None, None
    from benchmark.sensor import dequantise

    depth = DepthVideo(
        depth_m=dequantise(arrays["depth_counts"], float(arrays["depth_quantum_m"])), fps=float(arrays["depth_fps"])
    )
    width, height = (int(v) for v in arrays["calib_size"])
    calib = Calibration(K=arrays["calib_K"], T_world_cam=arrays["calib_T_world_cam"], width=width, height=height)
    labels = np.asarray(arrays["labels"], dtype=np.uint8) if "labels" in arrays else None
    return depth, calib, labels
