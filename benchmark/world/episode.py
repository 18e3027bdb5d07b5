"""An episode: one scenario, its truth, and (after rendering) its depth video and calibration.

The record only; its file (the depth codec and the episode archive) is ``benchmark.camera.episode_file``.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from benchmark.world.scenario import Scenario
from benchmark.world.truth import Truth
from fsv import Calibration, ColourVideo, DepthVideo, HandModel, ObjectModel


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
        colour: The colour stream (its own calibration and timestamps), or None when it was not
            rendered (only a method or ``--streams`` that asks for it renders it).
        colour_labels: The colour camera's label images (T, H, W) uint8, as ``labels``, or None.
        annotations: The per-frame labels of learned methods (keypoints, box pose in BOP's
            convention, contacts in each stream's camera frame:
            :class:`benchmark.camera.annotations.Annotations`), or None; never handed to `fsv`.
    """

    scenario: Scenario
    truth: Truth
    object_model: ObjectModel
    hand_model: HandModel
    depth: DepthVideo | None = None
    calib: Calibration | None = None
    labels: np.ndarray | None = None
    colour: ColourVideo | None = None
    colour_labels: np.ndarray | None = None
    annotations: object = None

    @property
    def streams(self) -> tuple:
        """The names of the rendered streams (:data:`fsv.types.STREAMS` order)."""
        return (("depth",) if self.depth is not None else ()) + (("colour",) if self.colour is not None else ())

    def with_depth(self, depth: DepthVideo, calib: Calibration, labels: np.ndarray | None) -> "Episode":
        return replace(self, depth=depth, calib=calib, labels=labels)

    def with_colour(self, colour: ColourVideo, labels: np.ndarray) -> "Episode":
        return replace(self, colour=colour, colour_labels=labels)

    def with_annotations(self, annotations) -> "Episode":
        return replace(self, annotations=annotations)
