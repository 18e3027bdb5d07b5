"""The depth sensor's per-pixel loops: numba kernels in a fixed order (the same bits on every CPU),
and their preallocated workspace. The model they apply is :class:`benchmark.camera.sensor.SensorModel`."""

from __future__ import annotations

import threading

import numpy as np

from benchmark.errors import BenchmarkError
from fsv.jit import kernel


def _image(depth_m, what: str) -> np.ndarray:
    """A float32 (H, W) C-contiguous depth image, or a BenchmarkError naming `what` takes."""
    z = np.ascontiguousarray(depth_m, dtype=np.float32)
    if z.ndim != 2:
        raise BenchmarkError(f"{what} takes one depth image of shape (H, W), got shape {z.shape}")
    return z


def _intrinsics(K) -> tuple:
    """(fx, fy, cx, cy) as float64 from OpenCV intrinsics (3, 3)."""
    K = np.asarray(K, dtype=np.float64)
    if K.shape != (3, 3):
        raise BenchmarkError(f"K must be the (3, 3) intrinsics matrix, got shape {K.shape}")
    return float(K[0, 0]), float(K[1, 1]), float(K[0, 2]), float(K[1, 2])


_FAR_Z = np.float32(1e10)  # depth, [m]: farther than any edge threshold from any real depth
_NEAR_Z = np.float32(1e-15)  # depths at or below this (incl. 0 = nothing) count as nothing
_FAR_W = np.float32(1) / _NEAR_Z  # inverse depth of nothing, [1/m]
_HALF_FAR_W = np.float32(0.5) * _FAR_W
_ONE = np.float32(1)
_ZERO = np.float32(0)



class _Workspace:
    """Padded scratch images for one image shape, reused across frames (fresh large arrays per
    frame cost more in page faults than the arithmetic on them)."""

    def __init__(self, shape: tuple[int, int]):
        H, W = shape
        self.w = np.empty((H + 2, W + 2), dtype=np.float32)  # inverse depth, _FAR_W around
        self.zz = np.empty((H + 2, W + 2), dtype=np.float32)  # depth for the edge test, nan around
        self.ok = np.empty((H, W), dtype=bool)
        self.edge = np.empty((H, W), dtype=bool)  # measurable but for a depth jump
        self.c2 = np.empty((H, W), dtype=np.float32)  # incidence cosine (squared, after the sensor kernel)
        self.zfar = np.empty((H, W), dtype=np.float32)  # deepest 4-neighbour's depth
        self.offsets = np.empty((2, H, W), dtype=np.float32)  # lateral jitter's normals (rows, columns)
        self.jittered = np.empty((H, W), dtype=np.float32)  # the depth after the jitter
        self.uniform = np.empty((H, W), dtype=np.float32)  # dropout's uniforms
        self.flying = np.empty((H, W), dtype=np.float32)  # flying pixels' uniforms
        self.bias = np.empty((H, W), dtype=np.float32)  # multipath bias
        self.no_out = np.empty((0, W), dtype=np.float32)  # "no measurement, only the mask"


_local = threading.local()


def _workspace(shape: tuple[int, int]) -> _Workspace:
    """This thread's workspace for images of `shape`."""
    spaces = _local.__dict__.setdefault("spaces", {})
    if shape not in spaces:
        if len(spaces) > 4:
            spaces.clear()
        spaces[shape] = _Workspace(shape)
    return spaces[shape]


@kernel
def _pad(z, w, zz):
    """Fills the padded inverse depth `w` (1 / depth; _FAR_W where nothing is seen and outside
    the image) and the padded edge-test depth `zz` (nothing: _FAR_Z, far from any depth and equal
    to nothing; nan outside the image, so that no jump is found there)."""
    H, W = z.shape
    nan = np.float32(np.nan)
    w[0, :] = _FAR_W
    w[H + 1, :] = _FAR_W
    zz[0, :] = nan
    zz[H + 1, :] = nan
    for i in range(H):
        w[i + 1, 0] = _FAR_W
        w[i + 1, W + 1] = _FAR_W
        zz[i + 1, 0] = nan
        zz[i + 1, W + 1] = nan
        zr, wr, zzr = z[i], w[i + 1], zz[i + 1]
        for j in range(W):
            d = zr[j]
            wr[j + 1] = _ONE / max(d, _NEAR_Z)
            zzr[j + 1] = (_FAR_Z if d <= _ZERO else _ZERO) + d


@kernel(inline="always")
def _slope(w_before, w, w_after):
    """One-sided difference of the inverse depth towards the neighbour whose inverse depth is
    closer, and whether a neighbour that shows something exists in this direction."""
    before = w - w_before
    after = w_after - w
    a_before, a_after = abs(before), abs(after)
    return (after if a_after <= a_before else before), min(a_after, a_before) < _HALF_FAR_W


@kernel(inline="always")
def _incidence_terms(w, w_left, w_right, w_up, w_down, u, v, r2, fx, fy, scale):
    """``(w^2, scale |m|^2 |r|^2, near)`` of a pixel of inverse depth `w` with the inverse
    depths of its 4-neighbours (_FAR_W: nothing or outside the image).

    Their ratio is the squared cosine of the angle between the viewing ray and the surface
    normal, over `scale`. With P(u, v) = z r, r = ((u - cx) / fx, (v - cy) / fy, 1) and the
    inverse depth w = 1/z, the normal dP/du x dP/dv is parallel to
    m = (fx w_u, fy w_v, w - x fx w_u - y fy w_v) (the normal
    z^2 (-fx z_u, -fy z_v, fx x z_u + fy y z_v + z) with z_u = -z^2 w_u, over z^2), with
    m . r = w, so cos = w / (|m| |r|). The inverse depth is affine in (u, v) on a plane, so its
    one-sided differences are exact there; each is taken towards the neighbour whose inverse
    depth is closer (so they do not straddle an edge). ``near`` is False where the pixel has, in
    one direction, no neighbour that shows something (the terms are meaningless there).
    `u`, `v` are the pixel's offsets from the principal point, `r2` = |r|^2, all float32.
    """
    su, near_u = _slope(w_left, w, w_right)
    sv, near_v = _slope(w_up, w, w_down)
    mz = (w - su * u) - sv * v  # w - x fx w_u - y fy w_v, with x fx = u - cx
    mu = su * fx
    mv = sv * fy
    return w * w, (mz * mz + mu * mu + mv * mv) * r2 * scale, near_u & near_v


@kernel
def _grids(H, W, fx, fy, cx, cy):
    """Per column u - cx and (u - cx)^2 / fx^2, per row v - cy and (v - cy)^2 / fy^2 (float64)."""
    du = np.arange(W) - cx
    dv = np.arange(H) - cy
    return du, (du / fx) * (du / fx), dv, (dv / fy) * (dv / fy)


@kernel
def _sensor_kernel(z, w, zz, fx, fy, cx, cy, min_range, max_range, jump, cos2, dropout, fly, noise, axial, tof1,
                   quantum, disparity_q, fb, uniform, flying, bias, out, ok, edge, c2, zfar):
    """The sensor model's per-pixel work on a depth image `z` (`w`, `zz` from :func:`_pad`).

    First pass: whether each pixel is measurable into `ok` (in range, no jump above `jump` to a
    4-neighbour (inf: test off), not grazing (squared incidence cosine below `cos2`; 0: off)),
    whether it is measurable but for an edge into `edge`, its squared incidence cosine into
    `c2` and its deepest 4-neighbour's depth into `zfar`. Second pass, if `out` has rows (it holds
    standard normals on entry, the measured depth on exit): depth + bias (if `bias` has rows) +
    sigma * normal, sigma from `noise` and the axial model (0 none, 1 tof with scale `tof1`, 2
    Nguyen 2012, less the quantisation's variance); edge pixels with `flying` < `fly` kept, mixed
    towards `zfar` by `flying` / `fly`; quantised (if `disparity_q` > 0 the disparity fb / z to
    multiples of `disparity_q` pixels, then if `quantum` > 0 the depth to multiples of `quantum`
    metres, as :func:`dequantise`); 0 where not measurable, dropped (`uniform`
    < `dropout`) or not in front of the camera, and `ok` then says where it is kept.
    """
    H, W = z.shape
    du, au, dv, av = _grids(H, W, fx, fy, cx, cy)
    u32 = du.astype(np.float32)
    fx32, fy32 = np.float32(fx), np.float32(fy)
    for i in range(H):
        v, av_i = np.float32(dv[i]), av[i]
        zr, zz_up, zz_row, zz_down = z[i], zz[i], zz[i + 1], zz[i + 2]
        w_up, w_row, w_down = w[i], w[i + 1], w[i + 2]
        for j in range(W):
            d = zr[j]
            c = zz_row[j + 1]
            a, b, e, f = zz_row[j], zz_row[j + 2], zz_up[j + 1], zz_down[j + 1]
            step = (abs(c - a) > jump) | (abs(b - c) > jump) | (abs(c - e) > jump) | (abs(f - c) > jump)
            r2 = np.float32(1.0 + au[j] + av_i)
            w2, den, near = _incidence_terms(
                w_row[j + 1], w_row[j], w_row[j + 2], w_up[j + 1], w_down[j + 1], u32[j], v, r2, fx32, fy32, _ONE
            )
            cc = w2 / den if near else _ONE
            seen = (d > _ZERO) & (d >= min_range) & (d <= max_range) & (not (near & (w2 < den * cos2)))
            ok[i, j] = seen & (not step)
            edge[i, j] = seen & step
            c2[i, j] = min(cc, _ONE)
            far = _ZERO
            for n in (a, b, e, f):  # nan outside the image, _FAR_Z + 0 where nothing: neither counts
                if n < _FAR_Z and n > far:
                    far = n
            zfar[i, j] = far
    if out.shape[0] == 0:
        return
    has_bias, drop = bias.shape[0] > 0, uniform.shape[0] > 0
    has_fly = flying.shape[0] > 0
    half_pi = np.float32(np.pi / 2)
    twelfth = np.float32(1.0 / 12.0)
    for i in range(H):
        for j in range(W):
            d = z[i, j]
            s2 = _ZERO
            if axial == 1:
                s = tof1 * d * d / max(np.sqrt(c2[i, j]), np.float32(0.05))
                s2 = s * s
            elif axial == 2:
                th = np.arccos(np.sqrt(c2[i, j]))
                dz = max(d, np.float32(1e-3))
                s = (np.float32(0.0012) + np.float32(0.0019) * (dz - np.float32(0.4)) ** 2
                     + np.float32(0.0001) / np.sqrt(dz) * th * th / max(half_pi - th, np.float32(1e-3)) ** 2)
                s2 = s * s
            if axial > 0:
                q2 = _ZERO
                if quantum > 0:
                    q2 += np.float32(quantum * quantum)
                if disparity_q > 0:
                    qd = np.float32(d * d * disparity_q / fb)
                    q2 += qd * qd
                s2 = max(s2 - q2 * twelfth, _ZERO)
            sigma = np.sqrt(noise * noise + s2) if axial > 0 else noise
            m = out[i, j] * sigma + d
            if has_bias:
                m = m + bias[i, j]
            keep = ok[i, j]
            if has_fly and edge[i, j] and flying[i, j] < fly and zfar[i, j] > _ZERO:
                m = m + (flying[i, j] / fly) * (zfar[i, j] - d)
                keep = (m >= min_range) & (m <= max_range)
            if disparity_q > 0 and m > _ZERO:
                disparity = np.rint(fb / m / disparity_q) * disparity_q
                m = np.float32(fb / disparity) if disparity > 0 else _ZERO
            if quantum > 0:
                m = np.float32(np.rint(m / np.float32(quantum)) * quantum)
            if drop:
                keep = keep & (uniform[i, j] >= dropout)
            keep = keep & (m > _ZERO)
            out[i, j] = m if keep else _ZERO
            ok[i, j] = keep


@kernel
def _lateral_kernel(z, nv, nu, c, model, sigma_px, discontinuity, out):
    """Lateral jitter: `out` = `z` read at the pixel displaced by sigma_L * (`nv`, `nu`) (rounded),
    where the displaced pixel lies across a discontinuity (a jump above `discontinuity`, or one of
    the two shows nothing); sigma_L is `sigma_px` (`model` 1) or Nguyen 2012's 0.8 + 0.035 theta /
    (pi/2 - theta) with theta = arccos(`c`) (`model` 2)."""
    H, W = z.shape
    half_pi = np.float32(np.pi / 2)
    for i in range(H):
        for j in range(W):
            s = sigma_px
            if model == 2:
                th = np.arccos(min(c[i, j], _ONE))
                s = np.float32(0.8) + np.float32(0.035) * th / max(half_pi - th, np.float32(1e-3))
            ii = min(max(int(np.rint(i + s * nv[i, j])), 0), H - 1)
            jj = min(max(int(np.rint(j + s * nu[i, j])), 0), W - 1)
            d, o = z[i, j], z[ii, jj]
            across = (abs(o - d) > discontinuity) | ((d > _ZERO) != (o > _ZERO))
            out[i, j] = o if across else d


@kernel
def _multipath_kernel(z, r, peak, depth_scale, out):
    """Multipath bias (deeper) per pixel: `peak` * clip((z - mean) / `depth_scale`, 0, 1), mean the
    mean depth of the pixels that see something within `r` pixels (a box window, from integral
    images); 0 where nothing is seen."""
    H, W = z.shape
    S = np.zeros((H + 1, W + 1))
    N = np.zeros((H + 1, W + 1))
    for i in range(H):
        rs, rn = 0.0, 0.0
        for j in range(W):
            d = z[i, j]
            rs += d
            rn += 1.0 if d > 0 else 0.0
            S[i + 1, j + 1] = S[i, j + 1] + rs
            N[i + 1, j + 1] = N[i, j + 1] + rn
    for i in range(H):
        i0, i1 = max(i - r, 0), min(i + r + 1, H)
        for j in range(W):
            d = z[i, j]
            if d <= 0:
                out[i, j] = _ZERO
                continue
            j0, j1 = max(j - r, 0), min(j + r + 1, W)
            s = S[i1, j1] - S[i0, j1] - S[i1, j0] + S[i0, j0]
            n = N[i1, j1] - N[i0, j1] - N[i1, j0] + N[i0, j0]
            excess = (d - s / n) / depth_scale
            out[i, j] = np.float32(peak * min(max(excess, 0.0), 1.0))


@kernel
def _incidence_cos_kernel(z, w, fx, fy, cx, cy, c):
    H, W = z.shape
    du, au, dv, av = _grids(H, W, fx, fy, cx, cy)
    for i in range(H):
        for j in range(W):
            r2 = np.float32(1.0 + au[j] + av[i])
            w2, den, near = _incidence_terms(
                w[i + 1, j + 1],
                w[i + 1, j],
                w[i + 1, j + 2],
                w[i, j + 1],
                w[i + 2, j + 1],
                np.float32(du[j]),
                np.float32(dv[i]),
                r2,
                np.float32(fx),
                np.float32(fy),
                _ONE,
            )
            c[i, j] = np.sqrt(w2 / den) if near and z[i, j] > _ZERO else _ONE


def _incidence_cos(z: np.ndarray, K: np.ndarray) -> np.ndarray:
    """|cos| of the angle between viewing ray and surface normal per pixel, shape (H, W).

    1 where a pixel shows nothing or has no neighbour that shows something in a direction
    (not grazing); see :func:`_incidence_terms`.
    """
    z = _image(z, "_incidence_cos")
    ws = _workspace(z.shape)
    _pad(z, ws.w, ws.zz)
    c = np.empty(z.shape, dtype=np.float32)
    _incidence_cos_kernel(z, ws.w, *_intrinsics(K), c)
    return c


@kernel
def quantise_on_grid(depth, quantum_m, out) -> bool:
    """Depth as uint16 counts of ``quantum_m`` when it lies on that grid, in one pass.

    Per value, in C order: c = rint(float64(depth) / quantum_m); every c must lie in [0, 65535]
    and float32(c * quantum_m) equal the depth (what :func:`benchmark.camera.sensor.dequantise`
    gives back); then ``out = c``. The arithmetic of
    :func:`benchmark.camera.episode_file.quantise_depth`'s NumPy path, without its five
    video-sized float64 temporaries.

    Args:
        depth: Depth, any shape, C-contiguous float32 [m].
        quantum_m: The quantum [m].
        out: uint16, the shape of ``depth``, written (partly, when it returns False).

    Returns:
        Whether every value was on the grid and in range (False: ``out`` is not the answer).
    """
    d = depth.ravel()
    o = out.ravel()
    for i in range(d.size):
        c = np.rint(np.float64(d[i]) / quantum_m)
        if not (c >= 0.0 and c <= 65535.0):
            return False
        if np.float32(c * quantum_m) != d[i]:
            return False
        o[i] = np.uint16(c)
    return True
