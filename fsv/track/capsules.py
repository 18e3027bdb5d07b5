"""Capsule geometry of the hand tracker, compiled: ray casting and nearest surface points.

A capsule is the set of points within ``radius`` of the segment from ``a`` to ``b``. The two
queries the hand tracker asks thousands of times per frame are compiled with numba, one pixel or
point at a time in a fixed order of operations (no BLAS, no fast-math: the same bits on every
BLAS kernel):

* :func:`ray_capsules`: the first capsule a camera ray meets (cylinder, then the two end
  spheres), with the hit point and the outward surface normal;
* :func:`closest_on_capsules`: the nearest capsule surface of a point, with the signed distance.
"""

from __future__ import annotations

import math

import numpy as np

from fsv.jit import kernel

_TINY_LENGTH_M = 1e-12  # a capsule axis shorter than this is a sphere
_PARALLEL = 1e-12  # rays closer than this to parallel with the axis miss the cylinder wall
_BOUND_MARGIN_M = 1e-9  # slack of the bounding-sphere test (rounding of the exact tests)


def ray_capsules(origin: np.ndarray, rays: np.ndarray, a: np.ndarray, b: np.ndarray, radius: np.ndarray, *,
                 surface: bool = True):
    """First intersection of camera rays with a set of capsules.

    Args:
        origin: Camera centre, shape (3,), [m].
        rays: Ray directions with unit optical-axis component, shape (N, 3), so that the ray
            parameter of a hit is its depth.
        a, b: Capsule end points, shape (G, 3), [m].
        radius: Capsule radii, shape (G,), [m].
        surface: Also compute the hit points and normals (None otherwise).

    Returns:
        ``(depth (N,), geom (N,), point (N, 3), normal (N, 3))``: depth of the first hit (+inf for
        none), the capsule hit (-1 for none), the hit point and the outward unit surface normal.
    """
    origin = np.ascontiguousarray(origin, dtype=np.float64)
    rays = np.ascontiguousarray(rays, dtype=np.float64)
    a = np.ascontiguousarray(a, dtype=np.float64)
    b = np.ascontiguousarray(b, dtype=np.float64)
    radius = np.ascontiguousarray(np.broadcast_to(radius, (a.shape[0],)), dtype=np.float64)
    depth, geom, x, nrm = _ray_capsules(origin, rays, a, b, radius, surface)
    if not surface:
        return depth, geom, None, None
    return depth, geom, x, nrm


@kernel
def capsule_constants(origin, a, b, radius):  # pragma: no cover - compiled
    """Per-capsule constants of :func:`cast_ray` for rays from ``origin``: unit axis u (G, 3),
    length L (G,), w = origin - a (G, 3), w.u, w.w, wb = origin - b (G, 3), wb.wb, r^2, and a
    bounding sphere: its centre c less the origin and c.c, by rows (4, G), and its squared radius (G,)."""
    G = a.shape[0]
    u = np.empty((G, 3))
    L = np.empty(G)
    w = np.empty((G, 3))
    wu = np.empty(G)
    ww = np.empty(G)
    wb = np.empty((G, 3))
    wbwb = np.empty(G)
    r2 = np.empty(G)
    sphere = np.empty((4, G))
    br2 = np.empty(G)
    for g in range(G):
        l2 = 0.0
        for k in range(3):
            l2 += (b[g, k] - a[g, k]) * (b[g, k] - a[g, k])
        L[g] = max(math.sqrt(l2), _TINY_LENGTH_M)
        wu[g] = 0.0
        ww[g] = 0.0
        wbwb[g] = 0.0
        for k in range(3):
            u[g, k] = (b[g, k] - a[g, k]) / L[g]
            w[g, k] = origin[k] - a[g, k]
            wb[g, k] = origin[k] - b[g, k]
            sphere[k, g] = 0.5 * (a[g, k] + b[g, k]) - origin[k]
        for k in range(3):
            wu[g] += w[g, k] * u[g, k]
            ww[g] += w[g, k] * w[g, k]
            wbwb[g] += wb[g, k] * wb[g, k]
        sphere[3, g] = sphere[0, g] * sphere[0, g] + sphere[1, g] * sphere[1, g] + sphere[2, g] * sphere[2, g]
        r2[g] = radius[g] * radius[g]
        R = 0.5 * L[g] + radius[g] + _BOUND_MARGIN_M
        br2[g] = R * R
    return u, L, w, wu, ww, wb, wbwb, r2, sphere, br2


@kernel
def cast_ray(d0, d1, d2, u, L, w, wu, ww, wb, wbwb, r2, sphere, br2):  # pragma: no cover - compiled
    """First capsule met by the ray ``origin + t (d0, d1, d2)``: ``(t, g)``, (inf, -1) for none.

    The capsule constants are :func:`capsule_constants`' for the origin: a capsule is intersected
    only where the ray's line meets its bounding sphere."""
    dd = d0 * d0 + d1 * d1 + d2 * d2
    best = np.inf
    best_g = -1
    for g in range(L.shape[0]):
        # Bounding sphere: the squared distance of its centre from the ray's line.
        cd = sphere[0, g] * d0 + sphere[1, g] * d1 + sphere[2, g] * d2
        if sphere[3, g] - cd * cd / dd > br2[g]:
            continue
        t_g = np.inf
        du = d0 * u[g, 0] + d1 * u[g, 1] + d2 * u[g, 2]
        wd = d0 * w[g, 0] + d1 * w[g, 1] + d2 * w[g, 2]
        # Cylinder: |w_p + t d_p|^2 = r^2 with the components perpendicular to the axis.
        A = dd - du * du
        B = 2.0 * (wd - wu[g] * du)
        C = ww[g] - wu[g] * wu[g] - r2[g]
        disc = B * B - 4.0 * A * C
        if disc >= 0.0 and A > _PARALLEL:
            t = (-B - math.sqrt(disc)) / (2.0 * A)
            s = wu[g] + t * du  # the hit's position along the axis
            if t > 0.0 and s >= 0.0 and s <= L[g]:
                t_g = t
        # The end spheres.
        Be = 2.0 * wd
        disc = Be * Be - 4.0 * dd * (ww[g] - r2[g])
        if disc >= 0.0:
            t = (-Be - math.sqrt(disc)) / (2.0 * dd)
            if t > 0.0 and t < t_g:
                t_g = t
        Be = 2.0 * (d0 * wb[g, 0] + d1 * wb[g, 1] + d2 * wb[g, 2])
        disc = Be * Be - 4.0 * dd * (wbwb[g] - r2[g])
        if disc >= 0.0:
            t = (-Be - math.sqrt(disc)) / (2.0 * dd)
            if t > 0.0 and t < t_g:
                t_g = t
        if t_g < best:
            best = t_g
            best_g = g
    return best, best_g


@kernel
def hit_normal(x, a, u, L, g, out):  # pragma: no cover - compiled
    """Outward unit normal of capsule g at its surface point x (3,), written to ``out`` (3,)."""
    sax = 0.0
    for k in range(3):
        sax += (x[k] - a[g, k]) * u[g, k]
    sax = min(max(sax, 0.0), L[g])
    m = 0.0
    for k in range(3):
        out[k] = x[k] - (a[g, k] + sax * u[g, k])
        m += out[k] * out[k]
    m = max(math.sqrt(m), _TINY_LENGTH_M)
    for k in range(3):
        out[k] /= m


@kernel
def _ray_capsules(origin, rays, a, b, radius, surface):  # pragma: no cover - compiled
    N = rays.shape[0]
    u, L, w, wu, ww, wb, wbwb, r2, sphere, br2 = capsule_constants(origin, a, b, radius)
    depth = np.full(N, np.inf)
    geom = np.full(N, -1, dtype=np.int64)
    x = np.zeros((N, 3))
    nrm = np.zeros((N, 3))
    for n in range(N):
        best, g = cast_ray(rays[n, 0], rays[n, 1], rays[n, 2], u, L, w, wu, ww, wb, wbwb, r2, sphere, br2)
        if g < 0:
            continue
        depth[n] = best
        geom[n] = g
        if not surface:
            continue
        for k in range(3):
            x[n, k] = origin[k] + best * rays[n, k]
        hit_normal(x[n], a, u, L, g, nrm[n])
    return depth, geom, x, nrm


def closest_on_capsules(points: np.ndarray, a: np.ndarray, b: np.ndarray, radius: np.ndarray):
    """Nearest capsule of every point and the signed distance to its surface.

    Args:
        points: Shape (P, 3), [m].
        a, b: Capsule end points, shape (G, 3), [m].
        radius: Capsule radii, shape (G,), [m].

    Returns:
        ``(geom (P,), distance (P,), axis_point (P, 3), normal (P, 3))``: the nearest capsule, the
        signed distance to its surface (negative inside), the closest point on its axis and the
        unit outward direction from that point towards the observed point ((0, 0, 1) for a point
        on the axis).
    """
    return _closest_on_capsules(np.ascontiguousarray(points, dtype=np.float64), np.ascontiguousarray(a, dtype=np.float64),
                                np.ascontiguousarray(b, dtype=np.float64),
                                np.ascontiguousarray(np.broadcast_to(radius, (a.shape[0],)), dtype=np.float64))


@kernel
def closest_capsule(p0, p1, p2, a, ab, L2, radius, cp, normal):  # pragma: no cover - compiled
    """Nearest capsule surface of the point (p0, p1, p2): ``(g, signed distance)``; the closest
    axis point and the outward unit direction towards the point ((0, 0, 1) on the axis) are
    written to ``cp`` (3,) and ``normal`` (3,). ``ab = b - a`` and ``L2 = max(|ab|^2, tiny)``."""
    best = np.inf
    best_g = 0
    for g in range(a.shape[0]):
        t = (p0 - a[g, 0]) * ab[g, 0] + (p1 - a[g, 1]) * ab[g, 1] + (p2 - a[g, 2]) * ab[g, 2]
        t = min(max(t / L2[g], 0.0), 1.0)
        c0, c1, c2 = a[g, 0] + t * ab[g, 0], a[g, 1] + t * ab[g, 1], a[g, 2] + t * ab[g, 2]
        dg = math.sqrt((p0 - c0) * (p0 - c0) + (p1 - c1) * (p1 - c1) + (p2 - c2) * (p2 - c2)) - radius[g]
        if dg < best:
            best = dg
            best_g = g
            cp[0], cp[1], cp[2] = c0, c1, c2
    normal[0], normal[1], normal[2] = p0 - cp[0], p1 - cp[1], p2 - cp[2]
    m = math.sqrt(normal[0] * normal[0] + normal[1] * normal[1] + normal[2] * normal[2])
    if m > 1e-9:
        for k in range(3):
            normal[k] /= m
    else:
        normal[0], normal[1], normal[2] = 0.0, 0.0, 1.0
    return best_g, best


@kernel
def capsule_axes(a, b):  # pragma: no cover - compiled
    """``(ab = b - a (G, 3), L2 = max(|ab|^2, tiny) (G,))`` of :func:`closest_capsule`."""
    G = a.shape[0]
    ab = np.empty((G, 3))
    L2 = np.empty(G)
    for g in range(G):
        s = 0.0
        for k in range(3):
            ab[g, k] = b[g, k] - a[g, k]
            s += ab[g, k] * ab[g, k]
        L2[g] = max(s, _TINY_LENGTH_M)
    return ab, L2


@kernel
def _closest_on_capsules(points, a, b, radius):  # pragma: no cover - compiled
    P = points.shape[0]
    geom = np.zeros(P, dtype=np.int64)
    dist = np.full(P, np.inf)
    cp = np.zeros((P, 3))
    normal = np.zeros((P, 3))
    ab, L2 = capsule_axes(a, b)
    for p in range(P):
        geom[p], dist[p] = closest_capsule(points[p, 0], points[p, 1], points[p, 2], a, ab, L2, radius, cp[p], normal[p])
    return geom, dist, cp, normal
