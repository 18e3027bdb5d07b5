"""What a force-sensing-from-vision method is given: :class:`CameraInput`."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from fsv.errors import InputError
from fsv.grip import GripCalibration
from fsv.models import HandModel, ObjectModel
from fsv.track.tracker import TrackInit
from fsv.types import Calibration, ColourVideo, DepthVideo

GRAVITY = np.array([0.0, 0.0, -9.81])
"""Gravity in the world frame, [m/s^2] (z up, table top at z = 0)."""


@dataclass(frozen=True)
class CameraInput:
    """Everything a method sees of one episode: what a real camera set-up provides.

    Attributes:
        depth: The depth video, T frames.
        calib: Camera calibration (intrinsics; camera pose in the world, table top at z = 0).
        object_model: The known box (size, mass, inertia, friction).
        hand_model: The known hand (segments, joints, capsules, fingertips).
        init: A coarse first-frame initialisation of the box and the hand.
        gravity: Gravity in the world, shape (3,), [m/s^2].
        grip: The person's grip, measured once in a calibration recording with force sensors
            (:class:`fsv.grip.GripCalibration`); None if there was none. Nothing of the episode
            itself: a method may use it, as the reference's internal-force stage does, or not.
        colour: The colour camera's stream (its own calibration and timestamps), or None when the
            colour was not recorded: the benchmark renders it only for a method that declares it
            reads it (``streams``, :func:`fsv.method.method_streams`) or when ``--streams`` asks.
    """

    depth: DepthVideo
    calib: Calibration
    object_model: ObjectModel
    hand_model: HandModel
    init: TrackInit
    gravity: np.ndarray = field(default_factory=GRAVITY.copy)
    grip: GripCalibration | None = None
    colour: ColourVideo | None = None

    def __post_init__(self):
        for name, kind in (("depth", DepthVideo), ("calib", Calibration), ("object_model", ObjectModel),
                           ("hand_model", HandModel), ("init", TrackInit)):
            if not isinstance(getattr(self, name), kind):
                raise InputError(f"CameraInput.{name} must be an {kind.__module__}.{kind.__name__}, "
                                 f"got {type(getattr(self, name)).__name__}")
        if self.grip is not None and not isinstance(self.grip, GripCalibration):
            raise InputError(f"CameraInput.grip must be None or an fsv.grip.GripCalibration, got {type(self.grip).__name__}")
        if self.colour is not None:
            if not isinstance(self.colour, ColourVideo):
                raise InputError(f"CameraInput.colour must be None or an fsv.types.ColourVideo, got {type(self.colour).__name__}")
            if self.colour.num_frames != self.depth.num_frames:
                raise InputError(f"CameraInput.colour has {self.colour.num_frames} frames, the depth {self.depth.num_frames}")
        g = np.asarray(self.gravity, dtype=float)
        if g.shape != (3,) or not np.all(np.isfinite(g)):
            raise InputError(f"CameraInput.gravity must be a finite (3,) vector in m/s^2, got {self.gravity!r}")
        object.__setattr__(self, "gravity", g)
        if self.init.joints.shape != (self.hand_model.num_joints,):
            raise InputError(f"CameraInput.init.joints must have the hand's {self.hand_model.num_joints} angles, "
                             f"got {self.init.joints.shape}")

    @property
    def num_frames(self) -> int:
        return self.depth.num_frames

    @property
    def streams(self) -> tuple:
        """The names of the streams present (:data:`fsv.types.STREAMS` order)."""
        return ("depth",) + (("colour",) if self.colour is not None else ())
