"""Stage interfaces of the FSV method: small immutable records of numpy arrays.

Conventions (see docs/design.md): SI units; time axis first; frames at t_k = k / fps; world frame
with origin on the table top and z up; object frame at the box's centre of mass with axes along
its edges; camera frame in OpenCV's pinhole convention (x right, y down, z forward).
Every record checks its shapes on construction and raises :class:`fsv.errors.InputError`.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from dataclasses import dataclass

import numpy as np

from fsv._check import as_array, finite, positive, same_length
from fsv.errors import InputError


@dataclass(frozen=True)
class DepthVideo:
    """A depth video from one camera (frame after frame: :meth:`frames`).

    Attributes:
        depth_m: Depth along the optical axis, shape (T, H, W), float32 metres; 0 = no measurement.
        fps: Frame rate in [Hz]; frame k is taken at t_k = k / fps.
    """

    depth_m: np.ndarray
    fps: float

    def __post_init__(self):
        depth = as_array("DepthVideo.depth_m", self.depth_m, (None, None, None), np.float32)
        if not np.all(np.isfinite(depth)) or np.any(depth < 0):
            raise InputError("DepthVideo.depth_m must be finite and >= 0 (0 = no measurement)")
        positive("DepthVideo.fps", self.fps, "a positive number of Hz")
        object.__setattr__(self, "depth_m", depth)
        object.__setattr__(self, "fps", float(self.fps))

    @property
    def num_frames(self) -> int:
        return self.depth_m.shape[0]

    @property
    def t(self) -> np.ndarray:
        """Frame times in [s], shape (T,)."""
        return np.arange(self.num_frames) / self.fps

    def frames(self) -> Iterator[np.ndarray]:
        """The frames in order, (H, W) float32 [m] each: a reader that goes through the video
        frame after frame (the reference tracker) takes them from here, and so starts on the first
        frame of a :class:`DepthRecording` while the later ones are still being recorded."""
        return iter(self.depth_m)


class DepthRecording(DepthVideo):
    """A depth video still being recorded: its frames are written, in order, into an array that
    another process (a camera's driver, a renderer) shares with this one.

    To every reader it is the :class:`DepthVideo` it becomes: :attr:`depth_m` waits for the last
    frame, and every frame is checked as :class:`DepthVideo` checks them. :meth:`frames` hands each
    frame over as soon as it is written, so that a reader that goes through the video in order
    works on frame k while the later ones are recorded; the frames are the same bits either way.
    Pickled, it is the whole :class:`DepthVideo` (after the last frame).

    Args:
        buffer: The (T, H, W) float32 array the frames are written into [m]; only read here.
        fps: Frame rate [Hz].
        wait: ``wait(n)`` returns once the first ``n`` frames are in ``buffer``, with ``n`` from 1
            to T in any order (a recording that failed raises there, its error is the reader's).
    """

    def __init__(self, buffer: np.ndarray, fps: float, wait: Callable[[int], None]):
        if not (isinstance(buffer, np.ndarray) and buffer.dtype == np.float32 and buffer.ndim == 3):
            got = f"{buffer.dtype} array of shape {buffer.shape}" if isinstance(buffer, np.ndarray) else type(buffer).__name__
            raise InputError(f"DepthRecording.buffer must be a (T, H, W) float32 array, got {got}")
        if not callable(wait):
            raise InputError(f"DepthRecording.wait must be callable, got {type(wait).__name__}")
        positive("DepthRecording.fps", fps, "a positive number of Hz")
        view = buffer.view()
        view.setflags(write=False)
        object.__setattr__(self, "_buffer", view)
        object.__setattr__(self, "fps", float(fps))
        object.__setattr__(self, "_wait", wait)
        object.__setattr__(self, "_checked", 0)  # frames checked so far (each once)

    def _arrived(self, n: int) -> None:
        """Returns once the first ``n`` frames are recorded and checked."""
        if self._checked >= n:
            return
        self._wait(n)
        for k in range(self._checked, n):
            frame = self._buffer[k]
            if not np.all(np.isfinite(frame)) or np.any(frame < 0):
                raise InputError(f"DepthVideo.depth_m must be finite and >= 0 (0 = no measurement): frame {k} is not")
        object.__setattr__(self, "_checked", n)

    @property
    def depth_m(self) -> np.ndarray:
        """The whole video, (T, H, W) float32 [m], read-only (waits for its last frame)."""
        self._arrived(self.num_frames)
        return self._buffer

    @property
    def num_frames(self) -> int:
        return self._buffer.shape[0]

    def frames(self) -> Iterator[np.ndarray]:
        for k in range(self.num_frames):
            self._arrived(k + 1)
            yield self._buffer[k]

    def __repr__(self) -> str:
        T, H, W = self._buffer.shape
        return f"DepthRecording({T} frames of {W}x{H} at {self.fps:g} Hz, {self._checked} recorded)"

    def __reduce__(self):
        return DepthVideo, (self.depth_m, self.fps)


STREAMS = ("depth", "colour")
"""The camera's named streams, in the order files list them: the depth (always recorded) and the
colour camera's (recorded when a method or ``--streams`` asks for it)."""


def check_streams(names) -> tuple:
    """``names`` (an iterable of stream names, or one comma-separated string) as a tuple in
    :data:`STREAMS` order, ``depth`` always included.

    Raises:
        InputError: For a name not in :data:`STREAMS` (the message lists them).
    """
    if isinstance(names, str):
        names = [n.strip() for n in names.split(",")]
    names = [str(n) for n in names]
    bad = [n for n in names if n not in STREAMS]
    if bad:
        raise InputError(f"stream {bad[0]!r}: accepted: {', '.join(STREAMS)} (comma-separated)")
    return tuple(s for s in STREAMS if s == "depth" or s in names)


@dataclass(frozen=True)
class Calibration:
    """Pinhole camera calibration.

    Attributes:
        K: OpenCV intrinsics, shape (3, 3): [[fx, 0, cx], [0, fy, cy], [0, 0, 1]] in pixels.
        T_world_cam: Pose of the camera in the world, shape (4, 4): maps camera-frame points
            (OpenCV convention) to world points.
        width: Image width in pixels.
        height: Image height in pixels.
    """

    K: np.ndarray
    T_world_cam: np.ndarray
    width: int
    height: int

    def __post_init__(self):
        K = as_array("Calibration.K", self.K, (3, 3))
        T = as_array("Calibration.T_world_cam", self.T_world_cam, (4, 4))
        finite("Calibration.K", K)
        finite("Calibration.T_world_cam", T)
        R = T[:3, :3]
        if not np.allclose(R.T @ R, np.eye(3), atol=1e-6) or np.linalg.det(R) < 0:
            raise InputError("Calibration.T_world_cam[:3, :3] must be a rotation matrix")
        if int(self.width) <= 0 or int(self.height) <= 0:
            raise InputError(f"Calibration image size must be positive, got {self.width}x{self.height}")
        object.__setattr__(self, "K", K)
        object.__setattr__(self, "T_world_cam", T)
        object.__setattr__(self, "width", int(self.width))
        object.__setattr__(self, "height", int(self.height))

    def backproject(self, depth_m: np.ndarray) -> np.ndarray:
        """Back-projects a depth image to camera-frame points.

        Args:
            depth_m: Depth image, shape (H, W), metres; 0 = no measurement.

        Returns:
            Points in the camera frame, shape (H, W, 3) in [m]; invalid pixels give (0, 0, 0).
        """
        depth_m = np.asarray(depth_m)
        if depth_m.shape != (self.height, self.width):
            raise InputError(f"depth image must have shape ({self.height}, {self.width}), got {depth_m.shape}")
        v, u = np.mgrid[0 : self.height, 0 : self.width]
        fx, fy, cx, cy = self.K[0, 0], self.K[1, 1], self.K[0, 2], self.K[1, 2]
        z = depth_m.astype(np.float64)
        return np.stack([(u - cx) / fx * z, (v - cy) / fy * z, z], axis=-1)


@dataclass(frozen=True)
class Poses:
    """A sequence of rigid-body poses (object frame -> world frame).

    Attributes:
        t: Frame times in [s], shape (T,).
        pos: Position of the object frame's origin (the centre of mass) in the world, shape (T, 3), [m].
        rot: Rotation matrices world_R_object, shape (T, 3, 3).
    """

    t: np.ndarray
    pos: np.ndarray
    rot: np.ndarray

    def __post_init__(self):
        t = as_array("Poses.t", self.t, (None,))
        pos = as_array("Poses.pos", self.pos, (None, 3))
        rot = as_array("Poses.rot", self.rot, (None, 3, 3))
        same_length("Poses", t=t, pos=pos, rot=rot)
        for name, arr in (("t", t), ("pos", pos), ("rot", rot)):
            finite(f"Poses.{name}", arr)
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "pos", pos)
        object.__setattr__(self, "rot", rot)

    def __len__(self) -> int:
        return self.t.shape[0]


@dataclass(frozen=True)
class Kinematics:
    """First- and second-order kinematics of the object at frame times.

    All vectors are in the world frame.

    Attributes:
        t: Frame times in [s], shape (T,).
        pos: Centre-of-mass position, shape (T, 3), [m].
        rot: world_R_object, shape (T, 3, 3).
        vel: Linear velocity of the centre of mass, shape (T, 3), [m/s].
        acc: Linear acceleration of the centre of mass, shape (T, 3), [m/s^2].
        omega: Angular velocity, shape (T, 3), [rad/s].
        alpha: Angular acceleration, shape (T, 3), [rad/s^2].
        valid: Frames whose derivatives are defined (False near the ends of an offline window
            or before a causal filter has filled its window), shape (T,).
        method: Name of the differentiator that produced them (e.g. "algebraic", "oracle").
        delay_s: Estimation delay in [s] (0 for offline, centred estimates).
    """

    t: np.ndarray
    pos: np.ndarray
    rot: np.ndarray
    vel: np.ndarray
    acc: np.ndarray
    omega: np.ndarray
    alpha: np.ndarray
    valid: np.ndarray
    method: str = ""
    delay_s: float = 0.0

    def __post_init__(self):
        fields = dict(
            t=as_array("Kinematics.t", self.t, (None,)),
            pos=as_array("Kinematics.pos", self.pos, (None, 3)),
            rot=as_array("Kinematics.rot", self.rot, (None, 3, 3)),
            vel=as_array("Kinematics.vel", self.vel, (None, 3)),
            acc=as_array("Kinematics.acc", self.acc, (None, 3)),
            omega=as_array("Kinematics.omega", self.omega, (None, 3)),
            alpha=as_array("Kinematics.alpha", self.alpha, (None, 3)),
            valid=as_array("Kinematics.valid", self.valid, (None,), bool),
        )
        same_length("Kinematics", **fields)
        for k, v in fields.items():
            object.__setattr__(self, k, v)

    def __len__(self) -> int:
        return self.t.shape[0]

    def imu(self, gravity: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """What a strapdown AHRS fixed to the object would read.

        Args:
            gravity: Gravity in the world frame, shape (3,), [m/s^2] (e.g. (0, 0, -9.81)).

        Returns:
            ``(acc, gyro)``: specific force R^T (a - g), shape (T, 3) in [m/s^2], and angular
            velocity R^T ω, shape (T, 3) in [rad/s], both in the object frame.
        """
        g = np.asarray(gravity, dtype=float).reshape(3)
        acc = np.einsum("tji,tj->ti", self.rot, self.acc - g)
        gyro = np.einsum("tji,tj->ti", self.rot, self.omega)
        return acc, gyro


@dataclass(frozen=True)
class Contacts:
    """Hand-object contacts per finger and frame, in the object frame.

    Attributes:
        finger_names: Names of the K fingers, thumb first, shape (K,).
        active: Whether finger k touches the object at frame i, shape (T, K).
        sliding: Whether that contact slides (kinetic friction), shape (T, K).
        point: Contact point on the object's surface, object frame, shape (T, K, 3), [m];
            unspecified where not active.
        normal: Unit contact normal pointing into the object, object frame, shape (T, K, 3).
        slide_dir: Unit sliding direction of the finger relative to the object surface, object
            frame, shape (T, K, 3); zero where not sliding. Kinetic friction on the object
            points along +slide_dir (the finger drags the surface along with it).
        gap: Distance from the finger's pad to the object's surface, shape (T, K), [m]; NaN where
            unknown (the default). Where a finger is not active but its gap is finite, ``point``
            and ``normal`` hold the pad's projection onto the surface: a candidate contact the force
            programs may add when the active contacts cannot explain the motion
            (``fsv.forces.ForceSettings.repair_gap_m``).
    """

    finger_names: tuple
    active: np.ndarray
    sliding: np.ndarray
    point: np.ndarray
    normal: np.ndarray
    slide_dir: np.ndarray
    gap: np.ndarray = None

    def __post_init__(self):
        names = tuple(str(n) for n in self.finger_names)
        K = len(names)
        fields = dict(
            active=as_array("Contacts.active", self.active, (None, K), bool),
            sliding=as_array("Contacts.sliding", self.sliding, (None, K), bool),
            point=as_array("Contacts.point", self.point, (None, K, 3)),
            normal=as_array("Contacts.normal", self.normal, (None, K, 3)),
            slide_dir=as_array("Contacts.slide_dir", self.slide_dir, (None, K, 3)),
        )
        gap = np.full(fields["active"].shape, np.nan) if self.gap is None else self.gap
        fields["gap"] = as_array("Contacts.gap", gap, (None, K))
        same_length("Contacts", **fields)
        if np.any(np.isinf(fields["gap"])):
            raise InputError("Contacts.gap must be finite or NaN (unknown), it holds inf")
        if np.any(fields["sliding"] & ~fields["active"]):
            raise InputError("Contacts.sliding is set for a finger that is not active")
        object.__setattr__(self, "finger_names", names)
        for k, v in fields.items():
            object.__setattr__(self, k, v)

    def __len__(self) -> int:
        return self.active.shape[0]


@dataclass(frozen=True)
class ColourVideo:
    """The colour stream of an RGB-D camera: its own images, calibration and timestamps.

    Attributes:
        rgb: Images, shape (T, H, W, 3), uint8, sRGB-encoded (gamma applied, white-balanced), row 0
            at the top, channels red, green, blue.
        fps: Frame rate in [Hz].
        calib: The colour camera's calibration (its own intrinsics, image size and pose in the
            world; OpenCV convention, zero distortion), shape matching ``rgb``.
        t_s: Timestamp of each frame, shape (T,), [s]: the middle of its exposure.
        exposure_s: Exposure time in [s] (each frame integrates light over ``t_s[k] -+ exposure_s / 2``;
            0: an instantaneous frame).
    """

    rgb: np.ndarray
    fps: float
    calib: Calibration
    t_s: np.ndarray
    exposure_s: float = 0.0

    def __post_init__(self):
        rgb = np.asarray(self.rgb)
        if rgb.dtype != np.uint8:
            raise InputError(f"ColourVideo.rgb must be uint8, got {rgb.dtype}")
        if rgb.ndim != 4 or rgb.shape[3] != 3:
            raise InputError(f"ColourVideo.rgb must have shape (T, H, W, 3), got {rgb.shape}")
        if not isinstance(self.calib, Calibration):
            raise InputError(f"ColourVideo.calib must be an fsv.Calibration, got {type(self.calib).__name__}")
        if rgb.shape[1:3] != (self.calib.height, self.calib.width):
            raise InputError(f"ColourVideo.rgb is {rgb.shape[2]}x{rgb.shape[1]}, its calibration says "
                             f"{self.calib.width}x{self.calib.height}")
        positive("ColourVideo.fps", self.fps, "a positive number of Hz")
        t = as_array("ColourVideo.t_s", self.t_s, (rgb.shape[0],))
        finite("ColourVideo.t_s", t)
        if not (np.isfinite(self.exposure_s) and 0 <= self.exposure_s <= 1.0 / self.fps):
            raise InputError(f"ColourVideo.exposure_s must lie in [0, 1/fps = {1.0 / self.fps:g}] s, got {self.exposure_s!r}")
        rgb = rgb.copy() if rgb.flags.writeable else rgb
        rgb.setflags(write=False)
        object.__setattr__(self, "rgb", rgb)
        object.__setattr__(self, "t_s", t)
        object.__setattr__(self, "fps", float(self.fps))
        object.__setattr__(self, "exposure_s", float(self.exposure_s))

    @property
    def num_frames(self) -> int:
        return self.rgb.shape[0]
