"""The depth camera: its intrinsics and pose (``sim_assets/camera.yaml``), and the projection of its
OpenCV frame for OpenGL (:func:`clip_from_cam`, ``GL_FROM_CV``)."""

from __future__ import annotations

import importlib.resources
from dataclasses import dataclass

import numpy as np
import yaml

from benchmark.errors import BenchmarkError
from fsv import Calibration
from fsv.linalg import norm

GL_FROM_CV = np.diag([1.0, -1.0, -1.0, 1.0])
"""Maps OpenCV camera coordinates to OpenGL camera coordinates (and back: it is its own inverse)."""

@dataclass(frozen=True)
class Camera:
    """A pinhole depth camera in the world.

    Attributes:
        width: Image width in pixels.
        height: Image height in pixels.
        K: OpenCV intrinsics, shape (3, 3), pixels.
        T_world_cam: Camera pose in the world (OpenCV camera frame), shape (4, 4).
        fps: Nominal frame rate in [Hz] (the scenario's fps is the one used).
        znear: Near clipping plane of the renderer in [m].
        zfar: Far clipping plane of the renderer in [m].
    """

    width: int
    height: int
    K: np.ndarray
    T_world_cam: np.ndarray
    fps: float
    znear: float
    zfar: float

    def __post_init__(self):
        calib = self.calibration()
        if not 0 < self.znear < self.zfar:
            raise BenchmarkError(f"camera clipping planes need 0 < znear < zfar, got {self.znear}, {self.zfar}")
        object.__setattr__(self, "K", calib.K)
        object.__setattr__(self, "T_world_cam", calib.T_world_cam)

    def calibration(self) -> Calibration:
        """The calibration handed to `fsv` (intrinsics, camera-to-world pose, image size)."""
        return Calibration(K=self.K, T_world_cam=self.T_world_cam, width=self.width, height=self.height)


def look_at(position, target, up=(0.0, 0.0, 1.0)) -> np.ndarray:
    """Camera pose (OpenCV frame) at `position` whose optical axis points at `target`.

    Args:
        position: Camera centre in the world, shape (3,), [m].
        target: A world point on the optical axis, shape (3,), [m].
        up: World direction that appears "up" in the image, shape (3,).

    Returns:
        T_world_cam, shape (4, 4): x right, y down (towards -up), z forward.
    """
    p, t, u = (np.asarray(v, dtype=float).reshape(3) for v in (position, target, up))
    z = t - p
    if norm(z) < 1e-9:
        raise BenchmarkError(f"camera position and look_at coincide: {p}")
    z /= norm(z)  # fsv.linalg's norm, not BLAS's: the same pose under every kernel
    x = np.cross(z, u)
    if norm(x) < 1e-9:
        raise BenchmarkError(f"camera up {u} is parallel to the optical axis {z}")
    x /= norm(x)
    y = np.cross(z, x)
    T = np.eye(4)
    T[:3, :3] = np.stack([x, y, z], axis=1)
    T[:3, 3] = p
    return T


def load_camera(path=None) -> Camera:
    """Reads the camera (intrinsics from the field of view, pose from position and look-at).

    Args:
        path: A YAML file like ``sim_assets/camera.yaml`` (the default).
    """
    if path is None:
        text = importlib.resources.files("sim_assets").joinpath("camera.yaml").read_text()
    else:
        with open(path) as f:
            text = f.read()
    c = yaml.safe_load(text)
    W, H = int(c["width"]), int(c["height"])
    hfov, vfov = np.deg2rad(float(c["hfov_deg"])), np.deg2rad(float(c["vfov_deg"]))
    if not (0 < hfov < np.pi and 0 < vfov < np.pi):
        raise BenchmarkError(f"camera field of view must be in (0, 180) degrees, got {c['hfov_deg']} x {c['vfov_deg']}")
    K = np.array(
        [[(W / 2) / np.tan(hfov / 2), 0.0, (W - 1) / 2], [0.0, (H / 2) / np.tan(vfov / 2), (H - 1) / 2], [0, 0, 1]]
    )
    return Camera(
        width=W,
        height=H,
        K=K,
        T_world_cam=look_at(c["position"], c["look_at"], c.get("up", (0, 0, 1))),
        fps=float(c["fps"]),
        znear=float(c["znear"]),
        zfar=float(c["zfar"]),
    )


def camera_calibration(path=None) -> Calibration:
    """The :class:`fsv.Calibration` of the camera in ``sim_assets/camera.yaml`` (or `path`)."""
    return load_camera(path).calibration()


def clip_from_cam(camera: Camera) -> np.ndarray:
    """OpenGL projection of points in the OpenCV camera frame, shape (4, 4).

    A point (X, Y, Z) lands at the window position (u + 0.5, v + 0.5), where
    (u, v, 1) = K (X, Y, Z) / Z is its OpenCV pixel (OpenGL puts pixel centres at half-integers),
    with clip w = Z and Z in [znear, zfar] mapped to normalised depth [-1, 1]. Framebuffer row v
    is image row v, so the read-back images need no flip; triangles facing the camera are
    clockwise in the window (y points down the image).
    """
    K, W, H = camera.K, camera.width, camera.height
    n, f = camera.znear, camera.zfar
    return np.array(
        [
            [2 * K[0, 0] / W, 2 * K[0, 1] / W, (2 * K[0, 2] + 1) / W - 1, 0.0],
            [0.0, 2 * K[1, 1] / H, (2 * K[1, 2] + 1) / H - 1, 0.0],
            [0.0, 0.0, (f + n) / (f - n), -2 * f * n / (f - n)],
            [0.0, 0.0, 1.0, 0.0],
        ]
    )
