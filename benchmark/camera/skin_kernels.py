"""The skin's per-frame loops: skinning, pressed pulps and flattening on the box, in numba.

Like :mod:`benchmark.camera.raster_kernels`, everything runs in float64 in a fixed order with no
BLAS, so a frame's skin is the same bits on every machine.
"""

from __future__ import annotations

import math

from fsv.jit import kernel


@kernel
def skin_points(local, body, parent_local, parent_body, weight, rot, trans, out):
    """Linear blend skinning: ``out[i] = (1 - w) T_body p + w T_parent p_parent`` in the camera frame.

    Args:
        local: Vertices in their segments' frames, (V, 3).
        body: Body (index into ``rot``) of each vertex's segment, (V,) int64.
        parent_local: Vertices in their parent segments' frames at the bind pose, (V, 3).
        parent_body: Body of each vertex's parent segment, (V,) int64.
        weight: Parent weight, (V,).
        rot, trans: Camera-from-body rotations (B, 3, 3) and translations (B, 3).
        out: Camera-frame vertices, (V, 3), written.
    """
    for i in range(local.shape[0]):
        b, p, w = body[i], parent_body[i], weight[i]
        for r in range(3):
            own = rot[b, r, 0] * local[i, 0] + rot[b, r, 1] * local[i, 1] + rot[b, r, 2] * local[i, 2] + trans[b, r]
            if w > 0.0:
                par = (rot[p, r, 0] * parent_local[i, 0] + rot[p, r, 1] * parent_local[i, 1]
                       + rot[p, r, 2] * parent_local[i, 2] + trans[p, r])
                out[i, r] = (1.0 - w) * own + w * par
            else:
                out[i, r] = own


@kernel
def pulp_presses(box_pos, box_quat, point, normal, force, active, stiffness, exponent, centre, push):
    """Where each pulp presses and by how much, per frame, in the world frame.

    The compression is δ = ln(1 + m F / b) / m (Serina et al. 1997) for the normal force F of the
    contact (0 when inactive); the push is δ along the contact's normal into the box.

    Args:
        box_pos, box_quat: Box pose per frame, (T, 3) and (T, 4) (w, x, y, z).
        point, normal, force: Contact point, unit normal into the box and force, object frame, (T, K, 3).
        active: Contact active, (T, K) bool.
        stiffness: b [N/mm].
        exponent: m [1/mm].
        centre: Centres of pressure, world frame, (T, K, 3) [m], written.
        push: δ times the normal, world frame, (T, K, 3) [m], written.
    """
    for t in range(box_pos.shape[0]):
        w, x, y, z = box_quat[t, 0], box_quat[t, 1], box_quat[t, 2], box_quat[t, 3]
        R00, R01, R02 = 1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)
        R10, R11, R12 = 2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)
        R20, R21, R22 = 2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)
        for k in range(point.shape[1]):
            px, py, pz = point[t, k, 0], point[t, k, 1], point[t, k, 2]
            centre[t, k, 0] = R00 * px + R01 * py + R02 * pz + box_pos[t, 0]
            centre[t, k, 1] = R10 * px + R11 * py + R12 * pz + box_pos[t, 1]
            centre[t, k, 2] = R20 * px + R21 * py + R22 * pz + box_pos[t, 2]
            nx, ny, nz = normal[t, k, 0], normal[t, k, 1], normal[t, k, 2]
            f = force[t, k, 0] * nx + force[t, k, 1] * ny + force[t, k, 2] * nz
            d = 0.0
            if active[t, k] and f > 0.0:
                d = math.log1p(exponent * f / stiffness) / exponent * 1e-3
            push[t, k, 0] = d * (R00 * nx + R01 * ny + R02 * nz)
            push[t, k, 1] = d * (R10 * nx + R11 * ny + R12 * nz)
            push[t, k, 2] = d * (R20 * nx + R21 * ny + R22 * nz)


@kernel
def press_pulps(verts, finger, pulp, centre, push, reach):
    """Pushes each pressed pulp's vertices into the face it presses, tapering with distance.

    A vertex of finger k's distal phalanx at distance d from the centre of pressure moves by
    ``(1 - d^2 / reach_k^2)^2`` times the push (nothing beyond ``reach_k``).

    Args:
        verts: Camera-frame vertices, (V, 3), updated.
        finger: Finger of each vertex, (V,) int64 (-1 on the palm).
        pulp: Whether the vertex may be pressed, (V,) bool.
        centre, push: Camera-frame centre of pressure and push per finger, (K, 3) [m].
        reach: Radius of the pressed region per finger, (K,) [m].
    """
    for i in range(verts.shape[0]):
        if not pulp[i]:
            continue
        k = finger[i]
        if push[k, 0] == 0.0 and push[k, 1] == 0.0 and push[k, 2] == 0.0:
            continue
        dx, dy, dz = verts[i, 0] - centre[k, 0], verts[i, 1] - centre[k, 1], verts[i, 2] - centre[k, 2]
        q = (dx * dx + dy * dy + dz * dz) / (reach[k] * reach[k])
        if q >= 1.0:
            continue
        w = (1.0 - q) * (1.0 - q)
        for r in range(3):
            verts[i, r] += w * push[k, r]


@kernel
def flatten_on_box(verts, R, t, half):
    """Moves every vertex inside the box onto the box's nearest face (skin does not enter the box).

    Args:
        verts: Camera-frame vertices, (V, 3), updated.
        R, t: The box's camera-frame rotation (3, 3) and centre (3,).
        half: The box's half extents, (3,) [m].
    """
    q = [0.0, 0.0, 0.0]
    for i in range(verts.shape[0]):
        dx, dy, dz = verts[i, 0] - t[0], verts[i, 1] - t[1], verts[i, 2] - t[2]
        inside = True
        best, axis = math.inf, -1
        for c in range(3):
            q[c] = R[0, c] * dx + R[1, c] * dy + R[2, c] * dz
            room = half[c] - abs(q[c])
            if room <= 0.0:
                inside = False
                break
            if room < best:
                best, axis = room, c
        if not inside:
            continue
        q[axis] = half[axis] if q[axis] >= 0.0 else -half[axis]
        for r in range(3):
            verts[i, r] = R[r, 0] * q[0] + R[r, 1] * q[1] + R[r, 2] * q[2] + t[r]
