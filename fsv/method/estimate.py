"""What a method estimated from one depth video: :class:`Estimate`."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from fsv.forces import ForceSolution
from fsv.types import Contacts, Kinematics, Poses


@dataclass(frozen=True)
class TrackOutput:
    """The least a tracker returns (the reference tracker's ``fsv.track.Tracking`` carries more).

    Attributes:
        box: Box poses, T frames.
        contacts: Finger contacts detected from the tracked hand (object frame).
        fingertips: Fingertip pad centres in the world, shape (T, K, 3), [m], or None.
        timing_s: Seconds spent per part of the tracker (any keys).
    """

    box: Poses
    contacts: Contacts
    fingertips: np.ndarray | None = None
    timing_s: dict = field(default_factory=dict)


@dataclass(frozen=True)
class Estimate:
    """What the method estimated from one depth video.

    Attributes:
        tracking: The tracker's output: at least ``box`` (:class:`fsv.Poses`) and ``contacts``
            (:class:`fsv.Contacts`); the reference tracker returns an ``fsv.track.Tracking``.
        contacts: The contacts the force stages used (the tracked ones unless an oracle replaced them).
        kinematics: The box kinematics the force stages used.
        nominal: The nominal forces (eq. 4-6), or None when no force stage ran.
        forces: The method's final forces (the reference: eq. 14 with learned internal forces; a
            force stage declared ``final``, such as :class:`fsv.method.direct.DirectForces`: its
            own output, the same object as ``nominal``), or None without either.
        internal_pred: The internal normal forces fed to the final forces, shape (T, K), [N], or None.
        oracle: Names of the stages replaced by truth ("contacts", "kinematics"); empty for a method
            proper.
        timing_s: Seconds spent per stage: ``track`` (with ``track_<part>`` for the tracker's parts),
            ``kinematics``, ``forces``, ``learn``, ``total``.
        labels: The name of each stage that produced this estimate (``tracker``, ``differentiator``,
            ``forces``, ``internal``); "oracle" for a stage replaced by truth.
        learned_model: The ``fsv.learn.InternalForceModel`` the internal-force stage used when it is
            :class:`fsv.method.LearnedInternalForces`; None for any other internal-force stage or none.
    """

    tracking: object
    contacts: Contacts
    kinematics: Kinematics
    nominal: ForceSolution | None
    forces: ForceSolution | None
    internal_pred: np.ndarray | None
    oracle: tuple
    timing_s: dict
    labels: dict = field(default_factory=dict)
    learned_model: object = None

    @property
    def box(self) -> Poses:
        """The tracked box poses."""
        return self.tracking.box

    @property
    def fingertips(self) -> np.ndarray | None:
        """The tracked fingertip pad centres, shape (T, K, 3), [m], or None if the tracker has none."""
        return getattr(self.tracking, "fingertips", None)
