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

Everything runs in compiled passes over the pixels (numba; float32 arithmetic in a fixed order, no
fast-math); the normals are NumPy's own draws, bit for bit, compiled
(:func:`benchmark.camera.normal_draws.standard_normal_f32`), the uniforms NumPy's."""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from benchmark.camera.normal_draws import standard_normal_f32
from benchmark.camera.sensor_kernels import (
    _image,
    _incidence_cos_kernel,
    _intrinsics,
    _lateral_kernel,
    _multipath_kernel,
    _pad,
    _sensor_kernel,
    _workspace,
)
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
        standard_normal_f32(rng, out)
        fx, fy, cx, cy = _intrinsics(K)
        if self.lateral != "none":
            standard_normal_f32(rng, ws.offsets)
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


def sensor_preset(name: str, noise_m: float = 0.0) -> SensorModel:
    """The preset ``name`` with white noise ``noise_m`` [m] added.

    Raises:
        BenchmarkError: For an unknown name (the message lists the presets).
    """
    if name not in PRESETS:
        raise BenchmarkError(f"sensor must be one of {', '.join(SENSORS)}; got {name!r}")
    return replace(PRESETS[name], noise_m=float(noise_m))


def quantise(depth_m: np.ndarray, quantum_m: float) -> np.ndarray:
    """Rounds depth to multiples of `quantum_m`; float32, bit-identical to :func:`dequantise`."""
    return dequantise(np.rint(np.asarray(depth_m, dtype=np.float64) / quantum_m).astype(np.int64), quantum_m)


def dequantise(counts: np.ndarray, quantum_m: float) -> np.ndarray:
    """Depth in metres (float32) from integer multiples of `quantum_m`."""
    return (np.asarray(counts, dtype=np.float64) * quantum_m).astype(np.float32)


# Stand-ins for "nothing in view" in finite float32 arithmetic (no nan/inf special cases).
