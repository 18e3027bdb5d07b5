"""Forward kinematics of a known hand model (`fsv.HandModel`), vectorised over frames.

The hand's configuration is the vector ``hand_qpos`` of length 7 + n: the palm's position (3, [m])
and orientation quaternion (w, x, y, z) in the world, followed by the n hinge angles ([rad]) in
``HandModel.joint_names`` order (the same layout as the benchmark's ``Truth.hand_qpos``).

Segment b's world pose is its parent's pose composed with its fixed offset and then with its hinge
rotations, all anchored at the segment origin, applied in order about axes of its own frame::

    R_b = R_parent(b) @ R(offset_quat_b) @ Rot(axis_j1, q_j1) @ Rot(axis_j2, q_j2) ...
    p_b = p_parent(b) + R_parent(b) @ offset_pos_b

Every function accepts any number of leading batch axes (e.g. frames) and returns arrays with the
same leading axes.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fsv.errors import InputError
from fsv.linalg import mm, mv
from fsv.models import HandModel
from fsv.rotation import axis_angle_to_rot, quat_to_rot


@dataclass(frozen=True)
class HandPose:
    """World poses of a hand's segments.

    Attributes:
        pos: Segment origins in the world, shape (..., B, 3), [m].
        rot: Segment orientations world_R_segment, shape (..., B, 3, 3).
    """

    pos: np.ndarray
    rot: np.ndarray

    def __post_init__(self):
        if self.pos.shape[-1] != 3 or self.rot.shape[-2:] != (3, 3) or self.pos.shape[:-1] != self.rot.shape[:-2]:
            raise InputError(f"HandPose: pos (..., B, 3) and rot (..., B, 3, 3) disagree: {self.pos.shape}, {self.rot.shape}")

    def to_world(self, segment: np.ndarray, points: np.ndarray) -> np.ndarray:
        """Maps points given in segment frames to the world.

        Args:
            segment: Segment index per point, shape (P,).
            points: Points in their segments' frames, shape (P, 3), [m].

        Returns:
            World points, shape (..., P, 3), [m].
        """
        segment = np.asarray(segment, dtype=np.int64)
        R = self.rot[..., segment, :, :]
        return self.pos[..., segment, :] + np.einsum("...pij,pj->...pi", R, np.asarray(points, dtype=float))


def finger_of_segment(model: HandModel) -> np.ndarray:
    """The finger each segment belongs to (its index in ``finger_names``, thumb first), -1 for the palm, (B,)."""
    finger = np.full(len(model.segment_names), -1, dtype=np.int64)
    for k, tip in enumerate(model.fingertip_segment):
        b = int(tip)
        while b > 0:
            finger[b] = k
            b = int(model.parent[b])
    return finger


def split_qpos(model: HandModel, hand_qpos: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Splits hand configurations into palm position, palm rotation and joint angles.

    Args:
        model: The hand model (fixes n).
        hand_qpos: Configurations, shape (..., 7 + n).

    Returns:
        ``(palm_pos (..., 3), palm_rot (..., 3, 3), joints (..., n))``.

    Raises:
        InputError: If the last axis is not 7 + n long.
    """
    hand_qpos = np.asarray(hand_qpos, dtype=float)
    n = model.num_joints
    if hand_qpos.shape[-1] != 7 + n:
        raise InputError(f"hand_qpos must have 7 + {n} = {7 + n} entries on its last axis, got {hand_qpos.shape}")
    return hand_qpos[..., :3], quat_to_rot(hand_qpos[..., 3:7]), hand_qpos[..., 7:]


def forward_kinematics(model: HandModel, palm_pos: np.ndarray, palm_rot: np.ndarray, joints: np.ndarray) -> HandPose:
    """World poses of all segments.

    Args:
        model: The hand model.
        palm_pos: Palm origin in the world, shape (..., 3), [m].
        palm_rot: Palm orientation world_R_palm, shape (..., 3, 3).
        joints: Hinge angles in ``model.joint_names`` order, shape (..., n), [rad].

    Returns:
        The segment poses, with leading axes broadcast from the inputs.
    """
    palm_pos = np.asarray(palm_pos, dtype=float)
    palm_rot = np.asarray(palm_rot, dtype=float)
    joints = np.asarray(joints, dtype=float)
    if joints.shape[-1] != model.num_joints or palm_pos.shape[-1] != 3 or palm_rot.shape[-2:] != (3, 3):
        raise InputError(f"forward_kinematics wants palm_pos (...,3), palm_rot (...,3,3), joints (...,{model.num_joints}); "
                         f"got {palm_pos.shape}, {palm_rot.shape}, {joints.shape}")
    lead = np.broadcast_shapes(palm_pos.shape[:-1], palm_rot.shape[:-2], joints.shape[:-1])
    hinge = axis_angle_to_rot(model.joint_axis, joints)  # (..., n, 3, 3)
    offset_rot = quat_to_rot(model.offset_quat)
    B = len(model.segment_names)
    pos = np.empty(lead + (B, 3))
    rot = np.empty(lead + (B, 3, 3))
    pos[..., 0, :] = palm_pos
    rot[..., 0, :, :] = palm_rot
    for b in range(B):
        if b > 0:
            p = model.parent[b]
            pos[..., b, :] = pos[..., p, :] + mv(rot[..., p, :, :], model.offset_pos[b])
            rot[..., b, :, :] = mm(rot[..., p, :, :], offset_rot[b])
        for j in np.flatnonzero(model.joint_segment == b):
            rot[..., b, :, :] = mm(rot[..., b, :, :], hinge[..., j, :, :])
    return HandPose(pos=pos, rot=rot)


def forward_kinematics_qpos(model: HandModel, hand_qpos: np.ndarray) -> HandPose:
    """:func:`forward_kinematics` from configurations laid out as ``Truth.hand_qpos``, shape (..., 7 + n)."""
    return forward_kinematics(model, *split_qpos(model, hand_qpos))


def capsule_endpoints(model: HandModel, pose: HandPose) -> np.ndarray:
    """End points of every collision capsule in the world (spheres have equal ends).

    Args:
        model: The hand model.
        pose: Its segment poses, leading axes (...).

    Returns:
        Shape (..., G, 2, 3), [m]; radii are ``model.geom_radius``.
    """
    a = pose.to_world(model.geom_segment, model.geom_fromto[:, :3])
    b = pose.to_world(model.geom_segment, model.geom_fromto[:, 3:])
    return np.stack([a, b], axis=-2)


def fingertip_centres(model: HandModel, pose: HandPose) -> np.ndarray:
    """Centres of the fingertip pads in the world, thumb first.

    Args:
        model: The hand model.
        pose: Its segment poses, leading axes (...).

    Returns:
        Shape (..., K, 3), [m]; pad radii are ``model.fingertip_radius``.
    """
    return pose.to_world(model.fingertip_segment, model.fingertip_offset)
