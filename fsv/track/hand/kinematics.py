"""The hand model's kinematics: capsule end points and their Jacobians for a state (:class:`HandKinematics`)."""

from __future__ import annotations

import numpy as np

from fsv.errors import InputError
from fsv.hand import finger_of_segment
from fsv.linalg import mm
from fsv.models import HandModel
from fsv.rotation import cross, quat_to_rot, rot_from_skew, skew_stack
from fsv.track.articulation import pose_chain
from fsv.track.hand.state import HandState
from fsv.track.kernel_args import readonly


class HandKinematics:
    """Forward kinematics of a hand model with the world axes and pivots of every hinge.

    Args:
        model: The known hand.
    """

    def __init__(self, model: HandModel):
        if not isinstance(model, HandModel):
            raise InputError(f"hand_model must be an fsv.HandModel, got {type(model).__name__}")
        self.model = model
        B, n = len(model.segment_names), model.num_joints
        self.offset_rot = quat_to_rot(model.offset_quat)
        self.joints_of = [np.flatnonzero(model.joint_segment == b) for b in range(B)]
        # moves[s, j]: hinge j moves segment s (it sits on s or on one of its ancestors).
        moves = np.zeros((B, n), dtype=bool)
        for b in range(B):
            p = model.parent[b]
            if p >= 0:
                moves[b] = moves[p]
            moves[b, self.joints_of[b]] = True
        self.moves = readonly(moves, bool)
        self.finger_of_segment = finger_of_segment(model)
        # Constants of :meth:`pose`: every hinge's cross-product matrix K and K @ K (Rodrigues'
        # formula, the same arrays as ``axis_angle_to_rot`` builds on every call).
        K = skew_stack(model.joint_axis)
        self.hinge_K, self.hinge_KK = readonly(K), readonly(mm(K, K))
        # The tree as flat arrays for the compiled chain (parents before children): segment b's
        # hinges are joint_ids[joint_start[b]:joint_start[b + 1]], in the order they compose. Read-only,
        # as every array the compiled fit takes (one specialisation: fsv.track.kernel_args).
        if np.any(model.parent[1:] >= np.arange(1, B)) or model.parent[0] != -1:
            raise InputError("HandModel segments must be ordered parents first, the palm (parent -1) first")
        self.parent = readonly(model.parent, np.int64)
        self.joint_start = readonly(np.concatenate([[0], np.cumsum([len(j) for j in self.joints_of])]), np.int64)
        self.joint_ids = readonly(np.concatenate(self.joints_of), np.int64)
        self.offset_pos = readonly(model.offset_pos)
        self.offset_rot_c = readonly(self.offset_rot)
        self.joint_axis = readonly(model.joint_axis)

    def hinges(self, joints: np.ndarray) -> np.ndarray:
        """Rotation of every hinge, bit for bit ``axis_angle_to_rot(model.joint_axis, joints)``: (n,) -> (n, 3, 3)."""
        return rot_from_skew(self.hinge_K, self.hinge_KK, joints)

    def pose(self, state: HandState):
        """Segment poses and hinge frames.

        Returns:
            ``(pos (B, 3), rot (B, 3, 3), axis (n, 3), pivot (n, 3))``: segment origins and
            orientations, and each hinge's world axis and pivot, [m].
        """
        return pose_chain(readonly(state.palm_pos), readonly(state.palm_rot),
                          self.hinges(state.joints), self.parent, self.offset_pos, self.offset_rot_c,
                          self.joint_start, self.joint_ids, self.joint_axis)

    def capsules(self, pos, rot) -> tuple[np.ndarray, np.ndarray]:
        """Capsule end points in the world, each (G, 3), [m]."""
        m = self.model
        R = rot[m.geom_segment]
        a = pos[m.geom_segment] + np.einsum("gij,gj->gi", R, m.geom_fromto[:, :3])
        b = pos[m.geom_segment] + np.einsum("gij,gj->gi", R, m.geom_fromto[:, 3:])
        return a, b

    def fingertips(self, pos, rot) -> np.ndarray:
        """Fingertip pad centres in the world, (K, 3), [m]."""
        m = self.model
        seg = m.fingertip_segment
        return pos[seg] + np.einsum("kij,kj->ki", rot[seg], m.fingertip_offset)

    def point_jacobian(self, x: np.ndarray, segment: np.ndarray, direction: np.ndarray, pose) -> np.ndarray:
        """Rows d(direction . x)/d(state) for points x rigidly attached to segments.

        Args:
            x: World points, shape (P, 3).
            segment: Segment carrying each point, shape (P,).
            direction: A world direction per point, shape (P, 3).
            pose: The output of :meth:`pose`.

        Returns:
            Shape (P, 6 + n): palm translation, palm rotation (world, about the palm origin),
            then the hinges.
        """
        pos, _, axis, pivot = pose
        n = self.model.num_joints
        J = np.zeros((x.shape[0], 6 + n))
        J[:, :3] = direction
        J[:, 3:6] = cross(x - pos[0], direction)
        moves = self.moves[segment]  # (P, n)
        # d/dq_j (direction . x) = direction . (a_j x (x - pivot_j)) = a_j . ((x - pivot_j) x direction)
        # lever x direction with lever = x - pivot_j, (P, n, 3): the components of cross() computed
        # from contiguous (P, n) arrays instead of strided views of a broadcast (same operations).
        l0, l1, l2 = (np.subtract.outer(x[:, k], pivot[:, k]) for k in range(3))
        d0, d1, d2 = (direction[:, k : k + 1] for k in range(3))
        lever_x_dir = np.empty((x.shape[0], n, 3))
        for k, (p1, q1, p2, q2) in enumerate(((l1, d2, l2, d1), (l2, d0, l0, d2), (l0, d1, l1, d0))):
            c = lever_x_dir[..., k]
            np.multiply(p1, q1, out=c)
            c -= p2 * q2
        J[:, 6:] = np.where(moves, np.einsum("jk,pjk->pj", axis, lever_x_dir), 0.0)
        return J
