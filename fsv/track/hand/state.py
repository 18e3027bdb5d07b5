"""The hand's state in one frame (:class:`HandState`) and one fit's outcome (:class:`HandFit`)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fsv.errors import InputError
from fsv.rotation import project_to_so3


@dataclass(frozen=True)
class HandState:
    """One hand configuration.

    Attributes:
        palm_pos: Palm origin in the world, shape (3,), [m].
        palm_rot: world_R_palm, shape (3, 3).
        joints: Hinge angles in ``HandModel.joint_names`` order, shape (n,), [rad].
    """

    palm_pos: np.ndarray
    palm_rot: np.ndarray
    joints: np.ndarray

    def __post_init__(self):
        pos = np.asarray(self.palm_pos, dtype=float)
        rot = np.asarray(self.palm_rot, dtype=float)
        q = np.asarray(self.joints, dtype=float)
        if pos.shape != (3,) or not np.all(np.isfinite(pos)):
            raise InputError(f"HandState.palm_pos must be a finite (3,) position, got {pos!r}")
        if rot.shape != (3, 3) or not np.allclose(rot.T @ rot, np.eye(3), atol=1e-4):
            raise InputError("HandState.palm_rot must be a (3, 3) rotation matrix")
        if q.ndim != 1 or not np.all(np.isfinite(q)):
            raise InputError(f"HandState.joints must be a finite (n,) vector, got shape {q.shape}")
        object.__setattr__(self, "palm_pos", pos)
        object.__setattr__(self, "palm_rot", project_to_so3(rot))
        object.__setattr__(self, "joints", q)

    @classmethod
    def _from_fit(cls, palm_pos: np.ndarray, palm_rot: np.ndarray, joints: np.ndarray) -> "HandState":
        """A state the tracker computed (finite arrays of the right shapes; ``palm_rot`` is
        re-orthonormalised), without the checks of user input."""
        return cls._fitted(palm_pos, project_to_so3(palm_rot), joints)

    @classmethod
    def _fitted(cls, palm_pos: np.ndarray, palm_rot: np.ndarray, joints: np.ndarray) -> "HandState":
        """:meth:`_from_fit` of a rotation already projected onto SO(3) (by the compiled fit,
        :mod:`fsv.track.hand.lm`): not projected a second time."""
        st = object.__new__(cls)
        object.__setattr__(st, "palm_pos", palm_pos)
        object.__setattr__(st, "palm_rot", palm_rot)
        object.__setattr__(st, "joints", joints)
        return st


@dataclass(frozen=True)
class HandFit:
    """The hand in one frame.

    Attributes:
        state: The fitted configuration.
        fingertips: Fingertip pad centres in the world, thumb first, shape (K, 3), [m].
        observed: Whether each finger's distal segments were seen in this frame, shape (K,).
        explained: Fraction of hand candidate points within 2 sigma of the fitted surface.
        reinitialised: Whether the particle search re-initialised the fit.
    """

    state: HandState
    fingertips: np.ndarray
    observed: np.ndarray
    explained: float
    reinitialised: bool = False
