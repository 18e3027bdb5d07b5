"""The depth rasteriser's per-pixel loops: numba kernels in float64 and a fixed order.

Every pixel's depth is computed from its own ray, not interpolated: for a triangle, the ray
meets the triangle's plane at depth ``(n . p0) / (n . d)`` and the pixel is covered when the ray
passes inside the triangle's three edges (the signs of three triple products); for a capsule or
sphere, the ray's first hit on the true surface. The ray of OpenCV pixel (u, v) (pixel centres at
integer coordinates) is d = ((u - cx) / fx, (v - cy) / fy, 1), so the ray parameter is the depth
along the optical axis. Nothing here depends on a GPU, a driver or a BLAS: the same scene gives
the same bits on every machine (numba does not contract multiplies and adds into FMAs by default,
and the loops run in one order).

The scene is drawn in a fixed order (triangles, then capsules, each in index order) with a strict
depth test, so a pixel two surfaces reach at exactly the same depth keeps the first.
"""

from __future__ import annotations

import numpy as np

from fsv.jit import kernel


@kernel
def camera_from_bodies(R_cw, t_cw, xpos, xmat, rot, trans):
    """Each body's pose in the camera frame, ``rot[b] = R_cw @ xmat[b]`` and ``trans[b] = R_cw @
    xpos[b] + t_cw``, in a fixed order (no BLAS).

    Args:
        R_cw, t_cw: Camera-from-world rotation (3, 3) and translation (3,).
        xpos, xmat: World poses of the bodies, (B, 3) and (B, 3, 3).
        rot, trans: (B, 3, 3) and (B, 3), written.
    """
    for b in range(xpos.shape[0]):
        for r in range(3):
            for c in range(3):
                rot[b, r, c] = R_cw[r, 0] * xmat[b, 0, c] + R_cw[r, 1] * xmat[b, 1, c] + R_cw[r, 2] * xmat[b, 2, c]
            trans[b, r] = R_cw[r, 0] * xpos[b, 0] + R_cw[r, 1] * xpos[b, 1] + R_cw[r, 2] * xpos[b, 2] + t_cw[r]


@kernel
def transform_points(points, body, rot, trans, out):
    """``out[i] = rot[body[i]] @ points[i] + trans[body[i]]``, in a fixed order (no BLAS).

    Args:
        points: Points in their bodies' frames, (N, 3) float64.
        body: Body index of each point, (N,) int64.
        rot, trans: Camera-from-body rotations (B, 3, 3) and translations (B, 3), float64.
        out: The camera-frame points, (N, 3) float64, written.
    """
    for i in range(points.shape[0]):
        b = body[i]
        for r in range(3):
            out[i, r] = rot[b, r, 0] * points[i, 0] + rot[b, r, 1] * points[i, 1] + rot[b, r, 2] * points[i, 2] + trans[b, r]


@kernel(inline="always")
def _pixel_range(lo, hi, n):
    """The pixel indices [a, b) of the pixel centres in [lo, hi], clamped to [0, n)."""
    a = int(np.ceil(lo)) if lo > 0.0 else 0
    b = int(np.floor(hi)) + 1 if hi < n - 1 else n
    if a > n:
        a = n
    if b < 0:
        b = 0
    return a, b


@kernel(inline="always")
def _extend(x, y, z, fx, fy, cx, cy, box):
    """Extends the pixel bounding box ``box`` (umin, umax, vmin, vmax) by the projection of (x, y, z), z > 0."""
    pu = fx * x / z + cx
    pv = fy * y / z + cy
    if pu < box[0]:
        box[0] = pu
    if pu > box[1]:
        box[1] = pu
    if pv < box[2]:
        box[2] = pv
    if pv > box[3]:
        box[3] = pv


@kernel(inline="always")
def _clipped_box(p, znear, fx, fy, cx, cy, box):
    """The pixel bounding box of the polygon ``p`` (M, 3) clipped to z >= znear (the near plane);
    False when nothing of it lies in front."""
    box[0] = np.inf
    box[1] = -np.inf
    box[2] = np.inf
    box[3] = -np.inf
    m = p.shape[0]
    any_in = False
    for i in range(m):
        j = (i + 1) % m
        zi, zj = p[i, 2], p[j, 2]
        if zi >= znear:
            any_in = True
            _extend(p[i, 0], p[i, 1], zi, fx, fy, cx, cy, box)
        if (zi >= znear) != (zj >= znear):  # the edge crosses the near plane: its crossing point
            s = (znear - zi) / (zj - zi)
            _extend(p[i, 0] + s * (p[j, 0] - p[i, 0]), p[i, 1] + s * (p[j, 1] - p[i, 1]), znear,
                    fx, fy, cx, cy, box)
    return any_in


@kernel
def pixel_rays(H, W, fx, fy, cx, cy):
    """Each column's and row's ray coordinate, ``(u - cx) / fx`` (W,) and ``(v - cy) / fy`` (H,):
    what the rasterisers' pixel loops read, made once a call instead of once a pixel of every
    primitive's box."""
    ray_x = np.empty(W)
    for u in range(W):
        ray_x[u] = (u - cx) / fx
    ray_y = np.empty(H)
    for v in range(H):
        ray_y[v] = (v - cy) / fy
    return ray_x, ray_y


@kernel
def draw_triangles(verts, faces, face_label, fx, fy, cx, cy, znear, zfar, zbuf, lbuf):
    """Draws triangles (front faces only) into the depth and label buffers.

    Args:
        verts: Camera-frame vertices, (V, 3) float64.
        faces: Triangles, (F, 3) int64, counter-clockwise seen from outside (trimesh's order).
        face_label: Label of each triangle, (F,) uint8.
        fx, fy, cx, cy: The intrinsics.
        znear, zfar: Depths drawn: znear < depth < zfar.
        zbuf: Depth buffer, (H, W) float64 (inf where empty), updated.
        lbuf: Label buffer, (H, W) uint8, updated.
    """
    H, W = zbuf.shape
    tri = np.empty((3, 3))
    box = np.empty(4)
    ray_x, ray_y = pixel_rays(H, W, fx, fy, cx, cy)
    for f in range(faces.shape[0]):
        for k in range(3):
            for c in range(3):
                tri[k, c] = verts[faces[f, k], c]
        e1x, e1y, e1z = tri[1, 0] - tri[0, 0], tri[1, 1] - tri[0, 1], tri[1, 2] - tri[0, 2]
        e2x, e2y, e2z = tri[2, 0] - tri[0, 0], tri[2, 1] - tri[0, 1], tri[2, 2] - tri[0, 2]
        nx, ny, nz = e1y * e2z - e1z * e2y, e1z * e2x - e1x * e2z, e1x * e2y - e1y * e2x  # outward normal
        c0 = nx * tri[0, 0] + ny * tri[0, 1] + nz * tri[0, 2]  # n . p0: the camera (origin) sees the front if < 0
        if not c0 < 0.0:
            continue
        if not _clipped_box(tri, znear, fx, fy, cx, cy, box):
            continue
        u0, u1 = _pixel_range(box[0], box[1], W)
        v0, v1 = _pixel_range(box[2], box[3], H)
        # edge normals through the camera: the ray d is inside when d . (p_i x p_j) <= 0 for every edge
        ax = tri[0, 1] * tri[1, 2] - tri[0, 2] * tri[1, 1]
        ay = tri[0, 2] * tri[1, 0] - tri[0, 0] * tri[1, 2]
        az = tri[0, 0] * tri[1, 1] - tri[0, 1] * tri[1, 0]
        bx = tri[1, 1] * tri[2, 2] - tri[1, 2] * tri[2, 1]
        by = tri[1, 2] * tri[2, 0] - tri[1, 0] * tri[2, 2]
        bz = tri[1, 0] * tri[2, 1] - tri[1, 1] * tri[2, 0]
        gx = tri[2, 1] * tri[0, 2] - tri[2, 2] * tri[0, 1]
        gy = tri[2, 2] * tri[0, 0] - tri[2, 0] * tri[0, 2]
        gz = tri[2, 0] * tri[0, 1] - tri[2, 1] * tri[0, 0]
        label = face_label[f]
        for v in range(v0, v1):
            dy = ray_y[v]
            for u in range(u0, u1):
                dx = ray_x[u]
                if ax * dx + ay * dy + az > 0.0 or bx * dx + by * dy + bz > 0.0 or gx * dx + gy * dy + gz > 0.0:
                    continue
                den = nx * dx + ny * dy + nz
                if not den < 0.0:
                    continue
                z = c0 / den
                if z > znear and z < zfar and z < zbuf[v, u]:
                    zbuf[v, u] = z
                    lbuf[v, u] = label


@kernel(inline="always")
def _sphere_hit(ox, oy, oz, dx, dy, dz, dd, cx_, cy_, cz_, rr):
    """Ray parameter of the first hit of o + s d on the sphere (c, r), or inf."""
    qx, qy, qz = ox - cx_, oy - cy_, oz - cz_
    p = dx * qx + dy * qy + dz * qz
    h = p * p - dd * (qx * qx + qy * qy + qz * qz - rr)
    if h < 0.0:
        return np.inf
    return (-p - np.sqrt(h)) / dd


@kernel
def draw_capsules(ends, radius, cap_label, fx, fy, cx, cy, znear, zfar, zbuf, lbuf):
    """Ray-casts capsules and spheres (a capsule whose ends coincide) into the buffers.

    Args:
        ends: Camera-frame axis ends, (C, 2, 3) float64.
        radius: Radii, (C,) float64.
        cap_label: Label of each capsule, (C,) uint8.
        fx, fy, cx, cy, znear, zfar, zbuf, lbuf: As :func:`draw_triangles`.
    """
    H, W = zbuf.shape
    corners = np.empty((8, 3))
    box = np.empty(4)
    ray_x, ray_y = pixel_rays(H, W, fx, fy, cx, cy)
    for c in range(ends.shape[0]):
        r = radius[c]
        rr = r * r
        ax_, ay_, az_ = ends[c, 0, 0], ends[c, 0, 1], ends[c, 0, 2]
        bx_, by_, bz_ = ends[c, 1, 0], ends[c, 1, 1], ends[c, 1, 2]
        # the axis-aligned box around the capsule, a little larger: its projection bounds the pixels
        lo_x, hi_x = min(ax_, bx_) - 1.02 * r, max(ax_, bx_) + 1.02 * r
        lo_y, hi_y = min(ay_, by_) - 1.02 * r, max(ay_, by_) + 1.02 * r
        lo_z, hi_z = min(az_, bz_) - 1.02 * r, max(az_, bz_) + 1.02 * r
        if hi_z <= znear or lo_z >= zfar:
            continue
        box[0] = np.inf
        box[1] = -np.inf
        box[2] = np.inf
        box[3] = -np.inf
        zc = lo_z if lo_z > znear else znear
        for i in range(8):
            corners[i, 0] = lo_x if i & 1 == 0 else hi_x
            corners[i, 1] = lo_y if i & 2 == 0 else hi_y
            corners[i, 2] = zc if i & 4 == 0 else hi_z
            _extend(corners[i, 0], corners[i, 1], corners[i, 2], fx, fy, cx, cy, box)
        u0, u1 = _pixel_range(box[0], box[1], W)
        v0, v1 = _pixel_range(box[2], box[3], H)
        mx, my, mz = 0.5 * (ax_ + bx_), 0.5 * (ay_ + by_), 0.5 * (az_ + bz_)
        bax, bay, baz = bx_ - ax_, by_ - ay_, bz_ - az_
        baba = bax * bax + bay * bay + baz * baz
        label = cap_label[c]
        for v in range(v0, v1):
            dy = ray_y[v]
            for u in range(u0, u1):
                dx = ray_x[u]
                dd = dx * dx + dy * dy + 1.0
                tc = (mx * dx + my * dy + mz) / dd  # solve near the capsule: no cancellation at range
                ox, oy, oz = tc * dx, tc * dy, tc
                s = min(_sphere_hit(ox, oy, oz, dx, dy, 1.0, dd, ax_, ay_, az_, rr),
                        _sphere_hit(ox, oy, oz, dx, dy, 1.0, dd, bx_, by_, bz_, rr))
                if baba > 0.0:
                    oax, oay, oaz = ox - ax_, oy - ay_, oz - az_
                    bard = bax * dx + bay * dy + baz
                    baoa = bax * oax + bay * oay + baz * oaz
                    A = baba * dd - bard * bard
                    if A > 0.0:  # the side of the cylinder, where its axis coordinate lies between the ends
                        B = baba * (dx * oax + dy * oay + oaz) - baoa * bard
                        C = baba * (oax * oax + oay * oay + oaz * oaz) - baoa * baoa - rr * baba
                        h = B * B - A * C
                        if h >= 0.0:
                            t = (-B - np.sqrt(h)) / A
                            y = baoa + t * bard
                            if y > 0.0 and y < baba and t < s:
                                s = t
                if s == np.inf:
                    continue
                z = tc + s
                if z > znear and z < zfar and z < zbuf[v, u]:
                    zbuf[v, u] = z
                    lbuf[v, u] = label


@kernel
def finish(zbuf, lbuf, depth, labels):
    """The float32 depth (0 where nothing is drawn) and the labels of the buffers."""
    H, W = zbuf.shape
    for v in range(H):
        for u in range(W):
            z = zbuf[v, u]
            if z == np.inf:
                depth[v, u] = np.float32(0.0)
                labels[v, u] = 0
            else:
                depth[v, u] = np.float32(z)
                labels[v, u] = lbuf[v, u]
