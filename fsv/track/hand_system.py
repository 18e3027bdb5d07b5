"""The hand fit's normal equations in one compiled pass: data, free space, no interpenetration, closure.

:meth:`fsv.track.hand.tracker.HandTracker._system` describes the residuals; this module evaluates them
for one hand configuration, accumulating ``A = sum w J^T J`` (upper triangle), ``g = -sum w J^T r``,
the robust cost and the count of explained points row by row, in a fixed order (scalar loops, no
BLAS, no fast-math: the same bits on every BLAS kernel). The temporal-smoothness rows, which need
rotation logarithms, are added by the caller.
"""

from __future__ import annotations

import math

import numpy as np

from fsv.jit import kernel
from fsv.track.articulation import add_row_span, joint_spans, point_row
from fsv.track.capsules import capsule_axes, capsule_constants, cast_ray, closest_capsule, hit_normal


@kernel
def box_sdf(p0, p1, p2, half, grad):  # pragma: no cover - compiled
    """Signed distance of the object-frame point (p0, p1, p2) to the box of half extents ``half``
    centred at the origin (negative inside); its gradient, the outward unit direction of steepest
    increase, is written to ``grad`` (3,) (inside: the normal of the nearest face, the first of
    equally near ones; a coordinate of 0 counts as positive)."""
    q0, q1, q2 = abs(p0) - half[0], abs(p1) - half[1], abs(p2) - half[2]
    s0 = 1.0 if p0 >= 0.0 else -1.0
    s1 = 1.0 if p1 >= 0.0 else -1.0
    s2 = 1.0 if p2 >= 0.0 else -1.0
    o0, o1, o2 = max(q0, 0.0), max(q1, 0.0), max(q2, 0.0)
    out_len = math.sqrt(o0 * o0 + o1 * o1 + o2 * o2)
    ax, qmax = 0, q0
    if q1 > qmax:
        ax, qmax = 1, q1
    if q2 > qmax:
        ax, qmax = 2, q2
    if out_len > 0.0:
        grad[0], grad[1], grad[2] = s0 * o0 / out_len, s1 * o1 / out_len, s2 * o2 / out_len
    else:
        grad[0], grad[1], grad[2] = 0.0, 0.0, 0.0
        grad[ax] = s0 if ax == 0 else (s1 if ax == 1 else s2)
    return out_len + min(qmax, 0.0)


def box_signed_distance(points_obj: np.ndarray, half: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Signed distance to a box centred at the origin and its gradient (object frame).

    Args:
        points_obj: Shape (P, 3), [m].
        half: Half edge lengths, shape (3,), [m].

    Returns:
        ``(distance (P,), gradient (P, 3))``: negative inside; the gradient is the outward unit
        direction of steepest increase (see :func:`box_sdf`).
    """
    return _box_signed_distance(np.ascontiguousarray(points_obj, dtype=np.float64),
                                np.ascontiguousarray(half, dtype=np.float64))


@kernel
def _box_signed_distance(points, half):  # pragma: no cover - compiled
    dist = np.empty(points.shape[0])
    grad = np.zeros((points.shape[0], 3))
    for p in range(points.shape[0]):
        dist[p] = box_sdf(points[p, 0], points[p, 1], points[p, 2], half, grad[p])
    return dist, grad


@kernel
def _segment_point_in_box(pos, rot, s, local, box_pos, box_rot, x):  # pragma: no cover - compiled
    """The point ``local`` (3,) of segment s: written to ``x`` (3,) in the world; returned in the
    box's frame, ``(q0, q1, q2) = (x - box_pos) @ box_rot``."""
    for i in range(3):
        v = 0.0
        for j in range(3):
            v += rot[s, i, j] * local[j]
        x[i] = pos[s, i] + v
    q0 = (x[0] - box_pos[0]) * box_rot[0, 0] + (x[1] - box_pos[1]) * box_rot[1, 0] + (x[2] - box_pos[2]) * box_rot[2, 0]
    q1 = (x[0] - box_pos[0]) * box_rot[0, 1] + (x[1] - box_pos[1]) * box_rot[1, 1] + (x[2] - box_pos[2]) * box_rot[2, 1]
    q2 = (x[0] - box_pos[0]) * box_rot[0, 2] + (x[1] - box_pos[1]) * box_rot[1, 2] + (x[2] - box_pos[2]) * box_rot[2, 2]
    return q0, q1, q2


@kernel
def hand_normal_equations(pos, rot, axis, pivot, moves, geom_segment, geom_fromto, radius,
                          origin, rays, z_obs, free_rays, free_z, sigma, cauchy_k, assign_max_m,
                          pen_local, pen_segment, pen_radius, penetration_m, box_pos, box_rot, half,
                          hidden, tip_segment, tip_offset, tip_radius, flexion, closure_m, closure_range_m):  # pragma: no cover - compiled
    """Normal equations of the hand fit without its smoothness rows.

    Args:
        pos, rot, axis, pivot: The configuration's segment poses and hinge frames
            (:func:`fsv.track.articulation.pose_chain`).
        moves: ``moves[s, j]``: hinge j moves segment s, shape (B, n).
        geom_segment, geom_fromto, radius: The capsules: segment (G,), end points in the segment's
            frame (G, 6), radii (G,).
        origin: Camera centre, shape (3,), [m].
        rays, z_obs: Hand candidates: rays (N, 3) and observed depths (N,), [m].
        free_rays, free_z: Pixels that see the scene: rays (M, 3) and depths (M,), [m].
        sigma: Depth noise scale, [m].
        cauchy_k: Scale of the Cauchy weights in noise sigmas.
        assign_max_m: Candidates farther than this from every capsule pull nothing, [m].
        pen_local, pen_segment, pen_radius: Capsule samples for the no-interpenetration rows
            (segment frame (S, 3), segment (S,), radius (S,)).
        penetration_m: Tolerance of those rows, [m].
        box_pos, box_rot, half: The tracked box.
        hidden: Fingers unseen in the last frame, (K,).
        tip_segment, tip_offset, tip_radius: Fingertip pads: segment (K,), centre in its frame
            (K, 3), radius (K,), [m].
        flexion: 1 for the flexion hinges, 0 for the others, (n,).
        closure_m, closure_range_m: Tolerance and reach of the grasp-closure rows, [m].

    Returns:
        ``(A (D, D) upper triangle, g (D,), cost, explained)`` with D = 6 + n; ``explained`` is
        the fraction of candidates within 2 sigma of the fitted surface.
    """
    n = axis.shape[0]
    D = 6 + n
    G = geom_segment.shape[0]
    A = np.zeros((D, D))
    g = np.zeros(D)
    row = np.empty(D)
    palm = pos[0]
    span = joint_spans(moves)
    # Capsule end points in the world.
    a = np.empty((G, 3))
    b = np.empty((G, 3))
    for c in range(G):
        s = geom_segment[c]
        for i in range(3):
            va = 0.0
            vb = 0.0
            for k in range(3):
                va += rot[s, i, k] * geom_fromto[c, k]
                vb += rot[s, i, k] * geom_fromto[c, 3 + k]
            a[c, i] = pos[s, i] + va
            b[c, i] = pos[s, i] + vb
    u, L, w, wu, ww, wb, wbwb, r2, sphere, br2 = capsule_constants(origin, a, b, radius)
    ab, L2 = capsule_axes(a, b)
    k = cauchy_k * sigma
    k2 = k * k
    cost = 0.0
    explained = 0.0
    x = np.empty(3)
    nrm = np.empty(3)
    cp = np.empty(3)
    # Candidates: along the ray where a capsule is hit in front of the observation, else ICP.
    for p in range(z_obs.shape[0]):
        d0, d1, d2 = rays[p, 0], rays[p, 1], rays[p, 2]
        t, c = cast_ray(d0, d1, d2, u, L, w, wu, ww, wb, wbwb, r2, sphere, br2)
        r = z_obs[p] - t
        if c >= 0 and r > -3.0 * sigma:
            for i in range(3):
                x[i] = origin[i] + t * rays[p, i]
            hit_normal(x, a, u, L, c, nrm)
            nd = nrm[0] * d0 + nrm[1] * d1 + nrm[2] * d2
            s = geom_segment[c]
            point_row(row, x[0], x[1], x[2], s, nrm[0], nrm[1], nrm[2], -1.0 / nd, palm, moves, axis, pivot)
            add_row_span(A, g, row, 1.0 / (1.0 + (r / k) ** 2), r, span[s, 0], span[s, 1])
            cost += 0.5 * k2 * math.log1p((r / k) ** 2)
            if abs(r) < 2.0 * sigma:
                explained += 1.0
        else:
            zo = z_obs[p]
            c, dist = closest_capsule(origin[0] + zo * d0, origin[1] + zo * d1, origin[2] + zo * d2, a, ab, L2,
                                      radius, cp, nrm)
            if dist < assign_max_m:
                if abs(dist) < 2.0 * sigma:
                    explained += 1.0
                s = geom_segment[c]
                point_row(row, cp[0], cp[1], cp[2], s, nrm[0], nrm[1], nrm[2], -1.0, palm, moves, axis, pivot)
                add_row_span(A, g, row, 1.0 / (1.0 + (dist / k) ** 2), dist, span[s, 0], span[s, 1])
            d_c = min(abs(dist), assign_max_m)
            cost += 0.5 * k2 * math.log1p((d_c / k) ** 2)
    if z_obs.shape[0] > 0:
        explained /= z_obs.shape[0]
    # Free space: a capsule predicted in front of what a scene pixel sees.
    for p in range(free_z.shape[0]):
        d0, d1, d2 = free_rays[p, 0], free_rays[p, 1], free_rays[p, 2]
        t, c = cast_ray(d0, d1, d2, u, L, w, wu, ww, wb, wbwb, r2, sphere, br2)
        if c < 0:
            continue
        for i in range(3):
            x[i] = origin[i] + t * free_rays[p, i]
        hit_normal(x, a, u, L, c, nrm)
        nd = nrm[0] * d0 + nrm[1] * d1 + nrm[2] * d2
        r = free_z[p] - t
        s = geom_segment[c]
        point_row(row, x[0], x[1], x[2], s, nrm[0], nrm[1], nrm[2], -1.0 / nd, palm, moves, axis, pivot)
        add_row_span(A, g, row, 1.0 / (1.0 + (r / k) ** 2), r, span[s, 0], span[s, 1])
        cost += 0.5 * k2 * math.log1p((r / k) ** 2)
    # No interpenetration with the box: capsule samples at least their radius outside.
    grad = np.empty(3)
    wp = (sigma / penetration_m) ** 2
    for p in range(pen_segment.shape[0]):
        s = pen_segment[p]
        q0, q1, q2 = _segment_point_in_box(pos, rot, s, pen_local[p], box_pos, box_rot, x)
        pen = pen_radius[p] - box_sdf(q0, q1, q2, half, grad)
        if pen <= 0.0:
            continue
        for i in range(3):  # the gradient in the world
            nrm[i] = box_rot[i, 0] * grad[0] + box_rot[i, 1] * grad[1] + box_rot[i, 2] * grad[2]
        point_row(row, x[0], x[1], x[2], s, nrm[0], nrm[1], nrm[2], -1.0, palm, moves, axis, pivot)
        add_row_span(A, g, row, wp, pen, span[s, 0], span[s, 1])
        cost += 0.5 * wp * pen * pen
    # Grasp closure: a hidden finger whose pad is near the box flexes until the pad meets it;
    # only its flexion hinges move (the palm stays where the depth puts it).
    wc = (sigma / closure_m) ** 2
    for f in range(hidden.shape[0]):
        if not hidden[f]:
            continue
        s = tip_segment[f]
        q0, q1, q2 = _segment_point_in_box(pos, rot, s, tip_offset[f], box_pos, box_rot, x)
        gap = box_sdf(q0, q1, q2, half, grad) - tip_radius[f]
        if not (gap > 0.0 and gap < closure_range_m):
            continue
        for i in range(3):
            nrm[i] = box_rot[i, 0] * grad[0] + box_rot[i, 1] * grad[1] + box_rot[i, 2] * grad[2]
        point_row(row, x[0], x[1], x[2], s, nrm[0], nrm[1], nrm[2], 1.0, palm, moves, axis, pivot)
        for i in range(6):
            row[i] = 0.0
        for j in range(n):
            row[6 + j] *= flexion[j]
        add_row_span(A, g, row, wc, gap, span[s, 0], span[s, 1])
        cost += 0.5 * wc * gap * gap
    return A, g, cost, explained


@kernel
def rigidity_rows(A, g, pos, rot, axis, pivot, moves, tip_segment, tip_offset, fingers, anchor, anchor_axis,
                  box_pos, box_rot, w):  # pragma: no cover - compiled
    """Adds the grasp-rigidity rows (:mod:`fsv.track.hand`) to ``A`` (upper triangle) and ``g`` and
    returns their cost: for each finger index k in ``fingers``, the displacement of its pad (on
    segment ``tip_segment[k]`` at ``tip_offset[k]``) from ``box_pos + box_rot @ anchor[k]`` along
    the two box axes other than ``anchor_axis[k]`` (the axes of the face it touches), weight ``w``
    (``(sigma / rigidity_m)^2``)."""
    row = np.zeros(A.shape[0])
    span = joint_spans(moves)
    x = np.empty(3)
    t = np.empty(3)
    cost = 0.0
    for k in fingers:
        s = tip_segment[k]
        for i in range(3):
            x[i] = pos[s, i] + rot[s, i, 0] * tip_offset[k, 0] + rot[s, i, 1] * tip_offset[k, 1] + rot[s, i, 2] * tip_offset[k, 2]
            t[i] = box_pos[i] + box_rot[i, 0] * anchor[k, 0] + box_rot[i, 1] * anchor[k, 1] + box_rot[i, 2] * anchor[k, 2]
        for a in range(3):
            if a == anchor_axis[k]:
                continue
            d0, d1, d2 = box_rot[0, a], box_rot[1, a], box_rot[2, a]
            r = d0 * (x[0] - t[0]) + d1 * (x[1] - t[1]) + d2 * (x[2] - t[2])
            point_row(row, x[0], x[1], x[2], s, d0, d1, d2, 1.0, pos[0], moves, axis, pivot)
            add_row_span(A, g, row, w, r, span[s, 0], span[s, 1])
            cost += 0.5 * w * r * r
    return cost
