"""Object kinematics from a pose sequence (the paper's §3.2): poses -> velocities and accelerations.

Translation: each world-frame coordinate of the centre of mass goes through the differentiator's
stencils (``fsv.kinematics.stencils``).

Rotation, on SO(3): for frame k the orientation R_e at the estimation time t_e = t_k - lag is
the method's order-0 filter applied in the tangent space of the nearest frame r,
R_e = R_r exp(sum_j c_j log(R_r^T R_j)) (the frame itself for central differences; a geodesic
blend of two frames for a fractional causal lag). Every rotation of the stencil's window is then
expressed relative to R_e as a rotation vector, phi_j = log(R_e^T R_j), so that
R(t) = R_e exp(phi(t)) with phi(t_e) ~ 0. Because the right Jacobian of SO(3) is the identity at
phi = 0 (and its derivative contributes phi' x phi' = 0 there), the body-frame angular velocity and
acceleration at t_e are phi'(t_e) and phi''(t_e); the stencils estimate those, and R_e maps them
to the world frame. A rotation at constant angular velocity has phi linear in time, so every
differentiator returns that velocity exactly (rotation angles within a window must stay below pi).

Position and orientation in the returned ``Kinematics`` are the filtered pose at t_e (order 0).

Frames whose stencil would reach outside the sequence are marked invalid in ``Kinematics.valid``
and hold the estimate of the nearest valid frame (so arrays stay finite).
"""

from __future__ import annotations

import functools
from dataclasses import replace

import numpy as np

from fsv.errors import InputError
from fsv.kinematics import so3
from fsv.kinematics.stencils import AlgebraicConfig, CentralConfig, GaussianConfig
from fsv.linalg import correlate_valid, mm, mv
from fsv.rotation import quat_to_rot
from fsv.types import Kinematics, Poses

_CONFIGS = (AlgebraicConfig, CentralConfig, GaussianConfig)


def sampling_period(t: np.ndarray) -> float:
    """The common spacing of frame times, [s].

    Raises:
        InputError: If there are fewer than two frames or the spacing varies by more than 1e-6 of it.
    """
    t = np.asarray(t, dtype=float)
    if t.size < 2:
        raise InputError(f"need at least 2 frames to differentiate, got {t.size}")
    dt = (t[-1] - t[0]) / (t.size - 1)
    steps = np.diff(t)
    if not dt > 0 or np.max(np.abs(steps - dt)) > 1e-6 * dt:
        raise InputError(
            f"frame times must be evenly spaced and increasing; steps range over "
            f"[{steps.min():.6g}, {steps.max():.6g}] s"
        )
    return float(dt)


def differentiate_poses(poses: Poses, config: AlgebraicConfig | CentralConfig | GaussianConfig) -> Kinematics:
    """Velocities and accelerations of a rigid body from its poses.

    Args:
        poses: Poses at evenly spaced frame times (world_R_object, centre of mass in the world).
        config: Which differentiator and its parameters (``AlgebraicConfig``, ``CentralConfig``
            or ``GaussianConfig``); ``config.causal`` selects real-time estimates.

    Returns:
        Kinematics in the world frame. Offline, values at frame k refer to t_k (``delay_s`` = 0);
        causal, they refer to t_k - ``delay_s`` and use frames up to k only. ``pos``/``rot`` are
        the method's filtered pose at that time (order-0 stencil).

    Raises:
        InputError: For an unknown config, uneven frame times, or a sequence shorter than the
            stencil (the message gives the number of frames needed).
    """
    if not isinstance(config, _CONFIGS):
        raise InputError(f"config must be one of {[c.__name__ for c in _CONFIGS]}, got {type(config).__name__}")
    if not isinstance(poses, Poses):
        raise InputError(f"poses must be fsv.Poses, got {type(poses).__name__}")
    dt = sampling_period(poses.t)
    taps = _taps(config, dt)
    T = len(poses)
    lo = max(-int(o.min()) for o, _ in taps)
    hi = T - max(int(o.max()) for o, _ in taps)  # valid frames: lo <= k < hi
    if hi <= lo:
        need = T + lo - hi + 1
        raise InputError(f"{config.name} ({config.describe()}) needs at least {need} frames, got {T}")
    valid = np.zeros(T, bool)
    valid[lo:hi] = True

    pos, vel, acc = (_apply(poses.pos, o, c, lo, hi) for o, c in taps)
    quats = so3.quat_from_matrix(poses.rot)
    q_ref = _reference(quats, *taps[0], lo, hi)
    rate, accel = _rotation_rates(quats, q_ref, taps[1:], lo, hi)
    R_ref = quat_to_rot(q_ref)
    omega = np.einsum("tij,tj->ti", R_ref, rate)
    alpha = np.einsum("tij,tj->ti", R_ref, accel)
    return Kinematics(
        t=poses.t,
        pos=_hold(pos, lo, hi),
        rot=R_ref,
        vel=_hold(vel, lo, hi),
        acc=_hold(acc, lo, hi),
        omega=_hold(omega, lo, hi),
        alpha=_hold(alpha, lo, hi),
        valid=valid,
        method=config.name,
        delay_s=_lag(config, dt),
    )


@functools.lru_cache(maxsize=512)
def _lag(config, dt: float) -> float:
    """Common lag of all orders: 0 offline, the largest stencil delay in causal mode, [s]."""
    return max(config.stencil(n, dt).delay_s for n in (0, 1, 2)) if config.causal else 0.0


@functools.lru_cache(maxsize=512)
def _taps(config, dt: float) -> list[tuple[np.ndarray, np.ndarray]]:
    """(offsets, coeffs) of orders 0, 1, 2 at the common lag (configs are frozen, hence cacheable)."""
    taps = [config.stencil(n, dt).taps(_lag(config, dt)) for n in (0, 1, 2)]
    for arrays in taps:
        for a in arrays:
            a.setflags(write=False)
    return taps


def _apply(x: np.ndarray, offsets: np.ndarray, coeffs: np.ndarray, lo: int, hi: int) -> np.ndarray:
    """sum_j coeffs[j] * x[k + offsets[j]] for lo <= k < hi; other rows are zero. x: (T, d)."""
    first = int(offsets.min())
    dense = np.zeros(int(offsets.max()) - first + 1)
    dense[offsets - first] = coeffs
    seg = x[lo + first : hi + first + dense.size - 1]
    out = np.zeros_like(x, dtype=float)
    for i in range(x.shape[1]):
        out[lo:hi, i] = correlate_valid(seg[:, i], dense)
    return out


def _hold(x: np.ndarray, lo: int, hi: int) -> np.ndarray:
    """Copies row lo to the rows before it and row hi - 1 to the rows after it."""
    x = np.array(x, dtype=float)
    x[:lo] = x[lo]
    x[hi:] = x[hi - 1]
    return x


def _reference(quats: np.ndarray, offsets: np.ndarray, coeffs: np.ndarray, lo: int, hi: int) -> np.ndarray:
    """Filtered orientation at each frame's estimation time (frames outside [lo, hi) hold the edge).

    The order-0 stencil is applied to rotation vectors in the tangent space of its heaviest tap.
    """
    T = quats.shape[0]
    k = np.clip(np.arange(T), lo, hi - 1)
    if offsets.size == 1:
        return quats[k + offsets[0]]
    q_r = quats[k + offsets[np.argmax(coeffs)]]
    phi = so3.relative_log(q_r, quats, k[:, None] + offsets[None, :])  # (3, T, taps)
    mean = mv(phi, coeffs).T / coeffs.sum()
    return so3.quat_mul(q_r, so3.quat_exp(mean))


def _rotation_rates(
    quats: np.ndarray, q_ref: np.ndarray, taps: list[tuple[np.ndarray, np.ndarray]], lo: int, hi: int
) -> tuple[np.ndarray, np.ndarray]:
    """Body-frame angular velocity and acceleration: the stencils applied to log(R_ref^T R_j)."""
    T = quats.shape[0]
    offsets = np.unique(np.concatenate([o for o, _ in taps]))
    k = np.arange(lo, hi)
    phi = so3.relative_log(q_ref[lo:hi], quats, k[:, None] + offsets[None, :])  # (3, n, len(offsets))
    out = []
    for o, c in taps:
        coeff = np.zeros(offsets.size)
        coeff[np.searchsorted(offsets, o)] = c
        full = np.zeros((T, 3))
        full[lo:hi] = mv(phi, coeff).T
        out.append(full)
    return out[0], out[1]



def kinematics_in_frame(kinematics: Kinematics, frame_from_world: np.ndarray) -> Kinematics:
    """The same motion in another frame fixed to the world: positions by the rigid motion
    ``frame_from_world`` (4, 4), orientations and every vector (velocities, accelerations, angular
    rates) by its rotation. The derivatives of poses in a fixed frame are the derivatives
    expressed in it, so this is what differentiating the moved poses gives (without BLAS)."""
    M = np.asarray(frame_from_world, dtype=float)
    if M.shape != (4, 4) or not np.all(np.isfinite(M)):
        raise InputError(f"frame_from_world must be a finite (4, 4) rigid motion, got {M.shape}")
    R = M[:3, :3]
    return replace(kinematics, pos=mv(R, kinematics.pos) + M[:3, 3], rot=mm(R, kinematics.rot),
                   vel=mv(R, kinematics.vel), acc=mv(R, kinematics.acc), omega=mv(R, kinematics.omega),
                   alpha=mv(R, kinematics.alpha))
