"""Rotations as matrices: the exponential map and its inverse, used by the pose updates."""

from __future__ import annotations

import numpy as np


def skew(w: np.ndarray) -> np.ndarray:
    """Cross-product matrix [w]x of a vector, shape (3,) -> (3, 3)."""
    return np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])


def exp_so3(w: np.ndarray) -> np.ndarray:
    """Rotation matrix of the rotation vector ``w`` (axis times angle in [rad]), (3,) -> (3, 3)."""
    w = np.asarray(w, dtype=float)
    theta = float(np.linalg.norm(w))
    W = skew(w)
    if theta < 1e-8:
        return np.eye(3) + W + 0.5 * W @ W
    return np.eye(3) + np.sin(theta) / theta * W + (1 - np.cos(theta)) / theta**2 * W @ W


def log_so3(R: np.ndarray) -> np.ndarray:
    """Rotation vector of a rotation matrix, (3, 3) -> (3,), angle in [0, pi]."""
    cos = np.clip((np.trace(R) - 1) / 2, -1.0, 1.0)
    theta = float(np.arccos(cos))
    v = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    if theta < 1e-6:
        return 0.5 * v
    if np.pi - theta < 1e-4:
        # Near pi: axis from the largest diagonal entry of (R + I) / 2 = a a^T.
        B = (R + np.eye(3)) / 2
        i = int(np.argmax(np.diag(B)))
        a = B[:, i] / np.sqrt(B[i, i])
        return theta * a * (1.0 if a @ v >= 0 else -1.0)
    return theta / (2 * np.sin(theta)) * v


def angle_between(Ra: np.ndarray, Rb: np.ndarray) -> np.ndarray:
    """Geodesic angle between rotations in [rad]: shapes (..., 3, 3) -> (...)."""
    tr = np.einsum("...ij,...ij->...", Ra, Rb)
    return np.arccos(np.clip((tr - 1) / 2, -1.0, 1.0))


def project_to_so3(M: np.ndarray) -> np.ndarray:
    """Nearest rotation matrix to ``M`` (polar decomposition), (3, 3) -> (3, 3)."""
    U, _, Vt = np.linalg.svd(M)
    D = np.diag([1.0, 1.0, np.sign(np.linalg.det(U @ Vt))])
    return U @ D @ Vt


def rot_to_quat(R: np.ndarray) -> np.ndarray:
    """Unit quaternion (w, x, y, z) with w >= 0 of a rotation matrix, (3, 3) -> (4,)."""
    w = np.sqrt(max(0.0, 1 + R[0, 0] + R[1, 1] + R[2, 2])) / 2
    x = np.sqrt(max(0.0, 1 + R[0, 0] - R[1, 1] - R[2, 2])) / 2
    y = np.sqrt(max(0.0, 1 - R[0, 0] + R[1, 1] - R[2, 2])) / 2
    z = np.sqrt(max(0.0, 1 - R[0, 0] - R[1, 1] + R[2, 2])) / 2
    x = np.copysign(x, R[2, 1] - R[1, 2])
    y = np.copysign(y, R[0, 2] - R[2, 0])
    z = np.copysign(z, R[1, 0] - R[0, 1])
    q = np.array([w, x, y, z])
    return q / np.linalg.norm(q)
