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
"""

from __future__ import annotations

import threading
from dataclasses import dataclass

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
        z = np.asarray(depth_m, dtype=np.float32)
        if z.ndim != 2:
            raise BenchmarkError(f"measurable takes one depth image of shape (H, W), got shape {z.shape}")
        return self._measurable(z, K, _workspace(z.shape)).copy()

    def _measurable(self, z: np.ndarray, K: np.ndarray, ws: "_Workspace") -> np.ndarray:
        """:meth:`measurable` of a float32 (H, W) image into the workspace's ``ok`` mask."""
        ok = np.greater(z, 0, out=ws.ok)
        if self.min_range_m > 0:
            ok &= np.greater_equal(z, np.float32(self.min_range_m), out=ws.b1)
        if np.isfinite(self.max_range_m):
            ok &= np.less_equal(z, np.float32(self.max_range_m), out=ws.b1)
        if self.edge_jump_m is not None:
            ok &= np.logical_not(_edges(z, self.edge_jump_m, ws), out=ws.b1)
        if self.grazing_deg is not None:
            cos2 = np.cos(np.deg2rad(self.grazing_deg)) ** 2
            w2, den, near = _incidence_terms(z, K, ws, scale=cos2)  # cos^2 = w2 / den
            grazing = np.less(w2, den, out=ws.b1)
            grazing &= near  # no neighbour that shows something: not grazing
            ok &= np.logical_not(grazing, out=grazing)
        return ok

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
        z = np.asarray(depth_m, dtype=np.float32)
        if z.ndim != 2:
            raise BenchmarkError(f"measure takes one depth image of shape (H, W), got shape {z.shape}")
        ws = _workspace(z.shape)
        ok = self._measurable(z, K, ws)
        out = np.empty(z.shape, dtype=np.float32)
        rng.standard_normal(dtype=np.float32, out=out)
        if self.dropout > 0:
            u = rng.random(dtype=np.float32, out=ws.t1)
            ok &= np.greater_equal(u, np.float32(self.dropout), out=ws.b1)
        if self.noise_quad_per_m > 0:
            sigma = np.multiply(z, z, out=ws.t1)
            sigma *= np.float32(self.noise_quad_per_m)
            sigma += np.float32(self.noise_m)
            out *= sigma
        else:
            out *= np.float32(self.noise_m)
        out += z
        if self.quantum_m is not None:
            out /= np.float32(self.quantum_m)
            np.rint(out, out=out)
            np.multiply(out, self.quantum_m, out=ws.f64, dtype=np.float64)  # as dequantise(out)
            out[...] = ws.f64
        ok &= np.greater(out, 0, out=ws.b1)
        out *= ok  # out > 0 where ok holds: no negative zeros
        return out


def quantise(depth_m: np.ndarray, quantum_m: float) -> np.ndarray:
    """Rounds depth to multiples of `quantum_m`; float32, bit-identical to :func:`dequantise`."""
    return dequantise(np.rint(np.asarray(depth_m, dtype=np.float64) / quantum_m).astype(np.int64), quantum_m)


def dequantise(counts: np.ndarray, quantum_m: float) -> np.ndarray:
    """Depth in metres (float32) from integer multiples of `quantum_m`."""
    return (np.asarray(counts, dtype=np.float64) * quantum_m).astype(np.float32)


class _Workspace:
    """Scratch arrays for one image shape, reused across frames (fresh large arrays per frame
    cost more in page faults than the arithmetic on them)."""

    def __init__(self, shape: tuple[int, int]):
        H, W = shape
        f32 = np.float32
        self.ok, self.b1, self.b2, self.b3, self.near = (np.empty((H, W), dtype=bool) for _ in range(5))
        self.t1, self.t2, self.t3, self.t4 = (np.empty((H, W), dtype=f32) for _ in range(4))
        self.f64 = np.empty((H, W), dtype=np.float64)
        self.K = None  # intrinsics of the pixel grids below
        self.u, self.v, self.r2 = (np.empty((H, W), dtype=f32) for _ in range(3))
        self.pad_u = np.full((H, W + 2), _FAR_W, dtype=f32)  # inverse depth, nothing outside the image
        self.pad_v = np.full((H + 2, W), _FAR_W, dtype=f32)
        self.d_u, self.a_u = np.empty((H, W + 1), dtype=f32), np.empty((H, W + 1), dtype=f32)
        self.d_v, self.a_v = np.empty((H + 1, W), dtype=f32), np.empty((H + 1, W), dtype=f32)
        self.step_u, self.step_v = np.empty((H, W - 1), dtype=bool), np.empty((H - 1, W), dtype=bool)
        self.jump_u, self.jump_v = np.empty((H, W - 1), dtype=f32), np.empty((H - 1, W), dtype=f32)

    def grids(self, K: np.ndarray):
        """``(u - cx, v - cy, |r|^2)`` per pixel for intrinsics K, (H, W) float32 each."""
        K = np.asarray(K, dtype=np.float64)
        if self.K is None or not np.array_equal(self.K, K):
            H, W = self.u.shape
            u, v = np.arange(W) - K[0, 2], np.arange(H) - K[1, 2]
            self.u[...] = u[None, :]
            self.v[...] = v[:, None]
            self.r2[...] = 1 + (u[None, :] / K[0, 0]) ** 2 + (v[:, None] / K[1, 1]) ** 2
            self.K = K.copy()
        return self.u, self.v, self.r2


_local = threading.local()


def _workspace(shape: tuple[int, int]) -> _Workspace:
    """This thread's workspace for images of `shape`."""
    spaces = _local.__dict__.setdefault("spaces", {})
    if shape not in spaces:
        if len(spaces) > 4:
            spaces.clear()
        spaces[shape] = _Workspace(shape)
    return spaces[shape]


def _edges(z: np.ndarray, jump_m: float, ws: _Workspace) -> np.ndarray:
    """Pixels whose depth differs from a 4-neighbour's by more than jump_m (nothing = infinitely far).

    Returns the workspace's ``b2`` mask; it may be set on pixels that show nothing.
    """
    empty = np.less_equal(z, 0, out=ws.b2)
    zz = np.multiply(empty, _FAR_Z, out=ws.t1)  # nothing: equal to each other, far from any depth
    zz += z
    jump = np.float32(jump_m)
    edge = ws.b2
    du = np.subtract(zz[:, 1:], zz[:, :-1], out=ws.jump_u)
    step_u = np.greater(np.abs(du, out=du), jump, out=ws.step_u)
    dv = np.subtract(zz[1:], zz[:-1], out=ws.jump_v)
    step_v = np.greater(np.abs(dv, out=dv), jump, out=ws.step_v)
    edge[:, 0] = False
    edge[:, 1:] = step_u
    edge[:, :-1] |= step_u
    edge[1:] |= step_v
    edge[:-1] |= step_v
    return edge


def _incidence_cos(z: np.ndarray, K: np.ndarray) -> np.ndarray:
    """|cos| of the angle between viewing ray and surface normal per pixel, shape (H, W).

    1 where a pixel shows nothing or has no neighbour that shows something in a direction
    (not grazing); see :func:`_incidence_terms`.
    """
    z = np.asarray(z, dtype=np.float32)
    w2, den, near = _incidence_terms(z, K, _workspace(z.shape), scale=1.0)
    c = np.sqrt(w2 / den)
    c[~(near & (z > 0))] = 1.0
    return c


# Stand-ins for "nothing in view" in finite float32 arithmetic (masked numpy operations and
# nan/inf special cases cost more than plain arithmetic on whole images).
_FAR_Z = np.float32(1e10)  # depth, [m]: farther than any edge threshold from any real depth
_NEAR_Z = np.float32(1e-15)  # depths at or below this (incl. 0 = nothing) count as nothing
_FAR_W = np.float32(1) / _NEAR_Z  # inverse depth of nothing, [1/m]


def _incidence_terms(z: np.ndarray, K: np.ndarray, ws: _Workspace, scale: float):
    """``(w^2, scale |m|^2 |r|^2, near)`` per pixel, (H, W) each, in the workspace.

    The ratio of the first two terms is the squared incidence cosine over `scale`. With
    P(u, v) = z r, r = ((u - cx) / fx, (v - cy) / fy, 1) and the inverse depth w = 1/z, the
    normal dP/du x dP/dv is parallel to m = (fx w_u, fy w_v, w - x fx w_u - y fy w_v) (the
    normal z^2 (-fx z_u, -fy z_v, fx x z_u + fy y z_v + z) with z_u = -z^2 w_u, over z^2),
    with m . r = w, so cos = w / (|m| |r|). The inverse depth is affine in (u, v) on a plane,
    so its one-sided differences are exact there; each is taken towards the neighbour whose
    inverse depth is closer (so they do not straddle an edge). ``near`` is False where a pixel
    has, in one direction, no neighbour that shows something (the terms are meaningless there).
    """
    w = ws.pad_v[1:-1]  # contiguous rows; the padding rows stay _FAR_W
    np.maximum(z, _NEAR_Z, out=w)
    np.divide(np.float32(1), w, out=w)  # nothing in view: _FAR_W
    ws.pad_u[:, 1:-1] = w

    def slope(d, a, pad, axis, s, near):
        """One-sided difference of w along `axis` towards the closer neighbour into s; near: one exists."""
        if axis == 1:
            np.subtract(pad[:, 1:], pad[:, :-1], out=d)  # d[i] = w[i] - w[i-1]
            fwd, bwd = (slice(None), slice(1, None)), (slice(None), slice(0, -1))
        else:
            np.subtract(pad[1:], pad[:-1], out=d)
            fwd, bwd = (slice(1, None), slice(None)), (slice(0, -1), slice(None))
        np.abs(d, out=a)
        use_fwd = np.less_equal(a[fwd], a[bwd], out=ws.b2)
        np.multiply(d[fwd], use_fwd, out=s)
        s += np.multiply(d[bwd], np.logical_not(use_fwd, out=ws.b3), out=ws.t4)  # exact: one is 0
        np.less(np.minimum(a[fwd], a[bwd], out=ws.t4), np.float32(0.5) * _FAR_W, out=near)
        return s

    near = ws.near
    su = slope(ws.d_u, ws.a_u, ws.pad_u, 1, ws.t1, near)
    sv = slope(ws.d_v, ws.a_v, ws.pad_v, 0, ws.t2, ws.b1)
    near &= ws.b1
    u, v, r2 = ws.grids(K)
    mz = np.multiply(su, u, out=ws.t3)
    np.subtract(w, mz, out=mz)
    mz -= np.multiply(sv, v, out=ws.t4)  # w - x fx w_u - y fy w_v, with x fx = u - cx
    su *= np.float32(K[0, 0])
    sv *= np.float32(K[1, 1])
    mz *= mz
    su *= su
    sv *= sv
    mz += su
    mz += sv
    mz *= r2
    if scale != 1:
        mz *= np.float32(scale)
    w2 = np.multiply(w, w, out=ws.t1)
    return w2, mz, near
