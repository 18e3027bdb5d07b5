"""Rotations as matrices: conversions from quaternions and axis-angle, the exponential map and its
inverse (shared by the hand model, the kinematics and the trackers)."""

from __future__ import annotations

import numpy as np

from fsv.linalg import dot, mm, norm


def quat_to_rot(quat: np.ndarray) -> np.ndarray:
    """Rotation matrices of unit quaternions.

    Args:
        quat: Quaternions (w, x, y, z), shape (..., 4); normalised here.

    Returns:
        Rotation matrices, shape (..., 3, 3).
    """
    q = np.asarray(quat, dtype=float)
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    w, x, y, z = np.moveaxis(q, -1, 0)
    return np.stack(
        [
            np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
            np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
            np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1),
        ],
        axis=-2,
    )


def axis_angle_to_rot(axis: np.ndarray, angle: np.ndarray) -> np.ndarray:
    """Rodrigues' formula.

    Args:
        axis: Unit rotation axes, shape (..., 3) (broadcast against ``angle``).
        angle: Rotation angles in [rad], shape (...).

    Returns:
        Rotation matrices, shape (..., 3, 3).
    """
    axis = np.asarray(axis, dtype=float)
    angle = np.asarray(angle, dtype=float)
    axis, angle = np.broadcast_arrays(axis, angle[..., None])
    K = skew_stack(axis)
    return rot_from_skew(K, mm(K, K), angle[..., 0])


def skew_stack(axis: np.ndarray) -> np.ndarray:
    """Cross-product matrices [a]x of vectors along the last axis, (..., 3) -> (..., 3, 3)."""
    x, y, z = np.moveaxis(np.asarray(axis, dtype=float), -1, 0)
    zero = np.zeros_like(x)
    return np.stack([np.stack([zero, -z, y], -1), np.stack([z, zero, -x], -1), np.stack([-y, x, zero], -1)], -2)


def rot_from_skew(K: np.ndarray, KK: np.ndarray, angle: np.ndarray) -> np.ndarray:
    """Rodrigues' formula from the axes' cross-product matrices (for fixed axes, compute them once).

    Args:
        K: ``skew_stack(axis)``, shape (..., 3, 3).
        KK: ``K @ K``, shape (..., 3, 3).
        angle: Rotation angles in [rad], shape (...).

    Returns:
        Rotation matrices, shape (..., 3, 3).
    """
    angle = np.asarray(angle, dtype=float)
    s, c = np.sin(angle)[..., None, None], np.cos(angle)[..., None, None]
    return np.eye(3) + s * K + (1 - c) * KK


def skew(w: np.ndarray) -> np.ndarray:
    """Cross-product matrix [w]x of a vector, shape (3,) -> (3, 3)."""
    return np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])


def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Cross product of 3-vectors along the last axis, bit for bit ``np.cross(a, b)``.

    The same products and differences in the same order as NumPy's, without its axis handling
    (the trackers call it thousands of times per second on small arrays).

    Args:
        a, b: Float arrays of shape (..., 3), broadcast against each other.

    Returns:
        Shape (broadcast of the leading shapes, 3).
    """
    cp = np.empty(np.broadcast_shapes(a.shape[:-1], b.shape[:-1]) + (3,))
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    cp0, cp1, cp2 = cp[..., 0], cp[..., 1], cp[..., 2]
    np.multiply(a1, b2, out=cp0)
    tmp = np.multiply(a2, b1, out=...)
    cp0 -= tmp
    np.multiply(a2, b0, out=cp1)
    np.multiply(a0, b2, out=tmp)
    cp1 -= tmp
    np.multiply(a0, b1, out=cp2)
    np.multiply(a1, b0, out=tmp)
    cp2 -= tmp
    return cp


def exp_so3(w: np.ndarray) -> np.ndarray:
    """Rotation matrix of the rotation vector ``w`` (axis times angle in [rad]), (3,) -> (3, 3)."""
    w = np.asarray(w, dtype=float)
    theta = norm(w)
    W = skew(w)
    if theta < 1e-8:
        return np.eye(3) + W + 0.5 * mm(W, W)
    return np.eye(3) + np.sin(theta) / theta * W + (1 - np.cos(theta)) / theta**2 * mm(W, W)


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
        return theta * a * (1.0 if dot(a, v) >= 0 else -1.0)
    return theta / (2 * np.sin(theta)) * v


def angle_between(Ra: np.ndarray, Rb: np.ndarray) -> np.ndarray:
    """Geodesic angle between rotations in [rad]: shapes (..., 3, 3) -> (...)."""
    tr = np.einsum("...ij,...ij->...", Ra, Rb)
    return np.arccos(np.clip((tr - 1) / 2, -1.0, 1.0))


POLAR_MAX_ITERATIONS = 30  # Newton's polar iteration converges quadratically: 3-5 suffice near SO(3)
POLAR_TOLERANCE = 1e-15  # stop once an iteration moves no entry by more than this


def project_to_so3(M: np.ndarray) -> np.ndarray:
    """Nearest rotation matrix to ``M`` (the orthogonal factor of its polar decomposition), (3, 3) -> (3, 3).

    For ``det(M) > 0`` (every use here: a rotation after a small update) Newton's iteration
    X <- (X + X^-T) / 2 with closed-form 3 x 3 inverses, in a fixed order of operations (the same
    bits on every BLAS kernel); otherwise the singular value decomposition.
    """
    M = np.asarray(M, dtype=float)
    X = M.copy()
    if _det3(X) <= 0:
        U, _, Vt = np.linalg.svd(M)
        D = np.diag([1.0, 1.0, np.sign(np.linalg.det(U @ Vt))])
        return U @ D @ Vt
    for _ in range(POLAR_MAX_ITERATIONS):
        nxt = 0.5 * (X + _cofactor3(X) / _det3(X))
        done = np.max(np.abs(nxt - X)) <= POLAR_TOLERANCE
        X = nxt
        if done:
            break
    return X


def _det3(X: np.ndarray) -> float:
    return float(X[0, 0] * (X[1, 1] * X[2, 2] - X[1, 2] * X[2, 1])
                 - X[0, 1] * (X[1, 0] * X[2, 2] - X[1, 2] * X[2, 0])
                 + X[0, 2] * (X[1, 0] * X[2, 1] - X[1, 1] * X[2, 0]))


def _cofactor3(X: np.ndarray) -> np.ndarray:
    """Cofactor matrix of a 3 x 3 matrix: ``det(X) * inv(X).T``."""
    return np.array([
        [X[1, 1] * X[2, 2] - X[1, 2] * X[2, 1], X[1, 2] * X[2, 0] - X[1, 0] * X[2, 2], X[1, 0] * X[2, 1] - X[1, 1] * X[2, 0]],
        [X[0, 2] * X[2, 1] - X[0, 1] * X[2, 2], X[0, 0] * X[2, 2] - X[0, 2] * X[2, 0], X[0, 1] * X[2, 0] - X[0, 0] * X[2, 1]],
        [X[0, 1] * X[1, 2] - X[0, 2] * X[1, 1], X[0, 2] * X[1, 0] - X[0, 0] * X[1, 2], X[0, 0] * X[1, 1] - X[0, 1] * X[1, 0]],
    ])


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
    return q / norm(q)
