"""Compiled kernels of the articulated hand: forward kinematics and point rows of the normal equations.

The hand's state is the palm pose (translation, rotation about the palm origin in the world
frame) and n hinge angles; a point x rigidly attached to segment s moves by

    dx = dt + dw x (x - palm) + sum_j dq_j a_j x (x - pivot_j)

over the hinges j that move s (on s or an ancestor). A residual along a direction e has the row
``e . dx`` per state coordinate. The fit's normal equations ``A += w J^T J``, ``g -= w J^T r``
are accumulated row by row without forming J (:func:`point_row`, :func:`add_row`; the same
order of operations on every machine: scalar loops, no BLAS, no fast-math).
"""

from __future__ import annotations

import math

import numpy as np

from fsv.jit import kernel


@kernel
def pose_chain(palm_pos, palm_rot, hinge, parent, offset_pos, offset_rot, joint_start, joint_ids, joint_axis):  # pragma: no cover - compiled
    """Segment poses and hinge frames of a kinematic tree (segments ordered parents first).

    Args:
        palm_pos: Root position, shape (3,), [m].
        palm_rot: Root rotation, shape (3, 3).
        hinge: Rotation of every hinge about its own axis, shape (n, 3, 3).
        parent: Parent of every segment (-1 for the root), shape (B,).
        offset_pos: Segment origin in its parent's frame, shape (B, 3), [m].
        offset_rot: Segment rotation in its parent's frame, shape (B, 3, 3).
        joint_start: Hinges of segment b are ``joint_ids[joint_start[b]:joint_start[b + 1]]``,
            in the order they compose, shape (B + 1,).
        joint_ids: Hinge indices, shape (n,).
        joint_axis: Hinge axes in their segment's frame, shape (n, 3).

    Returns:
        ``(pos (B, 3), rot (B, 3, 3), axis (n, 3), pivot (n, 3))``.
    """
    B, n = parent.shape[0], joint_axis.shape[0]
    pos = np.empty((B, 3))
    rot = np.empty((B, 3, 3))
    axis = np.empty((n, 3))
    pivot = np.empty((n, 3))
    R = np.empty((3, 3))
    tmp = np.empty((3, 3))
    for b in range(B):
        p = parent[b]
        if p < 0:
            for i in range(3):
                pos[b, i] = palm_pos[i]
                for k in range(3):
                    R[i, k] = palm_rot[i, k]
        else:
            for i in range(3):
                s = 0.0
                for k in range(3):
                    s += rot[p, i, k] * offset_pos[b, k]
                pos[b, i] = pos[p, i] + s
                for k in range(3):
                    s = 0.0
                    for m in range(3):
                        s += rot[p, i, m] * offset_rot[b, m, k]
                    R[i, k] = s
        for q in range(joint_start[b], joint_start[b + 1]):
            j = joint_ids[q]
            for i in range(3):
                s = 0.0
                for k in range(3):
                    s += R[i, k] * joint_axis[j, k]
                axis[j, i] = s
                pivot[j, i] = pos[b, i]
            for i in range(3):
                for k in range(3):
                    s = 0.0
                    for m in range(3):
                        s += R[i, m] * hinge[j, m, k]
                    tmp[i, k] = s
            for i in range(3):
                for k in range(3):
                    R[i, k] = tmp[i, k]
        for i in range(3):
            for k in range(3):
                rot[b, i, k] = R[i, k]
    return pos, rot, axis, pivot


@kernel
def point_row(row, x0, x1, x2, s, d0, d1, d2, f, palm, moves, axis, pivot):  # pragma: no cover - compiled
    """Writes ``f * d(direction . x) / d(state)`` of the point x on segment s into ``row`` (6 + n,)."""
    l0, l1, l2 = x0 - palm[0], x1 - palm[1], x2 - palm[2]
    row[0], row[1], row[2] = f * d0, f * d1, f * d2
    row[3] = f * (l1 * d2 - l2 * d1)
    row[4] = f * (l2 * d0 - l0 * d2)
    row[5] = f * (l0 * d1 - l1 * d0)
    for j in range(axis.shape[0]):
        if moves[s, j]:
            m0, m1, m2 = x0 - pivot[j, 0], x1 - pivot[j, 1], x2 - pivot[j, 2]
            row[6 + j] = f * (axis[j, 0] * (m1 * d2 - m2 * d1) + axis[j, 1] * (m2 * d0 - m0 * d2)
                              + axis[j, 2] * (m0 * d1 - m1 * d0))
        else:
            row[6 + j] = 0.0


@kernel
def add_row(A, g, row, w, r):  # pragma: no cover - compiled
    """``A += w row row^T`` (upper triangle) and ``g -= w row r``."""
    D = row.shape[0]
    wr = w * r
    for i in range(D):
        ri = row[i]
        if ri == 0.0:
            continue
        wi = w * ri
        for k in range(i, D):
            A[i, k] += wi * row[k]
        g[i] -= ri * wr


@kernel
def joint_spans(moves):  # pragma: no cover - compiled
    """Where :func:`point_row` can write a non-zero hinge entry: for each segment s, ``[lo, hi)`` of
    the row entries ``6 + j`` of the hinges that move it, (B, 2) int64. The hinges of a segment
    are consecutive in a tree numbered parents first along each chain (the hand's: a finger's
    hinges); where they are not, the span is every hinge entry, ``[6, 6 + n)``; a segment no hinge
    moves (the palm) has the empty span ``[6, 6)``."""
    B, n = moves.shape
    span = np.empty((B, 2), np.int64)
    for s in range(B):
        first = -1
        last = -1
        count = 0
        for j in range(n):
            if moves[s, j]:
                if first < 0:
                    first = j
                last = j
                count += 1
        if count == 0:
            span[s, 0], span[s, 1] = 6, 6
        elif count == last - first + 1:
            span[s, 0], span[s, 1] = 6 + first, 7 + last
        else:
            span[s, 0], span[s, 1] = 6, 6 + n
    return span


@kernel
def add_row_span(A, g, row, w, r, lo, hi):  # pragma: no cover - compiled
    """:func:`add_row` of a row that is zero outside ``[0, 6)`` and ``[lo, hi)`` (a :func:`point_row`
    row of a segment whose span is ``[lo, hi)``, :func:`joint_spans`), with the same bits: only the
    products of a zero entry are left out, and adding such a product (+-0) to an entry of ``A``
    changes nothing (the entries start at +0 and a sum is never -0 under round-to-nearest);
    where ``w row[i]`` is not finite (its product with 0 is NaN) the whole row is added as
    :func:`add_row` adds it."""
    D = row.shape[0]
    wr = w * r
    for i in range(6):
        ri = row[i]
        if ri == 0.0:
            continue
        wi = w * ri
        if math.isfinite(wi):
            for k in range(i, 6):
                A[i, k] += wi * row[k]
            for k in range(lo, hi):
                A[i, k] += wi * row[k]
        else:
            for k in range(i, D):
                A[i, k] += wi * row[k]
        g[i] -= ri * wr
    for i in range(lo, hi):
        ri = row[i]
        if ri == 0.0:
            continue
        wi = w * ri
        if math.isfinite(wi):
            for k in range(i, hi):
                A[i, k] += wi * row[k]
        else:
            for k in range(i, D):
                A[i, k] += wi * row[k]
        g[i] -= ri * wr


@kernel
def mirror_upper(A):  # pragma: no cover - compiled
    """Copies the upper triangle of a square matrix onto its lower triangle, in place."""
    D = A.shape[0]
    for i in range(D):
        for k in range(i):
            A[i, k] = A[k, i]
