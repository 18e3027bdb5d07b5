"""The colour camera's per-pixel loops: numba kernels in float64 and a fixed order.

The geometry kernels are :mod:`benchmark.camera.raster_kernels`' ``draw_triangles`` and
``draw_capsules`` with the same arithmetic in the same order (so the depth and the labels are the
same bits as the depth renderer's), which also write each pixel's outward unit normal (camera
frame) and the id of the primitive seen. :func:`shade` then evaluates the shading equation of
:mod:`benchmark.camera.colour` per pixel, with the procedural textures of
:mod:`benchmark.camera.appearance` evaluated in place: integer hashes (value noise and inked
cells) and bilinear interpolation, only ``+ - * /``, ``sqrt``, ``floor`` and integer operations,
so every texture is the same bits on every machine (no libm transcendental is called per pixel).
:func:`expose` is the sensor's per-pixel pass (noise, white balance, sRGB lookup table) and
:func:`register` maps a colour image onto a depth image.

Nothing here calls BLAS; numba does not contract multiplies and adds into FMAs by default and no
fast-math is used.
"""

from __future__ import annotations

import numpy as np

from benchmark.camera.raster_kernels import pixel_rays
from fsv.jit import kernel

_MASK32 = 0xFFFFFFFF
_INV_2_32 = 1.0 / 4294967296.0


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
        if (zi >= znear) != (zj >= znear):
            s = (znear - zi) / (zj - zi)
            _extend(p[i, 0] + s * (p[j, 0] - p[i, 0]), p[i, 1] + s * (p[j, 1] - p[i, 1]), znear,
                    fx, fy, cx, cy, box)
    return any_in


@kernel
def draw_triangles(verts, faces, face_label, id_offset, fx, fy, cx, cy, znear, zfar, zbuf, lbuf, nbuf, ibuf):
    """``raster_kernels.draw_triangles`` (same depth, same labels) that also writes normals and ids.

    Args:
        verts, faces, face_label, fx, fy, cx, cy, znear, zfar, zbuf, lbuf: As
            :func:`benchmark.camera.raster_kernels.draw_triangles`.
        id_offset: Added to the face index for the id written.
        nbuf: Outward unit normal of the surface seen, camera frame, (H, W, 3) float64, updated.
        ibuf: Id of the primitive seen (``id_offset + f``), (H, W) int32, updated.
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
        nx, ny, nz = e1y * e2z - e1z * e2y, e1z * e2x - e1x * e2z, e1x * e2y - e1y * e2x
        c0 = nx * tri[0, 0] + ny * tri[0, 1] + nz * tri[0, 2]
        if not c0 < 0.0:
            continue
        if not _clipped_box(tri, znear, fx, fy, cx, cy, box):
            continue
        u0, u1 = _pixel_range(box[0], box[1], W)
        v0, v1 = _pixel_range(box[2], box[3], H)
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
        inv = 1.0 / np.sqrt(nx * nx + ny * ny + nz * nz)
        ux, uy, uz = nx * inv, ny * inv, nz * inv
        fid = id_offset + f
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
                    nbuf[v, u, 0] = ux
                    nbuf[v, u, 1] = uy
                    nbuf[v, u, 2] = uz
                    ibuf[v, u] = fid


@kernel(inline="always")
def _sphere_hit(ox, oy, oz, dx, dy, dz, dd, cx_, cy_, cz_, rr):
    qx, qy, qz = ox - cx_, oy - cy_, oz - cz_
    p = dx * qx + dy * qy + dz * qz
    h = p * p - dd * (qx * qx + qy * qy + qz * qz - rr)
    if h < 0.0:
        return np.inf
    return (-p - np.sqrt(h)) / dd


@kernel
def draw_capsules(ends, radius, cap_label, id_offset, fx, fy, cx, cy, znear, zfar, zbuf, lbuf, nbuf, ibuf):
    """``raster_kernels.draw_capsules`` (same depth, same labels) that also writes normals and ids.

    The normal at the hit point p (camera frame, ``p = z (dx, dy, 1)``) is ``(p - q) / |p - q|``,
    q the closest point of the capsule's axis segment to p.

    Args:
        ends, radius, cap_label, fx, fy, cx, cy, znear, zfar, zbuf, lbuf: As
            :func:`benchmark.camera.raster_kernels.draw_capsules`.
        id_offset, nbuf, ibuf: As :func:`draw_triangles` (id ``id_offset + c``).
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
        cid = id_offset + c
        for v in range(v0, v1):
            dy = ray_y[v]
            for u in range(u0, u1):
                dx = ray_x[u]
                dd = dx * dx + dy * dy + 1.0
                tc = (mx * dx + my * dy + mz) / dd
                ox, oy, oz = tc * dx, tc * dy, tc
                s = min(_sphere_hit(ox, oy, oz, dx, dy, 1.0, dd, ax_, ay_, az_, rr),
                        _sphere_hit(ox, oy, oz, dx, dy, 1.0, dd, bx_, by_, bz_, rr))
                if baba > 0.0:
                    oax, oay, oaz = ox - ax_, oy - ay_, oz - az_
                    bard = bax * dx + bay * dy + baz
                    baoa = bax * oax + bay * oay + baz * oaz
                    A = baba * dd - bard * bard
                    if A > 0.0:
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
                    px, py, pz = z * dx, z * dy, z
                    w = 0.0
                    if baba > 0.0:
                        w = ((px - ax_) * bax + (py - ay_) * bay + (pz - az_) * baz) / baba
                        w = 0.0 if w < 0.0 else (1.0 if w > 1.0 else w)
                    qx, qy, qz = px - (ax_ + w * bax), py - (ay_ + w * bay), pz - (az_ + w * baz)
                    nn = np.sqrt(qx * qx + qy * qy + qz * qz)
                    if nn > 0.0:
                        nbuf[v, u, 0] = qx / nn
                        nbuf[v, u, 1] = qy / nn
                        nbuf[v, u, 2] = qz / nn
                    else:  # the hit on the axis itself (never on a capsule of positive radius)
                        nbuf[v, u, 0] = 0.0
                        nbuf[v, u, 1] = 0.0
                        nbuf[v, u, 2] = -1.0
                    ibuf[v, u] = cid


# --- textures -----------------------------------------------------------------------------------


@kernel(inline="always")
def hash2(i, j, seed):
    """An integer hash of the lattice point (i, j) and a seed, in [0, 2^32) (int64 arithmetic,
    exact: |i|, |j| < 2^31 and 0 <= seed < 2^24)."""
    h = (i * 374761393 + j * 668265263 + seed * 2246822519) & _MASK32
    h = ((h ^ (h >> 13)) * 1274126177) & _MASK32
    return h ^ (h >> 16)


@kernel(inline="always")
def value_noise(x, y, seed):
    """Value noise at (x, y) (lattice units): the hashed values of the four lattice corners,
    bilinearly interpolated with the smoothstep weight 3t^2 - 2t^3; in [0, 1)."""
    fx0 = np.floor(x)
    fy0 = np.floor(y)
    i, j = int(fx0), int(fy0)
    tx, ty = x - fx0, y - fy0
    sx = tx * tx * (3.0 - 2.0 * tx)
    sy = ty * ty * (3.0 - 2.0 * ty)
    v00 = hash2(i, j, seed) * _INV_2_32
    v10 = hash2(i + 1, j, seed) * _INV_2_32
    v01 = hash2(i, j + 1, seed) * _INV_2_32
    v11 = hash2(i + 1, j + 1, seed) * _INV_2_32
    a = v00 + sx * (v10 - v00)
    b = v01 + sx * (v11 - v01)
    return a + sy * (b - a)


@kernel(inline="always")
def box_ink(face, a, b, half_a, half_b, par):
    """Whether the point (a, b) [m] of box face ``face`` (face coordinates centred on the face,
    half sizes half_a, half_b) is inked: a hashed cell of ``par[face, 0]`` metres inked with
    probability ``par[face, 1]``, or inside the face's stripe (along a if ``par[face, 2]`` is 0,
    else b: the normalised coordinate in [par[face, 3], par[face, 4]])."""
    cell = par[face, 0]
    i = int(np.floor((a + half_a) / cell))
    j = int(np.floor((b + half_b) / cell))
    if hash2(i, j, int(par[face, 5])) * _INV_2_32 < par[face, 1]:
        return True
    c = a / half_a if par[face, 2] == 0.0 else b / half_b
    return c >= par[face, 3] and c <= par[face, 4]


@kernel
def shade(zbuf, lbuf, nbuf, ibuf, n_static, static_rad, fx, fy, cx, cy, light_dir, light_rgb, ambient, background,
          skin, box_R, box_t, box_half, box_base, box_ink_rgb, box_par, box_print, table_R, table_t, table_base,
          table_grain, table_par, table_texture, acc):
    """Adds each pixel's linear-RGB radiance to ``acc`` (the shading equation of :mod:`benchmark.camera.colour`).

    Args:
        zbuf, lbuf, nbuf: Depth (inf: nothing), label and unit normal buffers of one render.
        ibuf: Primitive id per pixel, (H, W) int32 (-1: nothing).
        n_static: Pixels whose id is below this (nothing included) take ``static_rad`` (the
            static scene's radiance, shaded once); -1 shades every pixel.
        static_rad: (H, W, 3) float32.
        fx, fy, cx, cy: The intrinsics.
        light_dir: Direction each light travels, camera frame, (L, 3) unit.
        light_rgb: Each light's linear RGB, (L, 3).
        ambient, background, skin: Linear RGB, (3,) each (ambient irradiance, radiance where nothing
            is seen, the skin's albedo).
        box_R, box_t: The box geom's frame in the camera frame: ``p_cam = box_R @ q + box_t``.
        box_half: The box's half extents, (3,) [m].
        box_base, box_ink_rgb: Per face (+x, -x, +y, -y, +z, -z) the base and ink albedo, (6, 3).
        box_par: Per face the print's parameters (:func:`box_ink`), (6, 6).
        box_print: False: every face the uniform albedo ``box_base[0]``.
        table_R, table_t: The world from the camera: ``p_world = table_R @ p_cam + table_t``.
        table_base, table_grain: The table's base and grain albedo, (3,) each.
        table_par: Grain direction in world xy (2), scale along and across it [m], seed, (5,).
        table_texture: False: the uniform albedo ``table_base``.
        acc: Radiance sums, (H, W, 3) float32, updated (each pixel's radiance rounded to float32
            before it is added).
    """
    H, W = zbuf.shape
    L = light_dir.shape[0]
    alb = np.empty(3)
    for v in range(H):
        dy = (v - cy) / fy
        for u in range(W):
            if ibuf[v, u] < n_static:
                acc[v, u, 0] += static_rad[v, u, 0]
                acc[v, u, 1] += static_rad[v, u, 1]
                acc[v, u, 2] += static_rad[v, u, 2]
                continue
            z = zbuf[v, u]
            if z == np.inf:
                acc[v, u, 0] += np.float32(background[0])
                acc[v, u, 1] += np.float32(background[1])
                acc[v, u, 2] += np.float32(background[2])
                continue
            nx, ny, nz = nbuf[v, u, 0], nbuf[v, u, 1], nbuf[v, u, 2]
            label = lbuf[v, u]
            if label >= 9:
                alb[0], alb[1], alb[2] = skin[0], skin[1], skin[2]
            elif label == 2:
                if box_print:
                    dx = (u - cx) / fx
                    rx, ry, rz = z * dx - box_t[0], z * dy - box_t[1], z - box_t[2]
                    q0 = box_R[0, 0] * rx + box_R[1, 0] * ry + box_R[2, 0] * rz
                    q1 = box_R[0, 1] * rx + box_R[1, 1] * ry + box_R[2, 1] * rz
                    q2 = box_R[0, 2] * rx + box_R[1, 2] * ry + box_R[2, 2] * rz
                    m0 = box_R[0, 0] * nx + box_R[1, 0] * ny + box_R[2, 0] * nz
                    m1 = box_R[0, 1] * nx + box_R[1, 1] * ny + box_R[2, 1] * nz
                    m2 = box_R[0, 2] * nx + box_R[1, 2] * ny + box_R[2, 2] * nz
                    if abs(m0) >= abs(m1) and abs(m0) >= abs(m2):
                        face = 0 if m0 >= 0.0 else 1
                        a, b, ha, hb = q1, q2, box_half[1], box_half[2]
                    elif abs(m1) >= abs(m2):
                        face = 2 if m1 >= 0.0 else 3
                        a, b, ha, hb = q2, q0, box_half[2], box_half[0]
                    else:
                        face = 4 if m2 >= 0.0 else 5
                        a, b, ha, hb = q0, q1, box_half[0], box_half[1]
                    if box_ink(face, a, b, ha, hb, box_par):
                        alb[0], alb[1], alb[2] = box_ink_rgb[face, 0], box_ink_rgb[face, 1], box_ink_rgb[face, 2]
                    else:
                        alb[0], alb[1], alb[2] = box_base[face, 0], box_base[face, 1], box_base[face, 2]
                else:
                    alb[0], alb[1], alb[2] = box_base[0, 0], box_base[0, 1], box_base[0, 2]
            else:  # the table and any other static environment
                if table_texture:
                    dx = (u - cx) / fx
                    px, py, pz = z * dx, z * dy, z
                    wx = table_R[0, 0] * px + table_R[0, 1] * py + table_R[0, 2] * pz + table_t[0]
                    wy = table_R[1, 0] * px + table_R[1, 1] * py + table_R[1, 2] * pz + table_t[1]
                    along = wx * table_par[0] + wy * table_par[1]
                    across = wy * table_par[0] - wx * table_par[1]
                    seed = int(table_par[4])
                    g1 = value_noise(along / table_par[2], across / table_par[3], seed)
                    g2 = value_noise(2.0 * along / table_par[2], 2.0 * across / table_par[3], seed + 1)
                    g = 0.65 * g1 + 0.35 * g2
                    for c in range(3):
                        alb[c] = table_base[c] + g * (table_grain[c] - table_base[c])
                else:
                    alb[0], alb[1], alb[2] = table_base[0], table_base[1], table_base[2]
            e0, e1, e2 = ambient[0], ambient[1], ambient[2]
            for i in range(L):
                cosine = -(nx * light_dir[i, 0] + ny * light_dir[i, 1] + nz * light_dir[i, 2])
                if cosine > 0.0:
                    e0 += light_rgb[i, 0] * cosine
                    e1 += light_rgb[i, 1] * cosine
                    e2 += light_rgb[i, 2] * cosine
            acc[v, u, 0] += np.float32(alb[0] * e0)
            acc[v, u, 1] += np.float32(alb[1] * e1)
            acc[v, u, 2] += np.float32(alb[2] * e2)


@kernel
def mean_radiance(acc, samples, out):
    """``out = acc / samples`` (float32; the exposure's mean radiance)."""
    H, W, C = acc.shape
    s = np.float32(samples)
    for v in range(H):
        for u in range(W):
            for c in range(C):
                out[v, u, c] = acc[v, u, c] / s


@kernel
def max_shift_px(p0, p1, fx, fy, cx, cy, znear):
    """Largest image displacement [px] of the points p0 -> p1 (camera frame, (N, 3)) in front of
    the near plane at both ends."""
    best = 0.0
    for i in range(p0.shape[0]):
        if p0[i, 2] <= znear or p1[i, 2] <= znear:
            continue
        du = fx * p1[i, 0] / p1[i, 2] - fx * p0[i, 0] / p0[i, 2]
        dv = fy * p1[i, 1] / p1[i, 2] - fy * p0[i, 1] / p0[i, 2]
        d = np.sqrt(du * du + dv * dv)
        if d > best:
            best = d
    return best


# --- sensor --------------------------------------------------------------------------------------


@kernel
def expose(radiance, raw, noisy, electrons_per_unit, full_well, read_var, gains, normal_table, srgb_table, out):
    """The sensor's per-pixel pass: signal, noise, white balance, sRGB encoding.

    Per pixel and channel c, in this order: signal e = L_c * electrons_per_unit [e-]; with noise,
    e + sqrt(max(e, 0) + read_var) * z, z = ``normal_table[i]`` with i the value's 16-bit index
    (value n of the image in C order takes bits 16 (n % 4) .. 16 (n % 4) + 15 of ``raw[n // 4]``);
    normalised by the full well and clipped to [0, 1]; times the white-balance gain, clipped to 1;
    encoded by ``srgb_table[int(x * (M - 1) + 0.5)]``.

    Args:
        radiance: Linear radiance, (H, W, 3) float32.
        raw: Random 64-bit words, (ceil(H W 3 / 4),) uint64 (unused without noise).
        noisy: Whether to add noise.
        electrons_per_unit, full_well, read_var: Signal electrons per unit radiance, full-well
            capacity [e-] and read-noise variance [e-^2].
        gains: White-balance gains, (3,).
        normal_table: Standard normal quantiles at (i + 0.5) / 65536, (65536,) float64.
        srgb_table: sRGB code of linear i / (M - 1), (M,) uint8.
        out: (H, W, 3) uint8, written.
    """
    H, W, C = radiance.shape
    M1 = srgb_table.shape[0] - 1
    inv_well = 1.0 / full_well
    g0, g1, g2 = gains[0], gains[1], gains[2]
    n = 0
    for v in range(H):
        for u in range(W):
            for c in range(C):
                e = np.float64(radiance[v, u, c]) * electrons_per_unit
                if noisy:
                    var = (e if e > 0.0 else 0.0) + read_var
                    idx = (raw[n >> 2] >> np.uint64(16 * (n & 3))) & np.uint64(0xFFFF)
                    e = e + np.sqrt(var) * normal_table[idx]
                n += 1
                x = e * inv_well
                x = 0.0 if x < 0.0 else (1.0 if x > 1.0 else x)
                x = x * (g0 if c == 0 else (g1 if c == 1 else g2))
                if x > 1.0:
                    x = 1.0
                out[v, u, c] = srgb_table[int(x * M1 + 0.5)]


@kernel
def register(rgb, Kc, R_wc, t_wc, depth, Kd, R_wd, t_wd, out):
    """Colour of each depth pixel: its back-projected point's nearest colour pixel (0 where the
    depth is 0 or the point falls outside the colour image or behind the colour camera).

    Args:
        rgb: Colour image, (Hc, Wc, 3) uint8.
        Kc: Colour intrinsics, (3, 3).
        R_wc, t_wc: World from colour camera, (3, 3) and (3,).
        depth: Depth image, (Hd, Wd) float32 [m] (0: no measurement).
        Kd: Depth intrinsics, (3, 3).
        R_wd, t_wd: World from depth camera, (3, 3) and (3,).
        out: (Hd, Wd, 3) uint8, written.
    """
    Hc, Wc = rgb.shape[0], rgb.shape[1]
    Hd, Wd = depth.shape
    # colour from depth, R = R_wc^T R_wd and t = R_wc^T (t_wd - t_wc), in a fixed order
    R = np.empty((3, 3))
    t = np.empty(3)
    d0, d1, d2 = t_wd[0] - t_wc[0], t_wd[1] - t_wc[1], t_wd[2] - t_wc[2]
    for r in range(3):
        for c in range(3):
            R[r, c] = R_wc[0, r] * R_wd[0, c] + R_wc[1, r] * R_wd[1, c] + R_wc[2, r] * R_wd[2, c]
        t[r] = R_wc[0, r] * d0 + R_wc[1, r] * d1 + R_wc[2, r] * d2
    fxd, fyd, cxd, cyd = Kd[0, 0], Kd[1, 1], Kd[0, 2], Kd[1, 2]
    fxc, fyc, cxc, cyc = Kc[0, 0], Kc[1, 1], Kc[0, 2], Kc[1, 2]
    for v in range(Hd):
        for u in range(Wd):
            out[v, u, 0] = 0
            out[v, u, 1] = 0
            out[v, u, 2] = 0
            z = np.float64(depth[v, u])
            if not z > 0.0:
                continue
            x, y = (u - cxd) / fxd * z, (v - cyd) / fyd * z
            X = R[0, 0] * x + R[0, 1] * y + R[0, 2] * z + t[0]
            Y = R[1, 0] * x + R[1, 1] * y + R[1, 2] * z + t[1]
            Z = R[2, 0] * x + R[2, 1] * y + R[2, 2] * z + t[2]
            if not Z > 0.0:
                continue
            uc = np.floor(fxc * X / Z + cxc + 0.5)
            vc = np.floor(fyc * Y / Z + cyc + 0.5)
            if uc < 0.0 or vc < 0.0 or uc > Wc - 1 or vc > Hc - 1:
                continue
            iu, iv = int(uc), int(vc)
            out[v, u, 0] = rgb[iv, iu, 0]
            out[v, u, 1] = rgb[iv, iu, 1]
            out[v, u, 2] = rgb[iv, iu, 2]
