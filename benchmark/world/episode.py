"""An episode: one scenario, its truth, and (after rendering) its depth video and calibration.

The record only; its file (the depth codec and the episode archive) is ``benchmark.camera.episode_file``.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from benchmark.world.scenario import Scenario
from benchmark.world.truth import Truth
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
