"""The method's world frame and the true one: a lab's world frame is its calibration.

A method told the camera's pose with an error (``--knowledge lab``) reports the box in its own
world frame, which differs from the true world by the calibration's error. Before the box pose and
the net force are compared with the truth, the estimate is carried into the true world through the
camera (``world_from_method = T_world_cam_true @ inv(T_world_cam_given)``): what is scored is the
tracking and the forces themselves, while what the calibration's error does to the method's
inferences (the direction of gravity it assumes, its back-projection) stays in the estimate. The
kinematics are scored in the box's own frame (the AHRS's), where no world frame enters.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fsv.linalg import rows_mt
from fsv.types import Poses


@dataclass(frozen=True)
class TrackingInWorld:
    """A tracker's output carried into the true world: ``box`` and ``fingertips`` mapped, ``contacts``
    (object frame) as they were."""

    box: Poses
    contacts: object
    fingertips: np.ndarray | None = None


def is_identity(world_from_method) -> bool:
    """True when there is nothing to map (None or the identity)."""
    return world_from_method is None or np.array_equal(np.asarray(world_from_method), np.eye(4))


def tracking_in_true_world(tracking, world_from_method):
    """``tracking`` with its box poses and fingertips in the true world (``tracking`` itself when
    ``world_from_method`` is None or the identity).

    Args:
        tracking: A tracker's output (``box``: :class:`fsv.Poses`, ``contacts``, optional ``fingertips`` (T, K, 3)).
        world_from_method: (4, 4), see the module docstring.
    """
    if is_identity(world_from_method):
        return tracking
    M = np.asarray(world_from_method, dtype=float)
    R, t = M[:3, :3], M[:3, 3]
    box = tracking.box
    mapped = Poses(t=box.t, pos=rows_mt(box.pos, R) + t, rot=np.einsum("ij,tjk->tik", R, box.rot))
    tips = getattr(tracking, "fingertips", None)
    return TrackingInWorld(box=mapped, contacts=tracking.contacts,
                           fingertips=None if tips is None else np.einsum("ij,tkj->tki", R, np.asarray(tips)) + t)


def rot_in_true_world(rot, world_from_method) -> np.ndarray:
    """Orientations (T, 3, 3) of the method's world expressed in the true world (``rot`` itself for
    the identity)."""
    if is_identity(world_from_method):
        return rot
    R = np.asarray(world_from_method, dtype=float)[:3, :3]
    return np.einsum("ij,tjk->tik", R, np.asarray(rot, dtype=float))
