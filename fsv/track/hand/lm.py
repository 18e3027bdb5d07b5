"""The hand fit's Levenberg-Marquardt iterations, compiled: the operations of the NumPy loop in its order.

:meth:`fsv.track.hand.tracker.HandTracker._solve` steps the hand's configuration by
Levenberg-Marquardt around the compiled normal equations (:mod:`fsv.track.hand_system`); written with
NumPy, the glue between them (the rotation updates, the smoothness rows, the damped solve) took
about 40 % of the hand fit's time (1.1 s of 2.5 s on a 10 s lift). :func:`solve` runs the same iterations in one compiled call, each
operation in the order NumPy computes it at the baseline instructions the benchmark pins:

* ``dot`` and ``norm`` (``einsum`` over a contiguous axis) sum in two lanes, eight elements at a
  time, then add the lanes (:func:`edot`);
* ``mm(A, B)`` of 3 x 3 matrices sums each entry in order, ``mm(A, B.T)`` the first and third
  products, then the second;
* ``theta ** 2`` of a Python float is the C library's ``pow``, which is not always ``theta * theta``:
  it is called under glibc's other name for it, ``powf64``, which the compiler does not rewrite.

``tests/test_track_hand_lm.py`` checks each helper against :mod:`fsv.rotation` and the whole loop
against the NumPy one, bit for bit. Where the C library has no ``powf64`` (not glibc), or a
rotation update leaves SO(3) (the polar iteration's singular-value fallback), the tracker runs the
NumPy loop (:data:`AVAILABLE`, status 2 of :func:`solve`).
"""

from __future__ import annotations

import ctypes
import math

import numpy as np
from numba import types

from fsv.jit import kernel
from fsv.linalg import _lu_solve
from fsv.rotation import POLAR_MAX_ITERATIONS, POLAR_TOLERANCE
from fsv.track.articulation import mirror_upper, pose_chain
from fsv.track.hand_system import hand_normal_equations, rigidity_rows


def _process_has(symbol: str) -> bool:
    """Whether the running process (the interpreter and the C libraries it loaded) exports ``symbol``."""
    try:
        return hasattr(ctypes.CDLL(None), symbol)
    except OSError:
        return False


AVAILABLE = _process_has("powf64")
"""Whether the C library exports ``powf64`` (glibc >= 2.27), the ``pow`` of Python's ``**``."""
_pow = types.ExternalFunction("powf64", types.float64(types.float64, types.float64))

OK, SINGULAR, FALLBACK = 0, 1, 2
""":func:`solve`'s status: done; a damped system was singular (NumPy's loop raises there); a rotation
left SO(3) (run the NumPy loop)."""

@kernel
def edot(a, b):  # pragma: no cover - compiled
    """``np.einsum("i,i->", a, b)`` of contiguous 1-D arrays at NumPy's SSE2 baseline."""
    n = a.shape[0]
    l0 = 0.0
    l1 = 0.0
    i = 0
    while n - i >= 8:
        ab3 = a[i + 6] * b[i + 6] + l0
        ab2 = a[i + 4] * b[i + 4] + ab3
        ab1 = a[i + 2] * b[i + 2] + ab2
        l0 = a[i] * b[i] + ab1
        ab3 = a[i + 7] * b[i + 7] + l1
        ab2 = a[i + 5] * b[i + 5] + ab3
        ab1 = a[i + 3] * b[i + 3] + ab2
        l1 = a[i + 1] * b[i + 1] + ab1
        i += 8
    while i < n:
        l0 = a[i] * b[i] + l0
        p = a[i + 1] * b[i + 1] if i + 1 < n else 0.0 * 0.0
        l1 = p + l1
        i += 2
    return 0.0 + (l0 + l1)


@kernel
def mm3(A, B):  # pragma: no cover - compiled
    """``fsv.linalg.mm(A, B)`` of 3 x 3 matrices."""
    out = np.empty((3, 3))
    for i in range(3):
        for k in range(3):
            out[i, k] = ((0.0 + A[i, 0] * B[0, k]) + A[i, 1] * B[1, k]) + A[i, 2] * B[2, k]
    return out


@kernel
def mm3t(A, B):  # pragma: no cover - compiled
    """``fsv.linalg.mm(A, B.T)`` of 3 x 3 matrices (the transpose a strided view)."""
    out = np.empty((3, 3))
    for i in range(3):
        for k in range(3):
            out[i, k] = 0.0 + ((A[i, 0] * B[k, 0] + A[i, 2] * B[k, 2]) + A[i, 1] * B[k, 1])
    return out


@kernel
def exp_so3(w):  # pragma: no cover - compiled
    """``fsv.rotation.exp_so3`` of a contiguous (3,) rotation vector."""
    theta = math.sqrt(edot(w, w))
    W = np.zeros((3, 3))
    W[0, 1], W[0, 2] = -w[2], w[1]
    W[1, 0], W[1, 2] = w[2], -w[0]
    W[2, 0], W[2, 1] = -w[1], w[0]
    WW = mm3(W, W)
    out = np.empty((3, 3))
    if theta < 1e-8:
        for i in range(3):
            for k in range(3):
                out[i, k] = ((1.0 if i == k else 0.0) + W[i, k]) + 0.5 * WW[i, k]
        return out
    a = math.sin(theta) / theta
    b = (1.0 - math.cos(theta)) / _pow(theta, 2.0)
    for i in range(3):
        for k in range(3):
            out[i, k] = ((1.0 if i == k else 0.0) + a * W[i, k]) + b * WW[i, k]
    return out


@kernel
def log_so3(R):  # pragma: no cover - compiled
    """``fsv.rotation.log_so3`` of a 3 x 3 rotation."""
    c = ((R[0, 0] + R[1, 1]) + R[2, 2] - 1.0) / 2.0
    c = min(max(c, -1.0), 1.0)
    theta = math.acos(c)
    v = np.empty(3)
    v[0], v[1], v[2] = R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]
    out = np.empty(3)
    if theta < 1e-6:
        for i in range(3):
            out[i] = 0.5 * v[i]
        return out
    if math.pi - theta < 1e-4:
        i = 0
        best = (R[0, 0] + 1.0) / 2.0
        for j in range(1, 3):
            if (R[j, j] + 1.0) / 2.0 > best:
                best = (R[j, j] + 1.0) / 2.0
                i = j
        root = math.sqrt((R[i, i] + 1.0) / 2.0)
        a = np.empty(3)
        for j in range(3):
            a[j] = ((R[j, i] + (1.0 if j == i else 0.0)) / 2.0) / root
        s = 1.0 if edot(a, v) >= 0 else -1.0
        for j in range(3):
            out[j] = (theta * a[j]) * s
        return out
    f = theta / (2.0 * math.sin(theta))
    for i in range(3):
        out[i] = f * v[i]
    return out


@kernel
def _det3(X):  # pragma: no cover - compiled
    return (X[0, 0] * (X[1, 1] * X[2, 2] - X[1, 2] * X[2, 1])
            - X[0, 1] * (X[1, 0] * X[2, 2] - X[1, 2] * X[2, 0])
            + X[0, 2] * (X[1, 0] * X[2, 1] - X[1, 1] * X[2, 0]))


@kernel
def project_to_so3(M):  # pragma: no cover - compiled
    """``fsv.rotation.project_to_so3`` where ``det(M) > 0``: ``(X, True)``; ``(M, False)`` otherwise
    (its singular-value branch is NumPy's)."""
    X = M.copy()
    if _det3(X) <= 0:
        return X, False
    C = np.empty((3, 3))
    for _ in range(POLAR_MAX_ITERATIONS):
        C[0, 0] = X[1, 1] * X[2, 2] - X[1, 2] * X[2, 1]
        C[0, 1] = X[1, 2] * X[2, 0] - X[1, 0] * X[2, 2]
        C[0, 2] = X[1, 0] * X[2, 1] - X[1, 1] * X[2, 0]
        C[1, 0] = X[0, 2] * X[2, 1] - X[0, 1] * X[2, 2]
        C[1, 1] = X[0, 0] * X[2, 2] - X[0, 2] * X[2, 0]
        C[1, 2] = X[0, 1] * X[2, 0] - X[0, 0] * X[2, 1]
        C[2, 0] = X[0, 1] * X[1, 2] - X[0, 2] * X[1, 1]
        C[2, 1] = X[0, 2] * X[1, 0] - X[0, 0] * X[1, 2]
        C[2, 2] = X[0, 0] * X[1, 1] - X[0, 1] * X[1, 0]
        d = _det3(X)
        nxt = np.empty((3, 3))
        moved = 0.0
        nan = False
        for i in range(3):
            for k in range(3):
                nxt[i, k] = 0.5 * (X[i, k] + C[i, k] / d)
                e = abs(nxt[i, k] - X[i, k])
                if e != e:
                    nan = True
                elif e > moved:
                    moved = e
        done = (not nan) and moved <= POLAR_TOLERANCE
        X = nxt
        if done:
            break
    return X, True


@kernel
def hinges(K, KK, q):  # pragma: no cover - compiled
    """``fsv.rotation.rot_from_skew(K, KK, q)``: every hinge's rotation, (n, 3, 3)."""
    n = q.shape[0]
    out = np.empty((n, 3, 3))
    for j in range(n):
        s = math.sin(q[j])
        c = 1.0 - math.cos(q[j])
        for a in range(3):
            for b in range(3):
                out[j, a, b] = ((1.0 if a == b else 0.0) + s * K[j, a, b]) + c * KK[j, a, b]
    return out


@kernel
def system(palm_pos, palm_rot, joints, prior_pos, prior_rot, prior_joints, ws_pos, ws_rot, ws_joint,
           kin, data, rigid, anchor, anchor_axis, w_rigid, box_pos, box_rot):  # pragma: no cover - compiled
    """``HandTracker._system``: ``(A, g, cost, explained)`` of a configuration.

    ``kin``: ``(hinge_K, hinge_KK, parent, offset_pos, offset_rot, joint_start, joint_ids,
    joint_axis, moves)``; ``data``: the arguments of
    :func:`~fsv.track.hand_system.hand_normal_equations` after the hinge frames, without the box's
    pose: ``(geom_segment, geom_fromto, radius, origin, rays, z_obs, free_rays, free_z, sigma,
    cauchy_k, assign_max_m, pen_local, pen_segment, pen_radius, penetration_m, half, hidden,
    tip_segment, tip_offset, tip_radius, flexion, closure_m, closure_range_m)``.
    """
    K, KK, parent, offset_pos, offset_rot, joint_start, joint_ids, joint_axis, moves = kin
    (geom_segment, geom_fromto, radius, origin, rays, z_obs, free_rays, free_z, sigma, cauchy_k, assign_max_m,
     pen_local, pen_segment, pen_radius, penetration_m, half, hidden, tip_segment, tip_offset, tip_radius, flexion,
     closure_m, closure_range_m) = data
    pos, rot, axis, pivot = pose_chain(palm_pos, palm_rot, hinges(K, KK, joints), parent, offset_pos, offset_rot,
                                       joint_start, joint_ids, joint_axis)
    A, g, cost, explained = hand_normal_equations(
        pos, rot, axis, pivot, moves, geom_segment, geom_fromto, radius, origin, rays, z_obs, free_rays, free_z,
        sigma, cauchy_k, assign_max_m, pen_local, pen_segment, pen_radius, penetration_m, box_pos, box_rot, half,
        hidden, tip_segment, tip_offset, tip_radius, flexion, closure_m, closure_range_m)
    if rigid.shape[0] > 0:
        cost += rigidity_rows(A, g, pos, rot, axis, pivot, moves, tip_segment, tip_offset, rigid, anchor, anchor_axis,
                              box_pos, box_rot, w_rigid)
    n = joints.shape[0]
    res_pos = palm_pos - prior_pos
    res_rot = log_so3(mm3t(palm_rot, prior_rot))
    res_joint = joints - prior_joints
    for i in range(3):
        A[i, i] += ws_pos
        g[i] = g[i] - ws_pos * res_pos[i]
    cost += 0.5 * ws_pos * edot(res_pos, res_pos)
    for i in range(3):
        A[3 + i, 3 + i] += ws_rot
        g[3 + i] = g[3 + i] - ws_rot * res_rot[i]
    cost += 0.5 * ws_rot * edot(res_rot, res_rot)
    for i in range(n):
        A[6 + i, 6 + i] += ws_joint
        g[6 + i] = g[6 + i] - ws_joint * res_joint[i]
    cost += 0.5 * ws_joint * edot(res_joint, res_joint)
    mirror_upper(A)
    return A, g, cost, explained


@kernel
def solve(palm_pos, palm_rot, joints, prior_pos, prior_rot, prior_joints, ws_pos, ws_rot, ws_joint, kin, data,
          rigid, anchor, anchor_axis, w_rigid, box_pos, box_rot, lo, hi, iterations):  # pragma: no cover - compiled
    """``HandTracker._solve``: Levenberg-Marquardt from the configuration, a step taken only if it
    lowers the robust cost.

    Returns:
        ``(status, moved, palm_pos, palm_rot, joints, explained, cost)``: status :data:`OK`,
        :data:`SINGULAR` or :data:`FALLBACK`; ``moved`` whether any step was taken (if not, the
        configuration is the one given).
    """
    # one call site of the system (the compiled code holds one copy of it): the given configuration
    # first, then each step's candidate
    cand_pos, cand_rot, cand_joints = palm_pos, palm_rot, joints
    A = np.empty((0, 0))
    g = np.empty(0)
    cost = 0.0
    explained = 0.0
    lam = 1e-3
    moved = False
    step = np.empty(0)
    for it in range(iterations + 1):
        A2, g2, cost2, expl2 = system(cand_pos, cand_rot, cand_joints, prior_pos, prior_rot, prior_joints, ws_pos,
                                      ws_rot, ws_joint, kin, data, rigid, anchor, anchor_axis, w_rigid, box_pos,
                                      box_rot)
        if it == 0:
            A, g, cost, explained = A2, g2, cost2, expl2
        elif cost2 < cost:
            palm_pos, palm_rot, joints, A, g, cost, explained = cand_pos, cand_rot, cand_joints, A2, g2, cost2, expl2
            moved = True
            lam = max(lam / 3, 1e-6)
            big = 0.0
            nan = False
            for i in range(step.shape[0]):
                e = abs(step[i])
                if e != e:
                    nan = True
                elif e > big:
                    big = e
            if not nan and big < 1e-5:
                break
        else:
            lam *= 8
        if it == iterations:
            break
        D = A.shape[0]
        n = D - 6
        M = np.empty((D, D))
        for i in range(D):
            for k in range(D):
                M[i, k] = (A[i, k] + lam * (A[i, k] if i == k else 0.0)) + 1e-12 * (1.0 if i == k else 0.0)
        B = np.empty((D, 1))
        for i in range(D):
            B[i, 0] = g[i]
        if not _lu_solve(M, B):
            return SINGULAR, moved, palm_pos, palm_rot, joints, explained, cost
        step = B[:, 0].copy()
        for i in range(3):
            step[i] = min(max(step[i], -0.02), 0.02)
        for i in range(3, D):
            step[i] = min(max(step[i], -0.3), 0.3)
        cand_pos = palm_pos + step[:3]
        cand_rot, ok = project_to_so3(mm3(exp_so3(np.ascontiguousarray(step[3:6])), palm_rot))
        if not ok:
            return FALLBACK, moved, palm_pos, palm_rot, joints, explained, cost
        cand_joints = np.empty(n)
        for i in range(n):
            cand_joints[i] = min(max(joints[i] + step[6 + i], lo[i]), hi[i])
    return OK, moved, palm_pos, palm_rot, joints, explained, cost
