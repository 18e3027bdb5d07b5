"""Camera views: where the depth camera stands. View 0 is ``sim_assets/camera.yaml``'s, the paper's
set-up (across the table from the user, a little to the side and above, about 0.55 m from the
box); view N >= 1 is drawn around it from a generator seeded with N, so a view is the same camera
for every scenario that names it.

A drawn view keeps the intrinsics and the image's "up" (the world's +z) and draws, independently
and uniformly, the camera's distance from its target, its elevation above the table and its
azimuth about the vertical (:data:`DISTANCE_M`, :data:`ELEVATION_DEG`, :data:`AZIMUTH_DEG`: view 0
has 0.549 m, 37.0 degrees and 65.8 degrees), and the target around the box's start
(:data:`TARGET_JITTER_M`). The ranges are choices: every drawn camera sees the fingers' side of the
box (azimuth within 45 degrees of facing the user) from a height a tripod on the table allows, within
the DS325's range (0.15-1.0 m).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from benchmark.camera.camera import Camera, load_camera, look_at
from fsv.linalg import norm

DISTANCE_M = (0.45, 0.70)
"""Range of the camera's distance from its target, [m]."""
ELEVATION_DEG = (25.0, 60.0)
"""Range of the camera's elevation above the table, seen from its target, [deg]."""
AZIMUTH_DEG = (45.0, 135.0)
"""Range of the camera's azimuth about the vertical, from the world's +x axis, [deg] (90: facing the user)."""
TARGET = (0.0, 0.0, 0.09)
"""The point view 0 looks at (sim_assets/camera.yaml's ``look_at``), [m]."""
TARGET_JITTER_M = 0.03
"""Half-width of the uniform draw of the target's x and y around :data:`TARGET`, [m]."""


@dataclasses.dataclass(frozen=True)
class View:
    """One camera pose: its index, distance [m], elevation and azimuth [deg], and target [m]."""

    index: int
    distance_m: float
    elevation_deg: float
    azimuth_deg: float
    target: tuple

    def record(self) -> dict:
        """JSON of the view."""
        return {"index": self.index, "distance_m": self.distance_m, "elevation_deg": self.elevation_deg,
                "azimuth_deg": self.azimuth_deg, "target_m": list(self.target)}


def _spherical(position, target) -> tuple:
    d = np.asarray(position, float) - np.asarray(target, float)
    dist = norm(d)
    return dist, math.degrees(math.asin(d[2] / dist)), math.degrees(math.atan2(d[1], d[0]))


def view_of(index: int) -> View:
    """View ``index`` (0: camera.yaml's; N >= 1: drawn with seed N, see the module docstring)."""
    if index == 0:
        cam = load_camera()
        dist, elev, azim = _spherical(cam.T_world_cam[:3, 3], TARGET)
        return View(0, dist, elev, azim, TARGET)
    rng = np.random.default_rng(np.random.SeedSequence([int(index), *b"view"]))
    dist = float(rng.uniform(*DISTANCE_M))
    elev = float(rng.uniform(*ELEVATION_DEG))
    azim = float(rng.uniform(*AZIMUTH_DEG))
    jitter = rng.uniform(-TARGET_JITTER_M, TARGET_JITTER_M, 2)
    target = (float(TARGET[0] + jitter[0]), float(TARGET[1] + jitter[1]), TARGET[2])
    return View(int(index), dist, elev, azim, target)


def camera_of(index: int) -> Camera:
    """The camera of view ``index``: camera.yaml's intrinsics, the view's pose."""
    cam = load_camera()
    if index == 0:
        return cam
    v = view_of(index)
    e, a = math.radians(v.elevation_deg), math.radians(v.azimuth_deg)
    offset = v.distance_m * np.array([math.cos(e) * math.cos(a), math.cos(e) * math.sin(a), math.sin(e)])
    return dataclasses.replace(cam, T_world_cam=look_at(np.asarray(v.target) + offset, v.target))
