"""Sensor model: turns exact rendered depth into what a DS325-like depth camera measures.

Per pixel with exact depth z (0 = nothing in view), in this order:

1. Missing pixels (depth 0), each effect switchable:
   - range limits: z outside [min_range_m, max_range_m] (the DS325 measures 0.15-1.0 m);
   - depth discontinuities: a 4-neighbour's depth differs by more than ``edge_jump_m`` (or
     shows nothing): time-of-flight pixels that straddle an edge mix two returns ("flying
     pixels") and the camera's confidence filter drops them, on both sides of the edge;
   - grazing angles: the angle between the viewing ray and the surface normal exceeds
     ``grazing_deg`` (too little light returns);
   - random dropout of a fraction ``dropout`` of the pixels.
2. Zero-mean Gaussian noise along the optical axis with standard deviation
   sigma(z) = noise_m + noise_quad_per_m * z**2 (the second term is the quadratic growth of
   time-of-flight and structured-light noise with depth; off by default, so that ``--noise``
   is exactly the standard deviation).
3. Quantisation to multiples of ``quantum_m`` (the DS325 reports whole millimetres).

Noise, quantisation and dropout draw from one ``np.random.Generator`` (the scenario's "depth"
stream): a standard normal per pixel per frame (and a uniform per pixel when dropout is on), so
the same scenario gives bit-identical frames.

Everything but the random draws runs in one compiled pass over the pixels (numba; float32
arithmetic in a fixed order, no fast-math), several times faster than the same steps as
whole-image NumPy operations, which cost a memory pass each.
"""

from __future__ import annotations

import threading
from dataclasses import dataclass

import numba
import numpy as np

from benchmark.errors import BenchmarkError


@dataclass(frozen=True)
class SensorModel:
    """Settings of the depth sensor model (defaults: a DS325 with ``noise_m`` of noise).

    Attributes:
        noise_m: Standard deviation of the Gaussian depth noise at zero depth, [m] (>= 0).
        noise_quad_per_m: Depth-dependent part of the standard deviation, sigma grows by
            ``noise_quad_per_m * z**2``, [1/m] (>= 0; 0 = off, the default).
        quantum_m: Depth resolution, [m]; None = no quantisation. Default 1 mm.
        min_range_m: Nearest measured depth, [m]. Default 0.15 m.
        max_range_m: Farthest measured depth, [m] (may be ``inf``). Default 1.0 m.
        edge_jump_m: Depth jump to a 4-neighbour above which a pixel is dropped, [m]; None = off.
            Default 20 mm.
        grazing_deg: Largest angle between viewing ray and surface normal still measured, [deg];
            None = off. Default 80 degrees.
        dropout: Fraction of pixels dropped at random, in [0, 1). Default 0.
    """

    noise_m: float = 0.0
    noise_quad_per_m: float = 0.0
    quantum_m: float | None = 0.001
    min_range_m: float = 0.15
    max_range_m: float = 1.0
    edge_jump_m: float | None = 0.02
    grazing_deg: float | None = 80.0
    dropout: float = 0.0

    def __post_init__(self):
        def bad(name, accepted):
            raise BenchmarkError(f"SensorModel.{name} must be {accepted}, got {getattr(self, name)!r}")

        for name in ("noise_m", "noise_quad_per_m", "min_range_m"):
            v = getattr(self, name)
            if not (np.isfinite(v) and v >= 0):
                bad(name, "a finite number >= 0")
        if not (self.max_range_m > self.min_range_m):
            bad("max_range_m", f"> min_range_m = {self.min_range_m}")
        if self.quantum_m is not None and not (np.isfinite(self.quantum_m) and self.quantum_m > 0):
            bad("quantum_m", "None (off) or a finite number > 0")
        if self.edge_jump_m is not None and not (np.isfinite(self.edge_jump_m) and self.edge_jump_m > 0):
            bad("edge_jump_m", "None (off) or a finite number > 0")
        if self.grazing_deg is not None and not (0 < self.grazing_deg < 90):
            bad("grazing_deg", "None (off) or an angle in (0, 90) degrees")
        if not (0 <= self.dropout < 1):
            bad("dropout", "a fraction in [0, 1)")

    @classmethod
    def ideal(cls) -> "SensorModel":
        """A perfect sensor: no noise, no quantisation, no missing pixels, unlimited range."""
        return cls(quantum_m=None, min_range_m=0.0, max_range_m=np.inf, edge_jump_m=None, grazing_deg=None)

    def sigma(self, depth_m: np.ndarray) -> np.ndarray:
        """Standard deviation of the noise at the given depth, same shape, [m]."""
        return self.noise_m + self.noise_quad_per_m * np.asarray(depth_m) ** 2

    def measurable(self, depth_m: np.ndarray, K: np.ndarray) -> np.ndarray:
        """Which pixels of an exact depth image the sensor measures (effects 1 except dropout).

        Args:
            depth_m: Exact depth, shape (H, W), [m]; 0 = nothing in view.
            K: OpenCV intrinsics, shape (3, 3).

        Returns:
            Boolean mask, shape (H, W).
        """
        z = _image(depth_m, "measurable")
        ws = _workspace(z.shape)
        _pad(z, ws.w, ws.zz)
        ok = np.empty(z.shape, dtype=bool)
        none = ws.no_out
        _sensor_kernel(z, ws.w, ws.zz, *_intrinsics(K), *self._mask_settings(), *self._noise_settings(), none, none, ok)
        return ok

    def _mask_settings(self) -> tuple:
        """Settings of the missing-pixel tests in float32: range limits, edge jump (inf = off)
        and squared cosine of the grazing angle (0 = off)."""
        return (
            np.float32(self.min_range_m),
            np.float32(self.max_range_m),
            np.float32(np.inf if self.edge_jump_m is None else self.edge_jump_m),
            np.float32(0 if self.grazing_deg is None else np.cos(np.deg2rad(self.grazing_deg)) ** 2),
        )

    def _noise_settings(self) -> tuple:
        """Dropout, noise and quantum in float32 (quantum -1 = off), and the quantum in float64."""
        quantum = -1.0 if self.quantum_m is None else float(self.quantum_m)
        return (
            np.float32(self.dropout),
            np.float32(self.noise_m),
            np.float32(self.noise_quad_per_m),
            np.float32(quantum),
            quantum,
        )

    def measure(self, depth_m: np.ndarray, K: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """Simulates one measured frame.

        Args:
            depth_m: Exact depth, shape (H, W), [m]; 0 = nothing in view.
            K: OpenCV intrinsics, shape (3, 3).
            rng: The generator of the depth stream; advanced by one (H, W) normal draw (and one
                (H, W) uniform draw if ``dropout > 0``) per call, whatever the image shows.

        Returns:
            Measured depth, shape (H, W), float32 metres; 0 = no measurement.
        """
        z = _image(depth_m, "measure")
        ws = _workspace(z.shape)
        out = np.empty(z.shape, dtype=np.float32)
        rng.standard_normal(dtype=np.float32, out=out)
        # without dropout the kernel reads no uniforms; z stands in (not out: aliasing slows it)
        uniform = rng.random(dtype=np.float32, out=np.empty(z.shape, dtype=np.float32)) if self.dropout > 0 else z
        _pad(z, ws.w, ws.zz)
        _sensor_kernel(z, ws.w, ws.zz, *_intrinsics(K), *self._mask_settings(), *self._noise_settings(), uniform, out, ws.ok)
        return out


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


def quantise(depth_m: np.ndarray, quantum_m: float) -> np.ndarray:
    """Rounds depth to multiples of `quantum_m`; float32, bit-identical to :func:`dequantise`."""
    return dequantise(np.rint(np.asarray(depth_m, dtype=np.float64) / quantum_m).astype(np.int64), quantum_m)


def dequantise(counts: np.ndarray, quantum_m: float) -> np.ndarray:
    """Depth in metres (float32) from integer multiples of `quantum_m`."""
    return (np.asarray(counts, dtype=np.float64) * quantum_m).astype(np.float32)


# Stand-ins for "nothing in view" in finite float32 arithmetic (no nan/inf special cases).
_FAR_Z = np.float32(1e10)  # depth, [m]: farther than any edge threshold from any real depth
_NEAR_Z = np.float32(1e-15)  # depths at or below this (incl. 0 = nothing) count as nothing
_FAR_W = np.float32(1) / _NEAR_Z  # inverse depth of nothing, [1/m]
_HALF_FAR_W = np.float32(0.5) * _FAR_W
_ONE = np.float32(1)
_ZERO = np.float32(0)

_jit = numba.njit(cache=True, nogil=True, error_model="numpy")
_jit_inline = numba.njit(cache=True, nogil=True, error_model="numpy", inline="always")


class _Workspace:
    """Padded scratch images for one image shape, reused across frames (fresh large arrays per
    frame cost more in page faults than the arithmetic on them)."""

    def __init__(self, shape: tuple[int, int]):
        H, W = shape
        self.w = np.empty((H + 2, W + 2), dtype=np.float32)  # inverse depth, _FAR_W around
        self.zz = np.empty((H + 2, W + 2), dtype=np.float32)  # depth for the edge test, nan around
        self.ok = np.empty((H, W), dtype=bool)
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


@_jit
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


@_jit_inline
def _slope(w_before, w, w_after):
    """One-sided difference of the inverse depth towards the neighbour whose inverse depth is
    closer, and whether a neighbour that shows something exists in this direction."""
    before = w - w_before
    after = w_after - w
    a_before, a_after = abs(before), abs(after)
    return (after if a_after <= a_before else before), min(a_after, a_before) < _HALF_FAR_W


@_jit_inline
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


@_jit
def _grids(H, W, fx, fy, cx, cy):
    """Per column u - cx and (u - cx)^2 / fx^2, per row v - cy and (v - cy)^2 / fy^2 (float64)."""
    du = np.arange(W) - cx
    dv = np.arange(H) - cy
    return du, (du / fx) * (du / fx), dv, (dv / fy) * (dv / fy)


@_jit
def _sensor_kernel(
    z, w, zz, fx, fy, cx, cy, min_range, max_range, jump, cos2, dropout, noise, noise_quad, quantum, quantum64, uniform, out, ok
):
    """The sensor model's per-pixel work on a depth image `z` (`w`, `zz` from :func:`_pad`).

    Writes whether each pixel is measurable into `ok`: in range, no jump above `jump` to a
    4-neighbour (inf: test off), not grazing (squared incidence cosine below `cos2`; 0: test
    off). If `out` has rows, it holds standard normals on entry and the measured depth on exit:
    per pixel in float32, depth + sigma(depth) * normal with sigma = noise (+ noise_quad depth^2
    if noise_quad > 0), rounded to a multiple of `quantum` if it is > 0 (the count times
    `quantum64` in float64, then to float32, as :func:`dequantise`), and 0 where the pixel is
    not measurable, dropped (if dropout > 0: `uniform` < dropout) or not in front of the camera;
    `ok` then says where it is kept. The inner loops are branch-free, so that they vectorise (and
    `uniform` must not be `out`: aliased arrays stop that).
    """
    H, W = z.shape
    du, au, dv, av = _grids(H, W, fx, fy, cx, cy)
    u32 = du.astype(np.float32)
    fx32, fy32 = np.float32(fx), np.float32(fy)
    drop, quadratic, quantise = dropout > _ZERO, noise_quad > _ZERO, quantum > _ZERO
    for i in range(H):
        v, av_i = np.float32(dv[i]), av[i]
        zr, zz_up, zz_row, zz_down = z[i], zz[i], zz[i + 1], zz[i + 2]
        w_up, w_row, w_down = w[i], w[i + 1], w[i + 2]
        okr = ok[i]
        for j in range(W):
            d = zr[j]
            c = zz_row[j + 1]
            step = (
                (abs(c - zz_row[j]) > jump)
                | (abs(zz_row[j + 2] - c) > jump)
                | (abs(c - zz_up[j + 1]) > jump)
                | (abs(zz_down[j + 1] - c) > jump)
            )
            r2 = np.float32(1.0 + au[j] + av_i)
            w2, den, near = _incidence_terms(
                w_row[j + 1], w_row[j], w_row[j + 2], w_up[j + 1], w_down[j + 1], u32[j], v, r2, fx32, fy32, cos2
            )
            okr[j] = (d > _ZERO) & (d >= min_range) & (d <= max_range) & (not step) & (not (near & (w2 < den)))
        if out.shape[0] > 0:
            outr, ur = out[i], uniform[i]
            for j in range(W):
                d = zr[j]
                sigma = (d * d * noise_quad + noise) if quadratic else noise
                m = outr[j] * sigma + d
                rounded = np.float32(np.rint(m / quantum) * quantum64)
                m = rounded if quantise else m
                keep = okr[j] & ((ur[j] >= dropout) | (not drop)) & (m > _ZERO)
                outr[j] = m * (_ONE if keep else _ZERO)  # kept: m > 0, no negative zeros
                okr[j] = keep


@_jit
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
