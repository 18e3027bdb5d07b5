"""The camera as the tracker uses it: pixel rays in the world frame, projection, the table's depth.

A pixel (u, v) (OpenCV, pixel centres at integer coordinates) sees the world point
``origin + z * ray[v, u]``, where ``z`` is the depth along the optical axis (what a depth frame
stores) and ``ray`` is scaled so that its component along the optical axis is 1.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fsv.errors import InputError
from fsv.linalg import rows_mt, vm
from fsv.types import Calibration


@dataclass(frozen=True)
class CameraRays:
    """Precomputed world-frame rays of every pixel of a calibrated camera.

    Attributes:
        origin: Camera centre in the world, shape (3,), [m].
        ray: Per-pixel ray directions in the world, scaled to unit optical-axis component,
            shape (H*W, 3) (row-major pixel index v * W + u).
        table_depth: Depth at which each pixel's ray meets the table plane z = table_z,
            shape (H*W,), [m]; +inf where the ray never meets it in front of the camera.
        width: Image width in pixels.
        height: Image height in pixels.
    """

    origin: np.ndarray
    ray: np.ndarray
    table_depth: np.ndarray
    width: int
    height: int

    @classmethod
    def from_calibration(cls, calib: Calibration, table_z: float = 0.0) -> "CameraRays":
        """Builds the rays of ``calib``; the table is the plane z = ``table_z`` of the world."""
        if not isinstance(calib, Calibration):
            raise InputError(f"calib must be an fsv.Calibration, got {type(calib).__name__}")
        if not np.isfinite(table_z):
            raise InputError(f"table_z must be a finite height in metres, got {table_z!r}")
        v, u = np.mgrid[0 : calib.height, 0 : calib.width]
        fx, fy, cx, cy = calib.K[0, 0], calib.K[1, 1], calib.K[0, 2], calib.K[1, 2]
        d_cam = np.stack([(u - cx) / fx, (v - cy) / fy, np.ones_like(u, dtype=float)], -1).reshape(-1, 3)
        R = calib.T_world_cam[:3, :3]
        origin = calib.T_world_cam[:3, 3].copy()
        ray = rows_mt(d_cam, R)
        with np.errstate(divide="ignore", invalid="ignore"):
            t = (table_z - origin[2]) / ray[:, 2]
        t = np.where(np.isfinite(t) & (t > 0), t, np.inf)
        return cls(origin=origin, ray=ray, table_depth=t, width=calib.width, height=calib.height)

    def project(self, calib: Calibration, points_world: np.ndarray) -> np.ndarray:
        """Projects world points to pixel coordinates (u, v) and depth: (N, 3) -> (N, 3)."""
        T = calib.T_world_cam
        p_cam = vm(np.asarray(points_world) - T[:3, 3], T[:3, :3])
        z = p_cam[:, 2]
        u = calib.K[0, 0] * p_cam[:, 0] / z + calib.K[0, 2]
        v = calib.K[1, 1] * p_cam[:, 1] / z + calib.K[1, 2]
        return np.stack([u, v, z], -1)

    def points(self, depth_m: np.ndarray, index: np.ndarray | None = None) -> np.ndarray:
        """World points of the given pixels of a depth image: (H, W) -> (N, 3), [m]."""
        z = np.asarray(depth_m, dtype=float).reshape(-1)
        if index is None:
            return self.origin + z[:, None] * self.ray
        return self.origin + z[index, None] * self.ray[index]
