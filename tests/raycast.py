"""Synthetic depth for the tracker's tests: exact ray casting of a box, a table and capsules.

Independent of `fsv.track` (slab method for the box, closed-form ray-capsule intersection), so
the tracker is checked against geometry it did not compute itself.
"""

from __future__ import annotations

import numpy as np

from fsv import Calibration


def look_at_calibration(eye, target, width=320, height=240, fov_deg=(74.0, 58.0)) -> Calibration:
    """A DS325-like pinhole camera at ``eye`` looking at ``target`` (world z up)."""
    eye, target = np.asarray(eye, float), np.asarray(target, float)
    z = target - eye
    z /= np.linalg.norm(z)
    x = np.cross(z, [0.0, 0.0, 1.0])
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    T = np.eye(4)
    T[:3, :3] = np.stack([x, y, z], 1)
    T[:3, 3] = eye
    fx = width / 2 / np.tan(np.radians(fov_deg[0] / 2))
    fy = height / 2 / np.tan(np.radians(fov_deg[1] / 2))
    K = np.array([[fx, 0, (width - 1) / 2], [0, fy, (height - 1) / 2], [0, 0, 1]])
    return Calibration(K=K, T_world_cam=T, width=width, height=height)


def _rays(calib: Calibration):
    v, u = np.mgrid[0 : calib.height, 0 : calib.width]
    K = calib.K
    d = np.stack([(u - K[0, 2]) / K[0, 0], (v - K[1, 2]) / K[1, 1], np.ones(u.shape)], -1).reshape(-1, 3)
    return calib.T_world_cam[:3, 3], d @ calib.T_world_cam[:3, :3].T


def _box_t(o, d, pos, rot, half):
    oo = (o - pos) @ rot
    dd = d @ rot
    with np.errstate(divide="ignore", invalid="ignore"):
        t1 = (-half - oo) / dd
        t2 = (half - oo) / dd
    tmin = np.nanmax(np.minimum(t1, t2), axis=1)
    tmax = np.nanmin(np.maximum(t1, t2), axis=1)
    return np.where((tmax >= tmin) & (tmin > 0), tmin, np.inf)


def _capsule_t(o, d, a, b, r):
    """Smallest ray parameter t (d not normalised) hitting the capsule a-b of radius r."""
    best = np.full(d.shape[0], np.inf)
    ab = b - a
    L2 = ab @ ab
    for c in (a, b):  # end spheres
        oc = o - c
        A = np.einsum("ij,ij->i", d, d)
        B = 2 * d @ oc
        C = oc @ oc - r * r
        disc = B * B - 4 * A * C
        t = np.where(disc >= 0, (-B - np.sqrt(np.maximum(disc, 0))) / (2 * A), np.inf)
        best = np.minimum(best, np.where(t > 0, t, np.inf))
    if L2 > 0:
        u = ab / np.sqrt(L2)
        oa = o - a
        dp = d - np.outer(d @ u, u)
        op = oa - (oa @ u) * u
        A = np.einsum("ij,ij->i", dp, dp)
        B = 2 * dp @ op
        C = op @ op - r * r
        disc = B * B - 4 * A * C
        with np.errstate(divide="ignore", invalid="ignore"):
            t = np.where(disc >= 0, (-B - np.sqrt(np.maximum(disc, 0))) / (2 * A), np.inf)
        s = (oa @ u) + t * (d @ u)
        ok = (t > 0) & (s >= 0) & (s <= np.sqrt(L2))
        best = np.minimum(best, np.where(ok, t, np.inf))
    return best


def _near_pixels(calib, a, b, r):
    """Flat indices of the pixels whose rays may hit the capsule a-b (its projected bounding box)."""
    T = calib.T_world_cam
    pc = (np.stack([a, b]) - T[:3, 3]) @ T[:3, :3]
    z = pc[:, 2]
    if np.any(z <= r):
        return np.arange(calib.width * calib.height)
    uv = pc[:, :2] / z[:, None] * [calib.K[0, 0], calib.K[1, 1]] + [calib.K[0, 2], calib.K[1, 2]]
    pad = r * calib.K[0, 0] / (z.min() - r) + 2
    u0, v0 = np.maximum(np.floor(uv.min(0) - pad).astype(int), 0)
    u1, v1 = np.minimum(np.ceil(uv.max(0) + pad).astype(int), [calib.width - 1, calib.height - 1])
    if u1 < u0 or v1 < v0:
        return np.zeros(0, dtype=int)
    vv, uu = np.mgrid[v0 : v1 + 1, u0 : u1 + 1]
    return (vv * calib.width + uu).reshape(-1)


def render_depth(calib, box_pos, box_rot, half, capsules=(), noise_m=0.0, rng=None, table=True):
    """Depth image (H, W) float32 of a box on the table z = 0 plus capsules (a, b, radius)."""
    o, d = _rays(calib)
    t = _box_t(o, d, np.asarray(box_pos, float), np.asarray(box_rot, float), np.asarray(half, float))
    if table:
        with np.errstate(divide="ignore", invalid="ignore"):
            tt = -o[2] / d[:, 2]
        t = np.minimum(t, np.where(tt > 0, tt, np.inf))
    for a, b, r in capsules:
        a, b, r = np.asarray(a, float), np.asarray(b, float), float(r)
        sel = _near_pixels(calib, a, b, r)
        t[sel] = np.minimum(t[sel], _capsule_t(o, d[sel], a, b, r))
    z = np.where(np.isfinite(t), t, 0.0)  # d has unit optical-axis component: t is the depth
    if noise_m > 0:
        z = np.where(z > 0, z + rng.normal(0.0, noise_m, z.shape), 0.0)
    return np.maximum(z, 0).reshape(calib.height, calib.width).astype(np.float32)

