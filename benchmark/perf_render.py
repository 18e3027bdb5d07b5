"""Speed of the depth renderer, against MuJoCo's own renderer on the same scene as a peer.

Run: ``python -m benchmark.perf_render [--frames N]``. It simulates a short episode of the
default scenario, then renders its frames at 320 x 240 three ways in this process:

- pyrender (this benchmark's renderer): exact depth + label image per frame;
- pyrender + the sensor model (what ``render()`` does per frame);
- MuJoCo's ``mujoco.Renderer`` with depth rendering (EGL) from an identical camera (same
  pose and intrinsics, added to the model as a MuJoCo camera).

It prints frames per second, the ratio against MuJoCo, and how far the two renderers' depths
differ on the pixels both see (a check that the scenes and cameras really are the same).
"""

from __future__ import annotations

import argparse
import os
import time

os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("PYOPENGL_PLATFORM", "egl")

import mujoco  # noqa: E402
import numpy as np  # noqa: E402

from benchmark.render import GL_FROM_CV, Camera, DepthRenderer, load_camera  # noqa: E402


def add_mujoco_camera(spec, camera: Camera, name: str = "depth_camera"):
    """Adds `camera` to a MuJoCo model spec as a MuJoCo camera with the same pose and intrinsics.

    MuJoCo cameras look along their -z axis with y up (OpenGL's convention), and their principal
    point is given as an offset in pixels from the image centre ((W - 1) / 2, (H - 1) / 2).
    """
    T = camera.T_world_cam @ GL_FROM_CV
    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, T[:3, :3].flatten())
    cam = spec.worldbody.add_camera(name=name, pos=T[:3, 3], quat=quat)
    cam.resolution = [camera.width, camera.height]
    cam.sensor_size = [camera.width * 1e-5, camera.height * 1e-5]  # any size: focal is in pixels
    cam.focal_pixel = [camera.K[0, 0], camera.K[1, 1]]
    cam.principal_pixel = [camera.K[0, 2] - (camera.width - 1) / 2, camera.K[1, 2] - (camera.height - 1) / 2]
    spec.visual.global_.offwidth = max(spec.visual.global_.offwidth, camera.width)
    spec.visual.global_.offheight = max(spec.visual.global_.offheight, camera.height)
    return cam


def _rate(fn, frames: int, repeats: int = 3) -> float:
    """Best frames per second over `repeats` passes of fn(k) for k in range(frames)."""
    best = np.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        for k in range(frames):
            fn(k)
        best = min(best, time.perf_counter() - t0)
    return frames / best
