"""Rotations as unit quaternions (w, x, y, z): conversions, products, exponential and log maps.

Vectorised over leading axes; the kinematics stage differentiates rotation vectors of *relative*
rotations (log map), never Euler angles.
"""

from __future__ import annotations

import numpy as np


def quat_from_matrix(R: np.ndarray) -> np.ndarray:
    """Unit quaternions (w >= 0) of rotation matrices (Shepperd's method: divide by the largest term).

    Args:
        R: Rotation matrices, shape (..., 3, 3).

    Returns:
        Quaternions (w, x, y, z), shape (..., 4).
    """
    R = np.asarray(R, dtype=float)
    r00, r11, r22 = R[..., 0, 0], R[..., 1, 1], R[..., 2, 2]
    # 4 |q_c|^2 for c in (w, x, y, z), and the off-diagonal combinations.
    four_sq = np.stack([1 + r00 + r11 + r22, 1 + r00 - r11 - r22, 1 - r00 + r11 - r22, 1 - r00 - r11 + r22], -1)
    s21, s02, s10 = R[..., 2, 1] - R[..., 1, 2], R[..., 0, 2] - R[..., 2, 0], R[..., 1, 0] - R[..., 0, 1]
    p10, p02, p21 = R[..., 1, 0] + R[..., 0, 1], R[..., 0, 2] + R[..., 2, 0], R[..., 2, 1] + R[..., 1, 2]
    # Row c: 4 q_c * (w, x, y, z).
    rows = np.stack(
        [
            np.stack([four_sq[..., 0], s21, s02, s10], -1),
            np.stack([s21, four_sq[..., 1], p10, p02], -1),
            np.stack([s02, p10, four_sq[..., 2], p21], -1),
            np.stack([s10, p02, p21, four_sq[..., 3]], -1),
        ],
        -2,
    )
    best = np.argmax(four_sq, axis=-1)
    q = np.take_along_axis(rows, best[..., None, None], axis=-2)[..., 0, :]
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    return np.where(q[..., :1] < 0, -q, q)


def quat_mul(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Hamilton product p q (rotation q first, then p), broadcasting over leading axes."""
    p, q = np.asarray(p, dtype=float), np.asarray(q, dtype=float)
    pw, px, py, pz = p[..., 0], p[..., 1], p[..., 2], p[..., 3]
    qw, qx, qy, qz = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    out = np.empty(np.broadcast_shapes(p.shape, q.shape))
    out[..., 0] = pw * qw - px * qx - py * qy - pz * qz
    out[..., 1] = pw * qx + px * qw + py * qz - pz * qy
    out[..., 2] = pw * qy - px * qz + py * qw + pz * qx
    out[..., 3] = pw * qz + px * qy - py * qx + pz * qw
    return out


def quat_conj(q: np.ndarray) -> np.ndarray:
    """Conjugate (the inverse of a unit quaternion), shape (..., 4)."""
    return np.asarray(q, dtype=float) * np.array([1.0, -1.0, -1.0, -1.0])


def quat_log(q: np.ndarray) -> np.ndarray:
    """Rotation vectors (axis * angle, angle in [0, pi]) of unit quaternions, (..., 4) -> (..., 3).

    q and -q give the same rotation vector (the shorter way round).
    """
    q = np.asarray(q, dtype=float)
    sign = np.where(q[..., 0] < 0, -1.0, 1.0)
    w, v = sign * q[..., 0], q[..., 1:]
    s = np.sqrt(np.einsum("...i,...i->...", v, v))
    small = s < 1e-8
    s_safe = np.where(small, 1.0, s)
    w_small = np.where(small, w, 1.0)  # w ~ 1 wherever s is small
    # angle / s -> 2 / w (1 - s^2 / (3 w^2)) as s -> 0.
    scale = np.where(small, 2 / w_small * (1 - s**2 / (3 * w_small**2)), 2 * np.arctan2(s, w) / s_safe)
    return v * (sign * scale)[..., None]


def quat_exp(phi: np.ndarray) -> np.ndarray:
    """Unit quaternions of rotation vectors, (..., 3) -> (..., 4)."""
    phi = np.asarray(phi, dtype=float)
    angle = np.linalg.norm(phi, axis=-1)
    half = 0.5 * angle
    small = angle < 1e-8
    # sin(half) / angle -> 1/2 - angle^2 / 48.
    sinc = np.where(small, 0.5 - angle**2 / 48, np.sin(half) / np.where(small, 1.0, angle))
    return np.concatenate([np.cos(half)[..., None], phi * sinc[..., None]], -1)


def relative_log(q_ref: np.ndarray, q: np.ndarray, index: np.ndarray) -> np.ndarray:
    """Rotation vectors of q_ref[i]^-1 q[index[i, j]], computed component-wise (the hot loop).

    Equivalent to ``quat_log(quat_mul(quat_conj(q_ref)[:, None], q[index]))`` but on contiguous
    per-component arrays, which is several times faster for windows of rotations.

    Args:
        q_ref: Reference unit quaternions, shape (n, 4).
        q: Unit quaternions, shape (T, 4).
        index: Indices into q, shape (n, m).

    Returns:
        Rotation vectors, component first: shape (3, n, m).
    """
    a = np.ascontiguousarray(np.asarray(q_ref, dtype=float).T)[:, :, None]
    bw, bx, by, bz = np.ascontiguousarray(np.asarray(q, dtype=float).T)[:, index]
    aw, ax, ay, az = a[0], -a[1], -a[2], -a[3]
    w = aw * bw - ax * bx - ay * by - az * bz
    v = np.stack([aw * bx + ax * bw + ay * bz - az * by, aw * by - ax * bz + ay * bw + az * bx, aw * bz + ax * by - ay * bx + az * bw])
    s = np.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
    sign = np.where(w < 0, -1.0, 1.0)
    w = sign * w
    small = s < 1e-8
    s_safe = np.where(small, 1.0, s)
    w_small = np.where(small, w, 1.0)
    scale = np.where(small, 2 / w_small * (1 - s * s / (3 * w_small * w_small)), 2 * np.arctan2(s, w) / s_safe)
    return v * (sign * scale)
