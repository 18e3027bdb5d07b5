"""A lab's AHRS on the box: what an Xsens MTi-300, as a lab mounts and records it, would report.

The paper's Table 1 compares vision's kinematics with an MTi-300 fixed to the box. Our ideal IMU is
the simulator's truth (``Truth.imu_acc``, ``Truth.imu_gyro``); this module adds what stands between
the truth and a real sensor's readings. For camera frame k (times t_k = k / fps), in the box frame:

    acc_k  = clip(A_a f(s_k) + b_a + n_a,k, +-acc_range)       A = (I + S) N C
    gyro_k = clip(A_g w(s_k) + b_g + n_g,k, +-gyro_range)

- f(t) = R^T (a - g) + alpha_b x r + w_b x (w_b x r): the specific force at the accelerometer, r
  the lever arm (box frame) from the point vision reports (the box's centre of mass) to the
  accelerometer, left after the lab's compensation; w(t) = R^T omega the box-frame angular velocity
  (the same quantities as ``Truth.imu_acc`` and ``Truth.imu_gyro`` when r = 0).
- C: the rotation from the box's axes into the sensor's: the lab's mounting misalignment, then the
  sensor's own alignment of its output frame to its base plate. N: the non-orthogonality of the
  sensor's axes (I plus off-diagonal terms). S: diagonal scale-factor errors.
- b: bias, constant within an episode: a turn-on bias plus the in-run bias instability (over a 10 s
  episode the in-run drift stays near the Allan-deviation floor, so we draw it once).
- n: white noise, standard deviation noise density x sqrt(bandwidth) per reading (the -3 dB
  bandwidth taken as the noise bandwidth; a first-order roll-off would give sqrt(pi/2) = 1.25 times
  more). Readings 33 ms apart are independent at these bandwidths.
- s_k: the instant the paired reading was taken, in camera time. The AHRS outputs a sample every
  1 / output_rate on its own clock; the lab pairs frame k with the sample whose timestamp is
  nearest t_k, j = round(t_k * output_rate); that clock runs ``time_offset`` behind the camera's,
  so s_k = j / output_rate + time_offset. The truth is known at the frames only, so the shift
  moves what the frames resolve and keeps the rest (:func:`shift_resolved`): the truth's
  accelerations hold hand tremor and contact content up to the frames' Nyquist rate (about
  0.19 m/s^2 RMS per axis on the six excitations) that a 375 Hz sensor reads at any instant with
  the same size but that no interpolation between 30 Hz samples can place; interpolating the whole
  signal would shrink it and make the lab's AHRS agree with vision *better* than the truth does.

Values (``MTI_300``), from
[DS] Movella, "MTi-300 AHRS" datasheet, (c) Movella, May 2023: gyroscope standard full range
     450 deg/s, in-run bias stability 10 deg/h, bandwidth (-3 dB) 415 Hz, noise density
     0.01 deg/s/sqrt(Hz) (g-sensitivity 0.003 deg/s/g, not modelled: < 1e-4 rad/s here);
     accelerometer standard full range 20 g, in-run bias stability 15 ug, bandwidth 375 Hz, noise
     density 60 ug/sqrt(Hz);
[UM] Xsens, "MTi User Manual, MTi 10-series and MTi 100-series", document MT0605P, revision
     2018.E, section 5.2.1: the base plate is aligned with the sensor's output frame within 0.1 deg;
     the output axes are orthogonal within 0.05 deg;
[KB] Xsens knowledge base, "Bias repeatability of gyroscopes" (base.xsens.com, article 203307252):
     the gyroscopes' turn-on to turn-on bias repeatability is +-0.5 deg/s within one year.
Not found in those documents, so our choices (each stated in its field): the accelerometers'
turn-on bias, the scale-factor errors, the mounting, the lever arm, the clock offset and the
output rate. g = 9.80665 m/s^2 converts the datasheet's g and ug.

Every draw comes from ``scenario.rng("ahrs")`` (:func:`draw`), in a fixed order and count that do
not depend on the parameters, so zeroing one error source leaves the others' draws unchanged. That
stream depends on the scenario's seed only: episodes of one seed (Table 1's six excitations) share
one drawn sensor, as one sensor mounted once would.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, fields, replace

import numpy as np

from benchmark.errors import ScenarioError
from benchmark.world.scenario import Scenario
from benchmark.world.truth import Truth
from fsv.linalg import mm, rows_mt

STANDARD_GRAVITY_MPS2 = 9.80665
"""The g of the datasheet's g and ug, [m/s^2]."""

IMU_CHOICES = ("ideal", "mti-300")
"""What Table 1 compares vision's kinematics with: the truth, or :data:`MTI_300`."""

SOURCES = {
    "noise": ("acc_noise_density_mps2_rthz", "gyro_noise_density_radps_rthz"),
    "bias": ("acc_turn_on_bias_mps2", "gyro_turn_on_bias_radps", "acc_bias_instability_mps2",
             "gyro_bias_instability_radps"),
    "scale factor": ("acc_scale_factor_error", "gyro_scale_factor_error"),
    "sensor alignment": ("sensor_alignment_rad", "axis_non_orthogonality_rad"),
    "mounting": ("mounting_misalignment_rad",),
    "lever arm": ("lever_arm_m",),
    "timing": ("time_offset_s", "output_rate_hz"),
}
"""The error sources and the :class:`AhrsParams` fields of each (for :meth:`AhrsParams.only`)."""


@dataclass(frozen=True)
class AhrsParams:
    """An AHRS and how the lab mounts and records it. Bounds (+-) are of uniform draws.

    Attributes:
        acc_noise_density_mps2_rthz: Accelerometer noise density, [m/s^2/sqrt(Hz)] ([DS]: 60 ug/sqrt(Hz)).
        acc_bandwidth_hz: Accelerometer -3 dB bandwidth, [Hz] ([DS]: 375 Hz).
        gyro_noise_density_radps_rthz: Gyroscope noise density, [rad/s/sqrt(Hz)] ([DS]: 0.01 deg/s/sqrt(Hz)).
        gyro_bandwidth_hz: Gyroscope -3 dB bandwidth, [Hz] ([DS]: 415 Hz).
        acc_bias_instability_mps2: Standard deviation of the in-run bias per axis, [m/s^2] ([DS]: 15 ug).
        gyro_bias_instability_radps: The same for the gyroscopes, [rad/s] ([DS]: 10 deg/h).
        acc_turn_on_bias_mps2: Bound of the accelerometers' turn-on bias per axis, [m/s^2]. Not in
            [DS], [UM] or [KB]; our choice: 5 mg, the order of industrial MEMS accelerometers' turn-on
            repeatability.
        gyro_turn_on_bias_radps: Bound of the gyroscopes' turn-on bias per axis, [rad/s] ([KB]: 0.5 deg/s).
        acc_scale_factor_error: Bound of each accelerometer axis's relative gain error. Not in the
            documents; our choice: 0.1 % (each unit's gains are calibrated at the factory, [UM]).
        gyro_scale_factor_error: The same for the gyroscopes; our choice: 0.1 %.
        sensor_alignment_rad: Bound of the angle between the sensor's output frame and its base
            plate, [rad] ([UM]: 0.1 deg).
        axis_non_orthogonality_rad: Bound of each pair of output axes' deviation from 90 deg, [rad]
            ([UM]: 0.05 deg).
        mounting_misalignment_rad: Bound of the angle between the base plate and the box's axes as
            vision defines them (the tracked model's edges), [rad]. Our choice: 1 deg, a sensor
            screwed to a hand-built box and aligned by eye with its edges (0.9 mm over the plate's 5 cm).
        lever_arm_m: Bound per box axis of the accelerometer's offset from the box's centre of
            mass after the lab's compensation, [m]. Our choice: 5 mm (the accelerometer's position
            in the housing, the housing's in the box and the box's centre of mass, each known to a
            few millimetres).
        time_offset_s: Bound of the offset between the AHRS's clock and the camera's, [s]. Our
            choice: half a frame at 30 fps (1/60 s): streams aligned to the nearest camera frame
            (e.g. by cross-correlating the gyroscope with vision's angular velocity); streams
            stamped on arrival at the host without that would be worse.
        output_rate_hz: The AHRS's output rate, [Hz]; ``inf`` reads at the frame instants. Our
            choice: 100 Hz (the MTi's output rates reach 400 Hz and more; the paper does not say).
        acc_range_mps2: Accelerometer full range, [m/s^2] ([DS]: 20 g); readings saturate there.
        gyro_range_radps: Gyroscope full range, [rad/s] ([DS]: 450 deg/s).
    """

    acc_noise_density_mps2_rthz: float = 60e-6 * STANDARD_GRAVITY_MPS2
    acc_bandwidth_hz: float = 375.0
    gyro_noise_density_radps_rthz: float = math.radians(0.01)
    gyro_bandwidth_hz: float = 415.0
    acc_bias_instability_mps2: float = 15e-6 * STANDARD_GRAVITY_MPS2
    gyro_bias_instability_radps: float = math.radians(10.0) / 3600.0
    acc_turn_on_bias_mps2: float = 5e-3 * STANDARD_GRAVITY_MPS2
    gyro_turn_on_bias_radps: float = math.radians(0.5)
    acc_scale_factor_error: float = 1e-3
    gyro_scale_factor_error: float = 1e-3
    sensor_alignment_rad: float = math.radians(0.1)
    axis_non_orthogonality_rad: float = math.radians(0.05)
    mounting_misalignment_rad: float = math.radians(1.0)
    lever_arm_m: float = 0.005
    time_offset_s: float = 1.0 / 60.0
    output_rate_hz: float = 100.0
    acc_range_mps2: float = 20.0 * STANDARD_GRAVITY_MPS2
    gyro_range_radps: float = math.radians(450.0)

    def __post_init__(self):
        for f in fields(self):
            v = getattr(self, f.name)
            ok = isinstance(v, (int, float, np.integer, np.floating)) and not isinstance(v, bool) and not math.isnan(v)
            if f.name in ("output_rate_hz", "acc_range_mps2", "gyro_range_radps"):
                if not (ok and v > 0):
                    raise ScenarioError(f"AhrsParams.{f.name} must be a number > 0 (inf allowed), got {v!r}")
            elif f.name in ("acc_bandwidth_hz", "gyro_bandwidth_hz"):
                if not (ok and math.isfinite(v) and v > 0):
                    raise ScenarioError(f"AhrsParams.{f.name} must be a finite number > 0, got {v!r}")
            elif not (ok and math.isfinite(v) and v >= 0):
                raise ScenarioError(f"AhrsParams.{f.name} must be a finite number >= 0, got {v!r}")
        if self.mounting_misalignment_rad + self.sensor_alignment_rad > math.pi / 2:
            raise ScenarioError("AhrsParams.mounting_misalignment_rad + sensor_alignment_rad must be at most pi/2, got "
                                f"{self.mounting_misalignment_rad!r} + {self.sensor_alignment_rad!r}")

    def only(self, *sources: str) -> "AhrsParams":
        """These parameters with every error source but ``sources`` (keys of :data:`SOURCES`) off."""
        bad = [s for s in sources if s not in SOURCES]
        if bad:
            raise ScenarioError(f"no such AHRS error source {bad[0]!r}; accepted: {', '.join(SOURCES)}")
        off = {k: (math.inf if k == "output_rate_hz" else 0.0) for s in SOURCES if s not in sources for k in SOURCES[s]}
        return replace(self, **off)

    def caption(self) -> str:
        """The lab's choices in a few words, for a table's caption."""
        return (f"{math.degrees(self.mounting_misalignment_rad):g} deg mounting, {1e3 * self.lever_arm_m:g} mm lever arm, "
                f"clock offset within {1e3 * self.time_offset_s:.1f} ms, {self.output_rate_hz:g} Hz output")

    def describe(self) -> dict:
        """The parameters as a JSON-ready dict (``inf`` as the string "inf")."""
        return {k: (v if math.isfinite(v) else "inf") for k, v in asdict(self).items()}


MTI_300 = AhrsParams()
"""An Xsens MTi-300 on the paper's box, with our stated choices for what its documents do not give."""

IDEAL = MTI_300.only()
"""No error source: the readings are the truth's ``imu_acc`` and ``imu_gyro``, bit for bit."""


@dataclass(frozen=True)
class AhrsDraw:
    """One episode's drawn sensor errors (see the module docstring).

    Attributes:
        rotation: C, the box axes into the sensor's, (3, 3).
        acc_axes: A_a = (I + S_a) N_a C, (3, 3).
        gyro_axes: A_g = (I + S_g) N_g C, (3, 3).
        acc_bias_mps2: b_a, (3,), [m/s^2].
        gyro_bias_radps: b_g, (3,), [rad/s].
        lever_arm_m: r, box frame, (3,), [m].
        time_offset_s: The AHRS clock's offset from the camera's, [s].
        misalignment_rad: The angle of ``rotation``, [rad].
    """

    rotation: np.ndarray
    acc_axes: np.ndarray
    gyro_axes: np.ndarray
    acc_bias_mps2: np.ndarray
    gyro_bias_radps: np.ndarray
    lever_arm_m: np.ndarray
    time_offset_s: float
    misalignment_rad: float

    def summary(self) -> dict:
        """What was drawn, for a report: degrees, milliseconds, m/s^2, rad/s and millimetres."""
        return {
            "misalignment_deg": math.degrees(self.misalignment_rad),
            "time_offset_ms": 1e3 * self.time_offset_s,
            "acc_bias_mps2": [float(v) for v in self.acc_bias_mps2],
            "gyro_bias_radps": [float(v) for v in self.gyro_bias_radps],
            "lever_arm_mm": [1e3 * float(v) for v in self.lever_arm_m],
        }


@dataclass(frozen=True)
class AhrsReadings:
    """What the AHRS reports at the camera's frames, box frame.

    Attributes:
        acc: Specific force, (T, 3), [m/s^2] (compare with ``Kinematics.imu``'s first output).
        gyro: Angular velocity, (T, 3), [rad/s].
        draw: The episode's drawn errors.
        label: Which sensor, for a table's caption.
    """

    acc: np.ndarray
    gyro: np.ndarray
    draw: AhrsDraw
    label: str


def _rotation(axis: np.ndarray, angle: float) -> np.ndarray:
    """The rotation by ``angle`` [rad] about the unit ``axis`` (3,), as a (3, 3) matrix (scalar math, fixed order)."""
    c, s = math.cos(angle / 2), math.sin(angle / 2)
    w, x, y, z = c, s * float(axis[0]), s * float(axis[1]), s * float(axis[2])
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ])


def _unit(v: np.ndarray) -> np.ndarray:
    x, y, z = (float(a) for a in v)
    n = math.sqrt(x * x + y * y + z * z)
    return np.array([x / n, y / n, z / n])


def _skewed_axes(off_diagonal: np.ndarray, bound_rad: float) -> np.ndarray:
    """N = I plus off-diagonal terms within +-bound/2, so each pair of axes is within bound of 90 deg, (3, 3)."""
    n = np.eye(3)
    n[~np.eye(3, dtype=bool)] = 0.5 * bound_rad * off_diagonal
    return n


def draw(params: AhrsParams, rng: np.random.Generator) -> AhrsDraw:
    """Draws one episode's sensor errors: 42 variates from ``rng``, always in this order.

    Mounting and sensor alignment: a uniform axis and a uniform angle in [0, bound] each; the
    non-orthogonality, scale factors, turn-on biases and lever arm uniform within their bounds; the
    in-run biases normal; the clock offset uniform in [-bound, bound].
    """
    mount_axis, mount_u = _unit(rng.standard_normal(3)), float(rng.uniform())
    plate_axis, plate_u = _unit(rng.standard_normal(3)), float(rng.uniform())
    skew_a, skew_g = rng.uniform(-1, 1, 6), rng.uniform(-1, 1, 6)
    scale_a, scale_g = rng.uniform(-1, 1, 3), rng.uniform(-1, 1, 3)
    turn_on_a, turn_on_g = rng.uniform(-1, 1, 3), rng.uniform(-1, 1, 3)
    in_run_a, in_run_g = rng.standard_normal(3), rng.standard_normal(3)
    lever, offset = rng.uniform(-1, 1, 3), float(rng.uniform(-1, 1))

    p = params
    C = mm(_rotation(plate_axis, plate_u * p.sensor_alignment_rad), _rotation(mount_axis, mount_u * p.mounting_misalignment_rad))
    acc_axes = mm(mm(np.diag(1 + p.acc_scale_factor_error * scale_a), _skewed_axes(skew_a, p.axis_non_orthogonality_rad)), C)
    gyro_axes = mm(mm(np.diag(1 + p.gyro_scale_factor_error * scale_g), _skewed_axes(skew_g, p.axis_non_orthogonality_rad)), C)
    cos_angle = min(1.0, max(-1.0, (C[0, 0] + C[1, 1] + C[2, 2] - 1) / 2))
    return AhrsDraw(
        rotation=C, acc_axes=acc_axes, gyro_axes=gyro_axes,
        acc_bias_mps2=p.acc_turn_on_bias_mps2 * turn_on_a + p.acc_bias_instability_mps2 * in_run_a,
        gyro_bias_radps=p.gyro_turn_on_bias_radps * turn_on_g + p.gyro_bias_instability_radps * in_run_g,
        lever_arm_m=p.lever_arm_m * lever, time_offset_s=p.time_offset_s * offset, misalignment_rad=math.acos(cos_angle),
    )


def sample_instants(t: np.ndarray, time_offset_s: float, output_rate_hz: float) -> np.ndarray:
    """s_k - t_k: when the reading paired with each frame was taken, relative to the frame, (T,), [s].

    Args:
        t: Frame times, (T,), [s].
        time_offset_s: The AHRS clock's offset, [s].
        output_rate_hz: The AHRS's output rate, [Hz] (``inf``: at the frame instants).
    """
    t = np.asarray(t, dtype=float)
    if math.isinf(output_rate_hz):
        return np.full(t.shape, float(time_offset_s))
    return (np.round(t * output_rate_hz) / output_rate_hz - t) + time_offset_s


def resample(signal: np.ndarray, shift_frames: np.ndarray) -> np.ndarray:
    """A signal sampled at frames k = 0..T-1, read at k + shift_frames[k] (Catmull-Rom cubic).

    Args:
        signal: (T, C) samples.
        shift_frames: (T,) offsets in frames; 0 returns the sample itself, bit for bit. Times
            outside [0, T-1] read the end sample.

    Returns:
        (T, C).
    """
    y = np.asarray(signal, dtype=float)
    T = y.shape[0]
    if T < 2:
        raise ScenarioError(f"resampling needs at least 2 frames, got {T}")
    x = np.clip(np.arange(T) + np.asarray(shift_frames, dtype=float), 0.0, T - 1.0)
    i = np.floor(x).astype(int)
    u = (x - i)[:, None]
    step = y[-1:] - y[-2:-1]
    padded = np.concatenate([2 * y[:1] - y[1:2], y, y[-1:] + step, y[-1:] + 2 * step])  # linear extension at the ends
    p0, p1, p2, p3 = padded[i], padded[i + 1], padded[i + 2], padded[i + 3]
    return p1 + 0.5 * u * ((p2 - p0) + u * ((2 * p0 - 5 * p1 + 4 * p2 - p3) + u * (3 * (p1 - p2) + (p3 - p0))))


def _binomial(y: np.ndarray) -> np.ndarray:
    """(1, 4, 6, 4, 1) / 16 smoothing along frames, ends repeated, (T, C) -> (T, C)."""
    p = np.concatenate([y[:1], y[:1], y, y[-1:], y[-1:]])
    return ((p[:-4] + p[4:]) + 4 * (p[1:-3] + p[3:-1]) + 6 * p[2:-2]) / 16


def shift_resolved(signal: np.ndarray, shift_frames: np.ndarray) -> np.ndarray:
    """A frame-rate signal read ``shift_frames`` later, moving only the content the frames resolve.

    y_k + (L(k + s_k) - L_k): L the signal low-passed by 2 B - B B, B the (1, 4, 6, 4, 1) / 16
    binomial (a 9-frame filter of gain b (2 - b), b = cos^4(pi f / fps): at 30 fps 0.99 at 2 Hz,
    0.91 at 4 Hz, 0.67 at 6 Hz, 0.12 at 10 Hz), read between frames by :func:`resample`; the rest,
    y - L, stays at the frame instant, where it has the size it has at any instant.

    Args:
        signal: (T, C) samples at frames k = 0..T-1.
        shift_frames: (T,) offsets in frames; 0 returns the samples bit for bit.

    Returns:
        (T, C).
    """
    y = np.asarray(signal, dtype=float)
    smooth = _binomial(y)
    low = 2 * smooth - _binomial(smooth)
    return y + (resample(low, shift_frames) - low)


def read(truth: Truth, fps: float, rng: np.random.Generator, params: AhrsParams = MTI_300, label: str = "mti-300") -> AhrsReadings:
    """The AHRS's readings over an episode.

    Args:
        truth: The episode's truth (``imu_acc``, ``imu_gyro``, ``box_quat``, ``box_alpha``), T frames.
        fps: Its frame rate, [Hz] (``truth.t`` must be k / fps from its first frame).
        rng: The generator, e.g. ``scenario.rng("ahrs")``: 42 variates (:func:`draw`), then 6 T normals.
        params: The sensor.
        label: Printed name of the sensor.

    Returns:
        The readings, (T, 3) each, box frame.
    """
    t = np.asarray(truth.t, dtype=float)
    T = t.size
    if not (math.isfinite(fps) and fps > 0):
        raise ScenarioError(f"fps must be a finite number > 0, got {fps!r}")
    if T > 1 and np.max(np.abs(t - (t[0] + np.arange(T) / fps))) > 1e-6:
        raise ScenarioError(f"the truth's frame times are not k / {fps:g} s")
    d = draw(params, rng)
    noise = rng.standard_normal((T, 6))
    R = truth.box_rot
    omega = truth.imu_gyro
    alpha = np.einsum("tji,tj->ti", R, truth.box_alpha)
    r = np.broadcast_to(d.lever_arm_m, omega.shape)
    acc = truth.imu_acc + np.cross(alpha, r) + np.cross(omega, np.cross(omega, r))
    shift = sample_instants(t, d.time_offset_s, params.output_rate_hz) * fps
    acc, gyro = shift_resolved(acc, shift), shift_resolved(omega, shift)
    sigma_a = params.acc_noise_density_mps2_rthz * math.sqrt(params.acc_bandwidth_hz)
    sigma_g = params.gyro_noise_density_radps_rthz * math.sqrt(params.gyro_bandwidth_hz)
    acc = rows_mt(acc, d.acc_axes) + d.acc_bias_mps2 + sigma_a * noise[:, :3]
    gyro = rows_mt(gyro, d.gyro_axes) + d.gyro_bias_radps + sigma_g * noise[:, 3:]
    return AhrsReadings(
        acc=np.clip(acc, -params.acc_range_mps2, params.acc_range_mps2),
        gyro=np.clip(gyro, -params.gyro_range_radps, params.gyro_range_radps), draw=d, label=label,
    )


def lab_readings(truth: Truth, scenario: Scenario, params: AhrsParams = MTI_300, label: str = "mti-300") -> AhrsReadings:
    """:func:`read` with the scenario's frame rate and its ``"ahrs"`` stream: the same scenario, the same bits."""
    return read(truth, scenario.fps, scenario.rng("ahrs"), params, label)
