"""The per-frame labels of a rendered episode, per stream: what learned methods train on.

:class:`Annotations` holds, for every frame, the 21 hand keypoints in the world
(:mod:`benchmark.camera.keypoints`, OpenPose order) and, for each rendered stream
(:class:`StreamLabels`), those keypoints in the stream's pixels with their depth and visibility,
the box pose in BOP's convention and the per-finger contacts in the stream's camera frame
(:mod:`benchmark.camera.annotations`). The segmentation is the stream's label image (the episode's
``labels`` and ``colour_labels``; :func:`benchmark.camera.annotations.segmentation` maps it to
hand, box, table and background).

A :class:`Labeller` is fed each stream's exact (noise-free) depth and label image frame by frame
inside the render loop, where they exist anyway, so the visibility costs no second render and no
video-sized buffer. Conventions: docs/camera.md.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from benchmark.camera.annotations import bop_pose, contacts_in_camera, project, visibility
from benchmark.camera.keypoints import KEYPOINT_FINGER, KEYPOINT_ON_PALM, keypoint_tolerance, keypoints_world
from benchmark.errors import BenchmarkError
from fsv import Calibration
from fsv.types import STREAMS

_STREAM_FIELDS = ("keypoints_uv", "keypoints_z", "keypoint_visibility", "cam_R_m2c", "cam_t_m2c", "contact_point_cam",
                  "contact_normal_cam", "contact_force_cam")


@dataclass(frozen=True)
class StreamLabels:
    """One stream's labels, T frames, K fingers.

    Attributes:
        keypoints_uv: The 21 keypoints' pixels, (T, 21, 2) float64 (OpenCV: pixel centres at
            integers); NaN behind the camera.
        keypoints_z: Their depth along the optical axis, (T, 21) float64, [m].
        keypoint_visibility: (T, 21) uint8: 0 visible, 1 occluded by the box, 2 by the hand, 3 off
            the image, 4 by the table (:data:`benchmark.camera.annotations.VISIBILITY_CODES`).
        cam_R_m2c: The box's rotation model-to-camera, (T, 3, 3) (BOP's ``cam_R_m2c``).
        cam_t_m2c: The box centre in the camera frame, (T, 3), [mm] (BOP's ``cam_t_m2c``).
        contact_point_cam: Each finger's centre of pressure in the camera frame, (T, K, 3), [m].
        contact_normal_cam: Its unit normal into the box, camera frame, (T, K, 3).
        contact_force_cam: Finger k's force on the box, camera frame, (T, K, 3), [N].
    """

    keypoints_uv: np.ndarray
    keypoints_z: np.ndarray
    keypoint_visibility: np.ndarray
    cam_R_m2c: np.ndarray
    cam_t_m2c: np.ndarray
    contact_point_cam: np.ndarray
    contact_normal_cam: np.ndarray
    contact_force_cam: np.ndarray


@dataclass(frozen=True)
class Annotations:
    """The labels of a rendered episode: keypoints in the world and each stream's labels.

    Attributes:
        keypoints_world: The 21 hand keypoints (OpenPose order), (T, 21, 3) float64, world frame, [m].
        streams: ``{stream name: StreamLabels}`` for every rendered stream.
    """

    keypoints_world: np.ndarray
    streams: dict

    def arrays(self) -> dict:
        """Named arrays for the episode file's ``annotations`` section (``<stream>_<field>``)."""
        out = {"keypoints_world": self.keypoints_world}
        for name, labels in self.streams.items():
            out.update({f"{name}_{f}": getattr(labels, f) for f in _STREAM_FIELDS})
        return out

    @classmethod
    def from_arrays(cls, arrays: dict) -> "Annotations":
        """Inverse of :meth:`arrays` (raises KeyError for a missing array)."""
        streams = {s: StreamLabels(**{f: np.asarray(arrays[f"{s}_{f}"]) for f in _STREAM_FIELDS})
                   for s in STREAMS if f"{s}_keypoints_uv" in arrays}
        return cls(keypoints_world=np.asarray(arrays["keypoints_world"]), streams=streams)

    def with_stream(self, name: str, labels: StreamLabels) -> "Annotations":
        return replace(self, streams={**self.streams, name: labels})


class Labeller:
    """Builds one stream's :class:`StreamLabels` from the exact depth and labels of each frame.

    Args:
        world: The episode's :class:`benchmark.world.assets.World`.
        truth: Its truth.
        calib: The stream's calibration (the true one: labels are truth).
        keypoints: :func:`benchmark.camera.keypoints.keypoints_world` of the episode, (T, 21, 3),
            if already computed (another stream's labeller computed it).
    """

    def __init__(self, world, truth, calib: Calibration, keypoints: np.ndarray | None = None):
        self.keypoints_world = keypoints_world(world, truth) if keypoints is None else keypoints
        self.calib = calib
        self._uv, self._z = project(self.keypoints_world, calib)
        self._tol = keypoint_tolerance(world.hand)
        self._vis = np.full(self._z.shape, 255, dtype=np.uint8)
        R, t = bop_pose(truth.box_pos, truth.box_quat, calib)
        self._bop = (R, t)
        self._contacts = contacts_in_camera(truth, calib)

    def see(self, k: int, exact_depth: np.ndarray, labels: np.ndarray) -> None:
        """Frame ``k``'s visibility from its exact depth (H, W) float32 [m] and labels (H, W) uint8."""
        self._vis[k] = visibility(self._uv[k], self._z[k], exact_depth, labels, finger_of_keypoint=KEYPOINT_FINGER,
                                  tol_m=self._tol, palm_is_own=KEYPOINT_ON_PALM)

    def labels(self) -> StreamLabels:
        """The stream's labels (every frame must have been seen)."""
        if np.any(self._vis == 255):
            raise BenchmarkError(f"frames {np.flatnonzero(np.any(self._vis == 255, axis=1))[:5].tolist()} were not "
                                 "seen by the labeller")
        c = self._contacts
        return StreamLabels(keypoints_uv=self._uv, keypoints_z=self._z, keypoint_visibility=self._vis,
                            cam_R_m2c=self._bop[0], cam_t_m2c=self._bop[1], contact_point_cam=c["point_cam"],
                            contact_normal_cam=c["normal_cam"], contact_force_cam=c["force_cam"])
