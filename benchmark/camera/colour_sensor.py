"""The colour sensor model: what an RGB camera beside the depth camera records of the radiance.

Per frame (the renderer gives the exposure's mean linear radiance L, (H, W, 3)), per pixel and
channel, in this order (:func:`benchmark.camera.colour_kernels.expose`):

1. Signal: e = L * full_well_e / saturation_radiance electrons (a fixed exposure and gain: the
   camera's exposure is set once for the lab's light, so that radiance ``saturation_radiance``
   fills the well; brighter saturates).
2. Noise (``noise``): the Gaussian approximation of Poisson shot noise plus read noise,
   e + sqrt(max(e, 0) + read_noise_e^2) * z, z standard normal.
3. Normalised by the full well, clipped to [0, 1].
4. White balance: times the gain of the channel (``white_balance``: "daylight" keeps the linear
   sRGB of the D65 white, gains 1, so a warm light casts warm; "auto" applies the gains that make
   the scene's illuminant neutral, ``g_c = w_G / w_c`` with w the white of
   :meth:`benchmark.camera.appearance.Lighting.white`: an ideal automatic white balance that
   knows the lights, the default of consumer RGB cameras modelled without its errors), clipped to 1.
5. sRGB encoding (IEC 61966-2-1) by a lookup table of 65536 entries (:func:`srgb_table`, its bits
   pinned by a test), to uint8.

Random draws: one ``np.random.Generator`` (the scenario's "colour" stream), per frame
``ceil(H W 3 / 4)`` 64-bit words of its bit generator (``rng.bit_generator.random_raw``), each
giving four 16-bit indices (lowest bits first) to the values of the image in C order (channel
fastest), each index turned into a standard normal by a table of 65536 quantiles
(:func:`normal_table`, the quantiles at (i + 0.5) / 65536: a uniform draw on 65536 levels, tails
cut at 4.3 sigma). Not ``rng.standard_normal``: it costs 7.5 ms per 640 x 480 x 3 frame on the
reference machine (3/4 of the budget of 100 frames/s), the raw words 0.4 ms. Without noise
nothing is drawn.

Presets (:func:`colour_preset`) by the depth presets' names (:data:`benchmark.world.scenario.SENSORS`):

* ``ds325``: the SoftKinetic DS325's colour camera, HD 1280 x 720 with a 63.2 x 49.3 degree field of
  view (its data sheet); rendered at 640 x 480 with that field of view (the issue accepts the
  lower resolution; the field of view's aspect, tan(31.6) / tan(24.65) = 1.34, is 4:3, so 640 x
  480 keeps square pixels). Its offset from the depth camera is not published: 2.5 cm along the
  depth camera's x, a stated choice (the Kinect v1's).
* ``kinect-v1``: 640 x 480, about 62 x 48.6 degrees, the colour camera about 2.5 cm from the IR
  camera along x (Khoshelham & Elberink 2012, Sensors 12(2)).
* ``ideal``: co-located with the depth camera, the depth camera's field of view, no noise, no
  blur (zero exposure: one render at t_k), gains 1, saturation radiance 1.

Shared by ds325 and kinect-v1 (stated choices, typical of small-pixel consumer CMOS sensors, not
measured on these cameras): exposure 1/60 s (indoor lab light at 30 frames/s), full well 6000 e-,
read noise 4 e-, saturation radiance 1.25 (a white surface under the brightest drawn lights just
saturates), automatic white balance.
"""

from __future__ import annotations

import functools
import math
import statistics
from dataclasses import dataclass, replace

import numpy as np

from benchmark.camera import colour_kernels as ck
from benchmark.camera.camera import Camera
from benchmark.errors import BenchmarkError
from benchmark.world.scenario import SENSORS

WHITE_BALANCES = ("daylight", "auto")
"""White-balance modes (step 4 of the module docstring)."""
TABLE_SIZE = 65536
"""Entries of the sRGB and the normal lookup tables."""


@functools.cache
def srgb_table() -> np.ndarray:
    """sRGB code (uint8) of the linear values i / 65535, i = 0..65535 (IEC 61966-2-1: 12.92 x
    below 0.0031308, else 1.055 x^(1/2.4) - 0.055), rounded half up; built with Python's scalar
    math (not a vectorised power whose last bits may differ by CPU). Read-only."""
    out = np.empty(TABLE_SIZE, dtype=np.uint8)
    for i in range(TABLE_SIZE):
        x = i / (TABLE_SIZE - 1)
        s = 12.92 * x if x <= 0.0031308 else 1.055 * x ** (1.0 / 2.4) - 0.055
        out[i] = int(math.floor(s * 255.0 + 0.5))
    out.flags.writeable = False
    return out


@functools.cache
def normal_table() -> np.ndarray:
    """Standard normal quantiles at (i + 0.5) / 65536, i = 0..65535, float64 (Python's
    ``statistics.NormalDist``, scalar math). Read-only."""
    inv = statistics.NormalDist().inv_cdf
    out = np.array([inv((i + 0.5) / TABLE_SIZE) for i in range(TABLE_SIZE)], dtype=np.float64)
    out.flags.writeable = False
    return out


@dataclass(frozen=True)
class ColourSensor:
    """Settings of the colour camera and its sensor model (module docstring).

    Attributes:
        width, height: Rendered image size [px].
        hfov_deg, vfov_deg: Field of view [deg]; None: the depth camera's (the intrinsics scaled
            to this image size).
        offset_m: The colour camera's centre in the depth camera's frame (OpenCV), (3,) [m];
            its axes are the depth camera's (``T_depth_colour`` is a translation).
        exposure_s: Exposure time [s] (frame k integrates over [t_k - e/2, t_k + e/2]); 0: no blur.
        blur_step_px: Largest image motion [px] between two sub-renders of the exposure.
        max_samples: Most sub-renders per frame (odd).
        noise: Shot and read noise on (False: noise-free).
        full_well_e: Full-well capacity [e-].
        read_noise_e: Read noise [e-] (standard deviation).
        saturation_radiance: Radiance that fills the well.
        white_balance: One of :data:`WHITE_BALANCES`.
    """

    width: int = 640
    height: int = 480
    hfov_deg: float | None = 63.2
    vfov_deg: float | None = 49.3
    offset_m: tuple = (0.025, 0.0, 0.0)
    exposure_s: float = 1.0 / 60.0
    blur_step_px: float = 1.0
    max_samples: int = 9
    noise: bool = True
    full_well_e: float = 6000.0
    read_noise_e: float = 4.0
    saturation_radiance: float = 1.25
    white_balance: str = "auto"

    def __post_init__(self):
        def bad(name, accepted):
            raise BenchmarkError(f"ColourSensor.{name} must be {accepted}, got {getattr(self, name)!r}")

        for name in ("width", "height", "max_samples"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < 1:
                bad(name, "an integer >= 1")
        if self.max_samples % 2 == 0:
            bad("max_samples", "odd (the middle sub-render lies at t_k)")
        if (self.hfov_deg is None) != (self.vfov_deg is None):
            bad("vfov_deg", "None exactly when hfov_deg is None")
        for name in ("hfov_deg", "vfov_deg"):
            v = getattr(self, name)
            if v is not None and not (np.isfinite(v) and 0 < v < 180):
                bad(name, "None or an angle in (0, 180) degrees")
        off = np.asarray(self.offset_m, dtype=float)
        if off.shape != (3,) or not np.all(np.isfinite(off)):
            bad("offset_m", "three finite numbers [m]")
        object.__setattr__(self, "offset_m", tuple(float(x) for x in off))
        for name in ("exposure_s", "read_noise_e"):
            v = getattr(self, name)
            if not (np.isfinite(v) and v >= 0):
                bad(name, "a finite number >= 0")
        for name in ("blur_step_px", "full_well_e", "saturation_radiance"):
            v = getattr(self, name)
            if not (np.isfinite(v) and v > 0):
                bad(name, "a finite number > 0")
        if self.white_balance not in WHITE_BALANCES:
            bad("white_balance", f"one of {', '.join(WHITE_BALANCES)}")
        if not isinstance(self.noise, (bool, np.bool_)):
            bad("noise", "True or False")

    @classmethod
    def ideal(cls) -> "ColourSensor":
        """Co-located with the depth camera, its field of view; no noise, no blur, gains 1."""
        return cls(hfov_deg=None, vfov_deg=None, offset_m=(0.0, 0.0, 0.0), exposure_s=0.0, noise=False,
                   saturation_radiance=1.0, white_balance="daylight")

    def gains(self, lighting) -> np.ndarray:
        """White-balance gains (3,) under a :class:`benchmark.camera.appearance.Lighting`."""
        if self.white_balance == "daylight":
            return np.ones(3)
        w = np.asarray(lighting.white(), dtype=np.float64)
        return np.array([w[1] / w[0], 1.0, w[1] / w[2]])

    def sigma_e(self, signal_e) -> np.ndarray:
        """Standard deviation of the noise at a signal [e-] (0 without noise)."""
        e = np.maximum(np.asarray(signal_e, dtype=float), 0.0)
        return np.sqrt(e + self.read_noise_e**2) if self.noise else np.zeros(e.shape)

    def measure(self, radiance: np.ndarray, rng: np.random.Generator | None, lighting=None,
                out: np.ndarray | None = None) -> np.ndarray:
        """One recorded frame.

        Args:
            radiance: The exposure's mean linear radiance, (H, W, 3) float32.
            rng: The generator of the noise (the scenario's "colour" stream), advanced by
                ``ceil(H W 3 / 4)`` 64-bit words of its bit generator when ``noise`` is on (None
                allowed without noise).
            lighting: The scene's lighting (needed for ``white_balance="auto"``).
            out: Where to write the image, (H, W, 3) uint8 (default: a new array).

        Returns:
            sRGB image, (H, W, 3) uint8.
        """
        L = np.ascontiguousarray(radiance, dtype=np.float32)
        if L.ndim != 3 or L.shape[2] != 3:
            raise BenchmarkError(f"measure takes one radiance image of shape (H, W, 3), got {L.shape}")
        if self.white_balance == "auto" and lighting is None:
            raise BenchmarkError("white_balance='auto' needs the scene's lighting")
        raw = _NO_RAW
        if self.noise:
            if rng is None:
                raise BenchmarkError("a noisy sensor needs a random generator")
            raw = rng.bit_generator.random_raw((L.size + 3) // 4)
        if out is None:
            out = np.empty(L.shape, dtype=np.uint8)
        elif out.shape != L.shape or out.dtype != np.uint8 or not out.flags.c_contiguous:
            raise BenchmarkError(f"out must be a C-contiguous uint8 array of shape {L.shape}")
        ck.expose(L, raw, bool(self.noise), self.full_well_e / self.saturation_radiance, self.full_well_e,
                  self.read_noise_e**2, self.gains(lighting), normal_table(), srgb_table(), out)
        return out


_NO_RAW = np.zeros(0, dtype=np.uint64)


def encode(radiance: np.ndarray) -> np.ndarray:
    """sRGB uint8 (H, W, 3) of linear radiance (clipped to [0, 1]): the ideal sensor's output."""
    return ColourSensor.ideal().measure(radiance, None)


PRESETS = {
    "ds325": ColourSensor(),
    "kinect-v1": ColourSensor(hfov_deg=62.0, vfov_deg=48.6),
    "ideal": ColourSensor.ideal(),
}
"""The colour-sensor presets by the depth presets' names (module docstring)."""

if tuple(PRESETS) != SENSORS:  # pragma: no cover - a preset added in one place only
    raise BenchmarkError(f"the colour presets {tuple(PRESETS)} differ from the scenario's sensors {SENSORS}")


def colour_preset(name: str) -> ColourSensor:
    """The colour sensor of the depth preset ``name`` (:data:`PRESETS`).

    Raises:
        BenchmarkError: For an unknown name (the message lists the presets).
    """
    if name not in PRESETS:
        raise BenchmarkError(f"colour sensor must be one of {', '.join(SENSORS)}; got {name!r}")
    return PRESETS[name]


def colour_camera(depth_camera: Camera, sensor: ColourSensor) -> Camera:
    """The colour camera beside a depth camera: the sensor's size and field of view (principal
    point at the image centre), pose ``depth_camera.T_world_cam @ T_depth_colour`` (a translation
    by ``sensor.offset_m`` in the depth camera's frame); fps and clipping planes the depth camera's."""
    W, H = sensor.width, sensor.height
    if sensor.hfov_deg is None:
        fx = float(depth_camera.K[0, 0]) * W / depth_camera.width
        fy = float(depth_camera.K[1, 1]) * H / depth_camera.height
    else:
        fx = (W / 2) / math.tan(math.radians(sensor.hfov_deg) / 2)
        fy = (H / 2) / math.tan(math.radians(sensor.vfov_deg) / 2)
    K = np.array([[fx, 0.0, (W - 1) / 2], [0.0, fy, (H - 1) / 2], [0.0, 0.0, 1.0]])
    T = np.array(depth_camera.T_world_cam, dtype=np.float64)
    off = np.asarray(sensor.offset_m)
    t = T[:3, 3].copy()
    for r in range(3):  # T[:3, 3] + R @ offset, in a fixed order
        t[r] = T[r, 3] + T[r, 0] * off[0] + T[r, 1] * off[1] + T[r, 2] * off[2]
    T[:3, 3] = t
    return replace(depth_camera, width=W, height=H, K=K, T_world_cam=T)
