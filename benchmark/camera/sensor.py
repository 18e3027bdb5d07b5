"""Sensor model: turns exact rendered depth into what a depth camera measures.

Per pixel with exact depth z (0 = nothing in view), in this order:

1. Lateral jitter (``lateral`` "constant" or "nguyen2012"): each pixel reads the exact depth at a
   point displaced by a Gaussian offset of ``sigma_L`` pixels per image axis (rounded to the
   nearest pixel), where that point lies across a depth discontinuity (a jump above
   ``discontinuity_m`` or nothing in view); on a continuous surface the depth stays. Silhouettes
   and the outlines of fingers on the box jitter; flat faces do not.
2. Multipath (``multipath_m`` > 0): light that reaches a surface via a nearby, closer surface
   (the box beside the table, a finger on the box) travels farther, so time-of-flight reads
   deeper at concave junctions. The bias is ``multipath_m * clip((z - mean) / multipath_depth_m,
   0, 1)``, with ``mean`` the mean depth of the pixels that see something within
   ``multipath_window_px`` pixels (a pixel deeper than its surroundings sits in a concave
   junction).
3. Missing pixels (depth 0), each effect switchable:
   - range limits: z outside [min_range_m, max_range_m];
   - depth discontinuities: a 4-neighbour's depth differs by more than ``edge_jump_m`` (or
     shows nothing): the camera's confidence filter drops them, on both sides of the edge;
     a fraction ``flying_frac`` of them survives as *flying pixels* with a depth between theirs
     and their deepest neighbour's (uniformly mixed);
   - grazing angles: the angle between the viewing ray and the surface normal exceeds
     ``grazing_deg`` (too little light returns);
   - random dropout of a fraction ``dropout`` of the pixels.
4. Zero-mean Gaussian noise along the optical axis, the sum of two independent parts:
   ``noise_m`` (white noise of the same standard deviation everywhere: the scenario's
   ``--noise``, the paper's synthetic noise levels) and the sensor's own axial noise sigma_s(z,
   theta) (``axial``: "none", "tof" or "nguyen2012", below), of which the part that the
   quantisation already contributes on average is left out, so that the measured depth's spread
   follows sigma_s's published curve: ``sigma = sqrt(noise_m^2 + max(sigma_s^2 - q^2 / 12, 0))``,
   q the local depth step of the quantisation.
5. Quantisation: of the disparity (``disparity_quantum_px`` with ``focal_baseline_px_m`` = focal
   length [px] x baseline [m], a structured-light camera: depth = fb / disparity), then to
   multiples of ``quantum_m`` (whole millimetres, as both cameras report depth).

Axial noise models, theta the angle between viewing ray and surface normal:

* "tof": sigma_s = ``tof_sigma_1m_m`` * z^2 / cos(theta) (z in metres): the range noise of a
  time-of-flight pixel is inversely proportional to the amplitude of the returned light (Lange &
  Seitz 2001, IEEE J. Quantum Electron. 37(3)), which falls with z^2 and with cos(theta) on a
  diffuse surface.
* "nguyen2012": the Kinect v1's measured axial noise (Nguyen, Izadi & Lovell 2012, "Modeling
  Kinect sensor noise for improved 3D reconstruction and tracking", 3DIMPVT):
  sigma_s = 0.0012 + 0.0019 (z - 0.4)^2 + 0.0001 / sqrt(z) * theta^2 / (pi/2 - theta)^2 [m];
  its lateral noise sigma_L = 0.8 + 0.035 theta / (pi/2 - theta) [px] ("nguyen2012" lateral).

Presets by name (:data:`PRESETS`, :func:`sensor_preset`): "ds325" (the paper's camera, the
default), "kinect-v1" and "ideal"; docs/scenarios.md gives their values and sources.

Noise, quantisation, jitter and dropout draw from one ``np.random.Generator`` (the scenario's
"depth" stream), per frame in this order: one standard normal per pixel (axial noise); if
lateral jitter is on, two more (row, then column offsets); if ``dropout`` > 0, one uniform per
pixel; if ``flying_frac`` > 0, one more. The same scenario gives bit-identical frames.

Everything but the random draws runs in compiled passes over the pixels (numba; float32
arithmetic in a fixed order, no fast-math).
"""

from __future__ import annotations

import threading
from dataclasses import dataclass, replace

import numba
import numpy as np

from benchmark.errors import BenchmarkError
from benchmark.world.scenario import SENSORS

AXIAL_MODELS = ("none", "tof", "nguyen2012")
"""Axial noise models (step 4 of the module docstring)."""
LATERAL_MODELS = ("none", "constant", "nguyen2012")
"""Lateral jitter models (step 1)."""


@dataclass(frozen=True)
class SensorModel:
    """Settings of the depth sensor model (defaults: the DS325's range, quantisation and dropouts;
    noise, jitter, multipath and flying pixels off; :func:`sensor_preset` gives the presets).

    Attributes:
        noise_m: Standard deviation of the white Gaussian depth noise, [m] (>= 0).
        axial: The sensor's own axial noise model, one of :data:`AXIAL_MODELS`.
        tof_sigma_1m_m: For ``axial="tof"``: its standard deviation at 1 m, frontal, [m].
        lateral: Lateral jitter model, one of :data:`LATERAL_MODELS`.
        lateral_px: For ``lateral="constant"``: the jitter's standard deviation, [px].
        discontinuity_m: Depth jump that separates two surfaces for the jitter, [m] (> 0).
        multipath_m: Largest multipath bias (deeper), [m]; 0 = off.
        multipath_window_px: Half-width of the window of the multipath's mean depth, [px] (>= 1).
        multipath_depth_m: Depth below the surroundings' mean at which the bias saturates, [m] (> 0).
        flying_frac: Fraction of the edge pixels kept as flying pixels, in [0, 1].
        quantum_m: Depth resolution, [m]; None = no depth quantisation. Default 1 mm.
        disparity_quantum_px: Disparity resolution, [px]; None = off. Applied before ``quantum_m``
            (a structured-light camera's driver reports the depth of a quantised disparity in
            whole millimetres).
        focal_baseline_px_m: Focal length times baseline of a structured-light camera, [px m].
        min_range_m: Nearest measured depth, [m]. Default 0.15 m.
        max_range_m: Farthest measured depth, [m] (may be ``inf``). Default 1.0 m.
        edge_jump_m: Depth jump to a 4-neighbour above which a pixel is dropped, [m]; None = off.
            Default 20 mm.
        grazing_deg: Largest angle between viewing ray and surface normal still measured, [deg];
            None = off. Default 80 degrees.
        dropout: Fraction of pixels dropped at random, in [0, 1). Default 0.
    """

    noise_m: float = 0.0
    axial: str = "none"
    tof_sigma_1m_m: float = 0.0
    lateral: str = "none"
    lateral_px: float = 0.0
    discontinuity_m: float = 0.02
    multipath_m: float = 0.0
    multipath_window_px: int = 5
    multipath_depth_m: float = 0.03
    flying_frac: float = 0.0
    quantum_m: float | None = 0.001
    disparity_quantum_px: float | None = None
    focal_baseline_px_m: float = 0.0
    min_range_m: float = 0.15
    max_range_m: float = 1.0
    edge_jump_m: float | None = 0.02
    grazing_deg: float | None = 80.0
    dropout: float = 0.0

    def __post_init__(self):
        def bad(name, accepted):
            raise BenchmarkError(f"SensorModel.{name} must be {accepted}, got {getattr(self, name)!r}")

        for name in ("noise_m", "tof_sigma_1m_m", "lateral_px", "multipath_m", "min_range_m", "focal_baseline_px_m"):
            v = getattr(self, name)
            if not (np.isfinite(v) and v >= 0):
                bad(name, "a finite number >= 0")
        for name in ("discontinuity_m", "multipath_depth_m"):
            v = getattr(self, name)
            if not (np.isfinite(v) and v > 0):
                bad(name, "a finite number > 0")
        if self.axial not in AXIAL_MODELS:
            bad("axial", f"one of {', '.join(AXIAL_MODELS)}")
        if self.lateral not in LATERAL_MODELS:
            bad("lateral", f"one of {', '.join(LATERAL_MODELS)}")
        w = self.multipath_window_px
        if isinstance(w, bool) or not isinstance(w, (int, np.integer)) or w < 1:
            bad("multipath_window_px", "an integer >= 1")
        if not (0 <= self.flying_frac <= 1):
            bad("flying_frac", "a fraction in [0, 1]")
        if not (self.max_range_m > self.min_range_m):
            bad("max_range_m", f"> min_range_m = {self.min_range_m}")
        if self.quantum_m is not None and not (np.isfinite(self.quantum_m) and self.quantum_m > 0):
            bad("quantum_m", "None (off) or a finite number > 0")
        if self.disparity_quantum_px is not None:
            if not (np.isfinite(self.disparity_quantum_px) and self.disparity_quantum_px > 0):
                bad("disparity_quantum_px", "None (off) or a finite number > 0")
            if not self.focal_baseline_px_m > 0:
                bad("focal_baseline_px_m", "> 0 with a disparity quantum")
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

    def axial_sigma(self, depth_m, theta_rad=0.0) -> np.ndarray:
        """The sensor's own axial noise sigma_s(z, theta) (without ``noise_m``), [m].

        Args:
            depth_m: Depth, any shape, [m].
            theta_rad: Angle between viewing ray and surface normal, broadcastable, [rad].
        """
        z = np.asarray(depth_m, dtype=float)
        th = np.asarray(theta_rad, dtype=float)
        if self.axial == "tof":
            return self.tof_sigma_1m_m * z**2 / np.cos(th)
        if self.axial == "nguyen2012":
            return 0.0012 + 0.0019 * (z - 0.4) ** 2 + 0.0001 / np.sqrt(z) * th**2 / (np.pi / 2 - th) ** 2
        return np.zeros(np.broadcast_shapes(z.shape, th.shape))

    def lateral_sigma(self, theta_rad=0.0) -> np.ndarray:
        """The lateral jitter's standard deviation sigma_L(theta) per image axis, [px]."""
        th = np.asarray(theta_rad, dtype=float)
        if self.lateral == "constant":
            return np.full(th.shape, float(self.lateral_px))
        if self.lateral == "nguyen2012":
            return 0.8 + 0.035 * th / (np.pi / 2 - th)
        return np.zeros(th.shape)

    def quantum_at(self, depth_m) -> np.ndarray:
        """The quantisation's depth step at a depth, [m] (0 without quantisation; the root sum of
        squares of the disparity's and the depth's steps when both are on)."""
        z = np.asarray(depth_m, dtype=float)
        q2 = np.zeros(z.shape)
        if self.quantum_m is not None:
            q2 = q2 + float(self.quantum_m) ** 2
        if self.disparity_quantum_px is not None:
            q2 = q2 + (z**2 * self.disparity_quantum_px / self.focal_baseline_px_m) ** 2
        return np.sqrt(q2)

    def sigma(self, depth_m, theta_rad=0.0) -> np.ndarray:
        """Standard deviation of the Gaussian noise drawn at a depth and angle (step 4), [m]."""
        s = self.axial_sigma(depth_m, theta_rad)
        if self.axial != "none":
            s = np.sqrt(np.maximum(s**2 - self.quantum_at(depth_m) ** 2 / 12.0, 0.0))
        return np.sqrt(self.noise_m**2 + s**2)

    def measurable(self, depth_m: np.ndarray, K: np.ndarray) -> np.ndarray:
        """Which pixels of an exact depth image the sensor measures (step 3 but dropout and
        flying pixels, on the exact depth).

        Args:
            depth_m: Exact depth, shape (H, W), [m]; 0 = nothing in view.
            K: OpenCV intrinsics, shape (3, 3).

        Returns:
            Boolean mask, shape (H, W).
        """
        z = _image(depth_m, "measurable")
        ws = _workspace(z.shape)
        _pad(z, ws.w, ws.zz)
        none = ws.no_out
        _sensor_kernel(z, ws.w, ws.zz, *_intrinsics(K), *self._mask_settings(), *self._noise_settings(),
                       none, none, none, none, ws.ok, ws.edge, ws.c2, ws.zfar)
        return ws.ok.copy()

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
        """Dropout, flying fraction, white noise, axial model code and its ToF scale (float32);
        depth quantum [m] and disparity quantum [px] (float64, -1 = off) and fb [px m]."""
        return (
            np.float32(self.dropout),
            np.float32(self.flying_frac),
            np.float32(self.noise_m),
            AXIAL_MODELS.index(self.axial),
            np.float32(self.tof_sigma_1m_m),
            -1.0 if self.quantum_m is None else float(self.quantum_m),
            -1.0 if self.disparity_quantum_px is None else float(self.disparity_quantum_px),
            float(self.focal_baseline_px_m),
        )

    def measure(self, depth_m: np.ndarray, K: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """Simulates one measured frame.

        Args:
            depth_m: Exact depth, shape (H, W), [m]; 0 = nothing in view.
            K: OpenCV intrinsics, shape (3, 3).
            rng: The generator of the depth stream; advanced per call by the draws listed in the
                module docstring, whatever the image shows.

        Returns:
            Measured depth, shape (H, W), float32 metres; 0 = no measurement.
        """
        z = _image(depth_m, "measure")
        ws = _workspace(z.shape)
        out = np.empty(z.shape, dtype=np.float32)
        rng.standard_normal(dtype=np.float32, out=out)
        fx, fy, cx, cy = _intrinsics(K)
        if self.lateral != "none":
            rng.standard_normal(dtype=np.float32, out=ws.offsets)
            _pad(z, ws.w, ws.zz)
            _incidence_cos_kernel(z, ws.w, fx, fy, cx, cy, ws.c2)
            _lateral_kernel(z, ws.offsets[0], ws.offsets[1], ws.c2, LATERAL_MODELS.index(self.lateral),
                            np.float32(self.lateral_px), np.float32(self.discontinuity_m), ws.jittered)
            z = ws.jittered
        uniform = rng.random(dtype=np.float32, out=ws.uniform) if self.dropout > 0 else ws.no_out
        flying = rng.random(dtype=np.float32, out=ws.flying) if self.flying_frac > 0 else ws.no_out
        bias = ws.no_out
        if self.multipath_m > 0:
            bias = ws.bias
            _multipath_kernel(z, int(self.multipath_window_px), np.float32(self.multipath_m),
                              np.float32(self.multipath_depth_m), bias)
        _pad(z, ws.w, ws.zz)
        _sensor_kernel(z, ws.w, ws.zz, fx, fy, cx, cy, *self._mask_settings(), *self._noise_settings(),
                       uniform, flying, bias, out, ws.ok, ws.edge, ws.c2, ws.zfar)
        return out


PRESETS = {
    "ds325": SensorModel(axial="tof", tof_sigma_1m_m=0.014, lateral="constant", lateral_px=0.5, multipath_m=0.008,
                         flying_frac=0.3, quantum_m=0.001, min_range_m=0.15, max_range_m=1.0),
    "kinect-v1": SensorModel(axial="nguyen2012", lateral="nguyen2012", quantum_m=0.001, disparity_quantum_px=0.125,
                             focal_baseline_px_m=580.0 * 0.075, min_range_m=0.4, max_range_m=3.0),
    "ideal": SensorModel.ideal(),
}
"""The depth-sensor presets by name (values and sources in docs/scenarios.md):

* ``ds325``: the paper's SoftKinetic DepthSense 325 (time of flight): its data sheet's range
  (0.15-1 m) and depth noise (< 1.4 cm at 1 m, frontal: ``tof_sigma_1m_m``), whole millimetres,
  the confidence filter's dropped edges, and artefacts whose size the data sheet does not give
  (chosen, not measured: 0.5 px lateral jitter, 8 mm peak multipath, 30 % of edge pixels flying).
* ``kinect-v1``: a structured-light Kinect v1 in near mode (0.4-3 m): Nguyen et al. 2012's axial
  and lateral noise, disparity quantised to 1/8 px with f b = 580 px x 0.075 m (Khoshelham &
  Elberink 2012, Sensors 12(2)), then reported in whole millimetres as its drivers do.
* ``ideal``: exact depth (the scenario's white noise only, if any).
"""

if tuple(PRESETS) != SENSORS:  # pragma: no cover - a preset added in one place only
    raise BenchmarkError(f"the sensor presets {tuple(PRESETS)} differ from the scenario's names {SENSORS}")
DEFAULT_SENSOR = "ds325"


def sensor_preset(name: str, noise_m: float = 0.0) -> SensorModel:
    """The preset ``name`` with white noise ``noise_m`` [m] added.

    Raises:
        BenchmarkError: For an unknown name (the message lists the presets).
    """
    if name not in PRESETS:
        raise BenchmarkError(f"sensor must be one of {', '.join(SENSORS)}; got {name!r}")
    return replace(PRESETS[name], noise_m=float(noise_m))


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


@_jit
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


@_jit
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
