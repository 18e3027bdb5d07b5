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
        ok = (z > 0) & (z >= self.min_range_m) & (z <= self.max_range_m)
        if self.edge_jump_m is not None:
            ok &= ~_edges(z, self.edge_jump_m)
        if self.grazing_deg is not None:
            z2, den = _incidence_terms(z, K)  # cos^2 = z2 / den; nan den: no neighbour, not grazing
            ok &= ~(z2 < np.float32(np.cos(np.deg2rad(self.grazing_deg)) ** 2) * den)
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
        ok = self.measurable(z, K)
        out = rng.standard_normal(z.shape, dtype=np.float32)
        if self.dropout > 0:
            ok &= rng.random(z.shape, dtype=np.float32) >= self.dropout
        out *= self.sigma(z).astype(np.float32) if self.noise_quad_per_m > 0 else np.float32(self.noise_m)
        out += z
        if self.quantum_m is not None:
            out = dequantise(np.rint(out / np.float32(self.quantum_m)), self.quantum_m)
        ok &= out > 0
        out[~ok] = 0.0
        return out


def quantise(depth_m: np.ndarray, quantum_m: float) -> np.ndarray:
    """Rounds depth to multiples of `quantum_m`; float32, bit-identical to :func:`dequantise`."""
    return dequantise(np.rint(np.asarray(depth_m, dtype=np.float64) / quantum_m).astype(np.int64), quantum_m)


def dequantise(counts: np.ndarray, quantum_m: float) -> np.ndarray:
    """Depth in metres (float32) from integer multiples of `quantum_m`."""
    return (np.asarray(counts, dtype=np.float64) * quantum_m).astype(np.float32)


def _edges(z: np.ndarray, jump_m: float) -> np.ndarray:
    """Pixels whose depth differs from a 4-neighbour's by more than jump_m (nothing = infinitely far)."""
    zz = np.where(z > 0, z, np.inf)
    edge = np.zeros(z.shape, dtype=bool)
    with np.errstate(invalid="ignore"):
        dx = ~(np.abs(np.diff(zz, axis=1)) <= jump_m)  # inf - inf is nan: both empty is not an edge
        dy = ~(np.abs(np.diff(zz, axis=0)) <= jump_m)
    dx &= np.isfinite(zz[:, 1:]) | np.isfinite(zz[:, :-1])
    dy &= np.isfinite(zz[1:, :]) | np.isfinite(zz[:-1, :])
    edge[:, 1:] |= dx
    edge[:, :-1] |= dx
    edge[1:, :] |= dy
    edge[:-1, :] |= dy
    return edge & (z > 0)


def _incidence_cos(z: np.ndarray, K: np.ndarray) -> np.ndarray:
    """|cos| of the angle between viewing ray and surface normal per pixel, shape (H, W).

    1 where a pixel has no neighbour that shows something (not grazing); see
    :func:`_incidence_terms`.
    """
    z2, den = _incidence_terms(z, K)
    with np.errstate(invalid="ignore", divide="ignore"):
        c = np.sqrt(z2 / den)
    c[~np.isfinite(c)] = 1.0
    return c


def _incidence_terms(z: np.ndarray, K: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(z^2, |m|^2 |r|^2)`` per pixel, whose ratio is the squared incidence cosine, (H, W) each.

    With P(u, v) = z r, r = ((u - cx) / fx, (v - cy) / fy, 1), the normal dP/du x dP/dv is
    parallel to m = (-fx z_u, -fy z_v, fx x z_u + fy y z_v + z) with m . r = z, so
    cos = z / (|m| |r|). The depth derivatives come from one-sided differences of the inverse
    depth w = 1/z (affine in (u, v) on a plane, so exact there): z_u = -z^2 w_u, taken towards
    the neighbour of closer depth (so they do not straddle an edge). The second term is nan
    where a pixel shows nothing or has no neighbour in a direction that shows something.
    """
    H, W = z.shape
    z = np.asarray(z, dtype=np.float32)
    with np.errstate(divide="ignore"):
        w = np.where(z > 0, np.float32(1) / z, np.float32(np.nan))

    def slope(axis):
        nan = np.float32(np.nan)
        d = np.diff(w, axis=axis, prepend=nan, append=nan)  # d[i] = w[i] - w[i-1], nan at the ends
        a = np.fmin(np.abs(d), np.float32(np.inf))  # nan -> inf
        n = w.shape[axis]
        fwd, bwd = [slice(None)] * 2, [slice(None)] * 2
        fwd[axis], bwd[axis] = slice(1, n + 1), slice(0, n)
        fwd, bwd = tuple(fwd), tuple(bwd)
        return np.where(a[fwd] <= a[bwd], d[fwd], d[bwd])

    x = ((np.arange(W) - K[0, 2]) / K[0, 0]).astype(np.float32)[None, :]
    y = ((np.arange(H) - K[1, 2]) / K[1, 1]).astype(np.float32)[:, None]
    z2 = z * z
    mx = slope(1)
    mx *= z2 * np.float32(K[0, 0])  # -fx z_u = fx z^2 w_u
    my = slope(0)
    my *= z2 * np.float32(K[1, 1])
    mz = z - x * mx - y * my
    return z2, (mx * mx + my * my + mz * mz) * (x * x + y * y + 1)
