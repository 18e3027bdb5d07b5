"""The box tracker's per-pixel loops, compiled with numba one pixel at a time in a fixed order: the
predicted depth of a box pose (:func:`_box_depth_kernel`), its flying pixels and the robust fit's
normal equations (:func:`_box_normal_equations`, the Jacobian never materialised). The method they
serve is :mod:`fsv.track.object`."""

from __future__ import annotations

import math

import numpy as np

from fsv.jit import kernel
from fsv.track.kernel_args import readonly

_FAR_M = 1.0  # background depth behind the box where no table is seen, [m] past the box



def _box_depth(o: np.ndarray, d: np.ndarray, bg: np.ndarray, pos: np.ndarray, rot: np.ndarray, half: np.ndarray,
               fx: float, silhouette_px: float, jacobian: bool):
    """:func:`predict_box_depth` on the rays ``d`` (N, 3) from ``o`` (3,) of the pixels, whose table
    depths are ``bg`` (N,): a fit gathers them once for all its iterations (see :func:`_box_rays`)."""
    o, d, bg = _box_rays(o, d, bg)
    depth, w, plane, J = _box_depth_kernel(o, d, bg, readonly(pos), readonly(rot), readonly(half), float(fx),
                                           float(silhouette_px), bool(jacobian))
    if not jacobian:
        return depth, w, plane
    return depth, w, plane, J


def _box_rays(o, d, bg):
    """The compiled kernels' ray arguments: origin (3,), rays (N, 3) and table depths (N,), float64, C order."""
    return readonly(o), readonly(d), readonly(bg)


# -- the compiled prediction -----------------------------------------------------------------
# One pixel at a time, in a fixed order of operations (no BLAS, no fast-math: the same bits on every
# CPU), the arithmetic of the vectorised NumPy model this replaces (kept as the reference in
# tests/test_box_kernel.py): faces (a, s) in the order a = 0, 1, 2, s = +1, -1 (face f = 2 a + (s < 0)),
# dot products summed left to right (NumPy's einsum sums 3-vectors in another order, so the two
# agree to rounding, not bit for bit), the normal equations summed in pixel order.


@kernel
def _box_faces(o, pos, rot, half):  # pragma: no cover - compiled
    """Signed distances of the camera outside each face's plane (> 0: the face is visible), (6,), and
    the faces' outward normals s R_a, (6, 3)."""
    dist = np.empty(6)
    normal = np.empty((6, 3))
    for a in range(3):
        t = 0.0
        for k in range(3):
            t += rot[k, a] * (o[k] - pos[k])
        dist[2 * a] = t - half[a]
        dist[2 * a + 1] = -t - half[a]
        for k in range(3):
            normal[2 * a, k] = rot[k, a]
            normal[2 * a + 1, k] = -rot[k, a]
    return dist, normal


@kernel(inline="always")
def _box_pixel(o, d0, d1, d2, bg, pos, rot, half, dist, normal, fx, silhouette_px, jacobian):  # pragma: no cover
    """Predicted depth, soft coverage, extended plane depth and (with ``jacobian``) the Jacobian row
    of one pixel's ray ``d``; see :func:`predict_box_depth`."""
    rect_best = -np.inf
    best_f = -1
    best_z = np.inf
    best_m = -np.inf
    best_nd = 0.0
    best_p0 = best_p1 = best_p2 = 0.0
    best_axis = 0
    best_sign = 0.0
    for f in range(6):
        dist_f = dist[f]
        if not dist_f > 0:
            continue
        a = f // 2
        n0, n1, n2 = normal[f, 0], normal[f, 1], normal[f, 2]
        nd = d0 * n0 + d1 * n1 + d2 * n2
        if not nd < -1e-9:
            continue  # the ray misses the face's plane: its margin is -inf, never the best
        z = -dist_f / nd
        p0 = o[0] + z * d0
        p1 = o[1] + z * d1
        p2 = o[2] + z * d2
        l0, l1, l2 = p0 - pos[0], p1 - pos[1], p2 - pos[2]
        rect = np.inf  # margin inside the face's rectangle (all four edges)
        sil = np.inf  # margin inside its silhouette edges only
        rect_axis = sil_axis = 0
        rect_sign = sil_sign = 0.0
        for b in range(3):
            if b == a:
                continue
            q = l0 * rot[0, b] + l1 * rot[1, b] + l2 * rot[2, b]
            for j in range(2):
                e = 1.0 if j == 0 else -1.0
                m_edge = half[b] - e * q  # distance inside the edge q_b = e * half_b
                if m_edge < rect:
                    rect, rect_axis, rect_sign = m_edge, b, -e
                if dist[2 * b + j] > 0:
                    continue  # the face across this edge is visible: not a silhouette edge
                if m_edge < sil:
                    sil, sil_axis, sil_sign = m_edge, b, -e
        if rect > rect_best:
            rect_best = rect
            best_f = f
            best_z = z
            best_nd = nd
            best_p0, best_p1, best_p2 = p0, p1, p2
            # Inside the face, the coverage margin is the distance to the silhouette; outside the
            # box (every rectangle margin negative) it is the best face's (negative) rectangle margin.
            if rect >= 0:
                best_m, best_axis, best_sign = sil, sil_axis, sil_sign
            else:
                best_m, best_axis, best_sign = rect, rect_axis, rect_sign
    no_face = best_f < 0
    z_box = 0.0 if no_face else best_z
    bg_eff = bg if np.isfinite(bg) else z_box + _FAR_M
    tau = silhouette_px * max(z_box, 1e-3) / fx
    if no_face or z_box >= bg_eff:
        w = 0.0
    else:
        x = best_m / tau
        x = -50.0 if x < -50.0 else (50.0 if x > 50.0 else x)
        w = 1.0 / (1.0 + np.exp(-x))
    depth = w * z_box + (1 - w) * bg_eff
    # The nearest face's plane, extended past its edges: the box's own pixels outside a slightly
    # wrong silhouette lie on it, which tells them apart from occluders (the hand) in front.
    plane = np.inf if no_face else z_box
    j0 = j1 = j2 = j3 = j4 = j5 = 0.0
    if jacobian and not no_face and w > 0:
        n0, n1, n2 = normal[best_f, 0], normal[best_f, 1], normal[best_f, 2]
        l0, l1, l2 = best_p0 - pos[0], best_p1 - pos[1], best_p2 - pos[2]
        c0 = l1 * n2 - l2 * n1  # (p - c) x n
        c1 = l2 * n0 - l0 * n2
        c2 = l0 * n1 - l1 * n0
        # m = half_b + sign * q_b on the nearest silhouette edge, q_b = R_b . (p - c):
        # dq_b = dw . (R_b x (p - c)) + (R_b . d) dz - R_b . dt.
        r0, r1, r2 = rot[0, best_axis], rot[1, best_axis], rot[2, best_axis]
        sgn = best_sign
        rb_d = r0 * d0 + r1 * d1 + r2 * d2
        e0 = r1 * l2 - r2 * l1  # R_b x (p - c)
        e1 = r2 * l0 - r0 * l2
        e2 = r0 * l1 - r1 * l0
        gain = (z_box - bg_eff) * w * (1 - w) / tau
        # d(m / tau) with tau proportional to the depth: (dm - m dz / z) / tau.
        mz = (best_m if np.isfinite(best_m) else 0.0) / z_box
        # J_t = w dz_dt + gain (dm_dt - mz dz_dt), dz_dt = n / nd, dm_dt = sgn ((R_b . d) dz_dt - R_b),
        # J_w = w dz_dw + gain (dm_dw - mz dz_dw), dz_dw = ((p - c) x n) / nd,
        # dm_dw = sgn (R_b x (p - c) + (R_b . d) dz_dw).
        dz_dt = n0 / best_nd
        dz_dw = c0 / best_nd
        j0 = w * dz_dt + gain * (sgn * (rb_d * dz_dt - r0) - mz * dz_dt)
        j3 = w * dz_dw + gain * (sgn * (e0 + rb_d * dz_dw) - mz * dz_dw)
        dz_dt = n1 / best_nd
        dz_dw = c1 / best_nd
        j1 = w * dz_dt + gain * (sgn * (rb_d * dz_dt - r1) - mz * dz_dt)
        j4 = w * dz_dw + gain * (sgn * (e1 + rb_d * dz_dw) - mz * dz_dw)
        dz_dt = n2 / best_nd
        dz_dw = c2 / best_nd
        j2 = w * dz_dt + gain * (sgn * (rb_d * dz_dt - r2) - mz * dz_dt)
        j5 = w * dz_dw + gain * (sgn * (e2 + rb_d * dz_dw) - mz * dz_dw)
    return depth, w, plane, j0, j1, j2, j3, j4, j5


@kernel
def _box_depth_kernel(o, d, bg, pos, rot, half, fx, silhouette_px, jacobian):  # pragma: no cover - compiled
    """Depth, soft coverage, plane depth (N,) and the Jacobian (N, 6) (or (0, 6) without ``jacobian``)."""
    N = d.shape[0]
    dist, normal = _box_faces(o, pos, rot, half)
    depth = np.empty(N)
    w = np.empty(N)
    plane = np.empty(N)
    J = np.zeros((N if jacobian else 0, 6))
    for i in range(N):
        z, wi, pl, j0, j1, j2, j3, j4, j5 = _box_pixel(o, d[i, 0], d[i, 1], d[i, 2], bg[i], pos, rot, half, dist,
                                                       normal, fx, silhouette_px, jacobian)
        depth[i], w[i], plane[i] = z, wi, pl
        if jacobian:
            J[i, 0], J[i, 1], J[i, 2], J[i, 3], J[i, 4], J[i, 5] = j0, j1, j2, j3, j4, j5
    return depth, w, plane, J


@kernel(inline="always")
def _flying(z_obs, plane, background, margin):  # pragma: no cover - compiled
    """A flying pixel: behind the nearest face's extended plane ``plane`` and in front of the
    background (the table's depth, or ``_FAR_M`` behind the plane where the ray misses the table),
    by more than ``margin`` from both; never with ``margin`` 0 or without a plane."""
    if not (margin > 0.0 and math.isfinite(plane)):
        return False
    back = background if math.isfinite(background) else plane + _FAR_M
    return plane + margin < z_obs < back - margin


@kernel
def _flying_pixels(z_obs, plane, background, margin):  # pragma: no cover - compiled
    """:func:`_flying` per pixel, for the particle search's cost: (N,) -> (N,) bool."""
    out = np.zeros(z_obs.shape[0], dtype=np.bool_)
    for i in range(z_obs.shape[0]):
        out[i] = _flying(z_obs[i], plane[i], background[i], margin)
    return out


@kernel
def _box_normal_equations(o, d, bg, z_obs, pos, rot, half, fx, silhouette_px, sigma, robust_k,
                          occluder_k, flying_k):  # pragma: no cover - compiled
    """One Gauss-Newton iteration's normal equations in one pass over the pixels, in pixel order:
    ``A = J^T W J`` (6, 6) and ``g = J^T W r`` (6,) with the Cauchy weights W of the residuals
    r = z_obs - depth, zero for invalid (z_obs <= 0), occluded and flying pixels
    (:func:`_flying`); the same sums as ``gram(J, w)`` and ``tmv(J, w * r)``."""
    N = d.shape[0]
    dist, normal = _box_faces(o, pos, rot, half)
    A = np.zeros((6, 6))
    g = np.zeros(6)
    Jn = np.empty(6)
    k = robust_k * sigma
    occ = -occluder_k * sigma
    for i in range(N):
        zo = z_obs[i]
        if not zo > 0:
            continue  # invalid pixel: zero weight
        zp, _, pl, Jn[0], Jn[1], Jn[2], Jn[3], Jn[4], Jn[5] = _box_pixel(
            o, d[i, 0], d[i, 1], d[i, 2], bg[i], pos, rot, half, dist, normal, fx, silhouette_px, True)
        if zo - min(zp, pl) < occ:
            continue  # in front of the prediction and the nearest face's plane: occluded
        if _flying(zo, pl, bg[i], flying_k * sigma):
            continue
        r = zo - zp
        t = r / k
        wn = 1.0 / (1.0 + t * t)
        wr = wn * r
        for a in range(6):
            v = wn * Jn[a]
            if v != 0.0:
                for b in range(a, 6):
                    A[a, b] += v * Jn[b]
            g[a] += Jn[a] * wr
    for a in range(6):
        for b in range(a):
            A[a, b] = A[b, a]
    return A, g
