"""Per-frame labels in a stream's camera: projection, keypoint visibility, segmentation, the box's
pose in BOP's convention and the contacts in the camera frame.

Conventions (docs/camera.md): OpenCV pinhole camera, x right, y down, z forward; ``T_world_cam = [R t]``
maps camera points to world points, so a world point p is ``x_c = R^T (p - t)`` in the camera;
``u = fx x / z + cx``, ``v = fy y / z + cy`` with pixel centres at integer coordinates; zero
distortion. Every formula is written out as elementwise ``+ - * /`` in a fixed order (no BLAS, no
fused multiply-add): the same bits on every machine.
"""

from __future__ import annotations

import numpy as np

from benchmark.camera.keypoints import KEYPOINT_FINGER, KEYPOINT_ON_PALM, keypoint_tolerance
from benchmark.camera.scene import LABEL_BOX, LABEL_FINGER0, LABEL_NONE, LABEL_PALM, LABEL_TABLE
from benchmark.errors import BenchmarkError
from fsv import Calibration

VISIBLE = 0
"""The keypoint is seen: nothing lies in front of it but its own part's surface (within its tolerance)."""
OCCLUDED_BY_BOX = 1
"""The box lies in front of the keypoint."""
OCCLUDED_BY_HAND = 2
"""Another part of the hand lies in front of it, or its own part by more than its tolerance."""
OFF_IMAGE = 3
"""Its nearest pixel is outside the image, or it lies behind the camera (z <= 0)."""
OCCLUDED_BY_TABLE = 4
"""The table (or other static environment) lies in front of it."""
VISIBILITY_CODES = {VISIBLE: "visible", OCCLUDED_BY_BOX: "occluded by the box", OCCLUDED_BY_HAND: "occluded by the hand",
                    OFF_IMAGE: "off the image", OCCLUDED_BY_TABLE: "occluded by the table"}
"""Visibility code -> meaning."""

SEG_BACKGROUND, SEG_TABLE, SEG_BOX, SEG_HAND = 0, 1, 2, 3
"""Segmentation classes: 0 background (nothing seen), 1 table, 2 box, 3 hand."""
SEGMENTATION_CLASSES = {SEG_BACKGROUND: "background", SEG_TABLE: "table", SEG_BOX: "box", SEG_HAND: "hand"}
"""Segmentation class -> name."""

_NUM_FINGERS = 5
_UNKNOWN = 255
_SEG_LUT = np.full(256, _UNKNOWN, dtype=np.uint8)
_SEG_LUT[LABEL_NONE] = SEG_BACKGROUND
_SEG_LUT[LABEL_TABLE] = SEG_TABLE
_SEG_LUT[LABEL_BOX] = SEG_BOX
_SEG_LUT[LABEL_PALM : LABEL_FINGER0 + _NUM_FINGERS] = SEG_HAND
_OCCLUDER_LUT = np.full(256, _UNKNOWN, dtype=np.uint8)
_OCCLUDER_LUT[LABEL_TABLE] = OCCLUDED_BY_TABLE
_OCCLUDER_LUT[LABEL_BOX] = OCCLUDED_BY_BOX
_OCCLUDER_LUT[LABEL_PALM : LABEL_FINGER0 + _NUM_FINGERS] = OCCLUDED_BY_HAND


def _calib(calib) -> Calibration:
    if not isinstance(calib, Calibration):
        raise BenchmarkError(f"calib must be an fsv.Calibration, got {type(calib).__name__}")
    K = calib.K
    if K[0, 1] != 0.0 or K[1, 0] != 0.0 or tuple(K[2]) != (0.0, 0.0, 1.0):
        raise BenchmarkError(f"calib.K must be [[fx, 0, cx], [0, fy, cy], [0, 0, 1]] (no skew), got {K.tolist()}")
    return calib


def _points(name: str, points, last: int) -> np.ndarray:
    p = np.asarray(points, dtype=np.float64)
    if p.ndim < 1 or p.shape[-1] != last:
        raise BenchmarkError(f"{name} must have shape (..., {last}), got {p.shape}")
    return p


def camera_from_world(points_world, calib: Calibration) -> np.ndarray:
    """World points in the camera frame: ``x_c = R^T (p - t)`` with ``T_world_cam = [R t]``.

    Row i of ``R^T`` is column i of R: ``x_c[i] = (R[0,i] dx + R[1,i] dy) + R[2,i] dz``, d = p - t.

    Args:
        points_world: (..., 3), [m].
        calib: The stream's calibration.

    Returns:
        (..., 3) float64, [m].
    """
    calib = _calib(calib)
    p = _points("points_world", points_world, 3)
    R, t = calib.T_world_cam[:3, :3], calib.T_world_cam[:3, 3]
    dx, dy, dz = p[..., 0] - t[0], p[..., 1] - t[1], p[..., 2] - t[2]
    out = np.empty(p.shape)
    for i in range(3):
        out[..., i] = (R[0, i] * dx + R[1, i] * dy) + R[2, i] * dz
    return out


def project(points_world, calib: Calibration) -> tuple[np.ndarray, np.ndarray]:
    """Pixel coordinates and depth of world points in a stream's camera.

    ``(x, y, z) = R^T (p - t)`` (:func:`camera_from_world`), then ``u = (fx * x) / z + cx`` and
    ``v = (fy * y) / z + cy``, evaluated in that order. Pixel (col, row) has its centre at
    (u, v) = (col, row); zero distortion.

    Args:
        points_world: (..., 3), [m].
        calib: The stream's calibration (its K, T_world_cam).

    Returns:
        ``(uv, z)``: pixel coordinates (..., 2) float64 [px] (NaN where z <= 0, behind the camera)
        and depth along the optical axis (..., ) float64 [m], the quantity the depth image holds.
    """
    calib = _calib(calib)
    xc = camera_from_world(points_world, calib)
    fx, fy, cx, cy = calib.K[0, 0], calib.K[1, 1], calib.K[0, 2], calib.K[1, 2]
    x, y, z = xc[..., 0], xc[..., 1], xc[..., 2]
    front = z > 0.0
    zs = np.where(front, z, 1.0)
    uv = np.empty(z.shape + (2,))
    uv[..., 0] = np.where(front, (fx * x) / zs + cx, np.nan)
    uv[..., 1] = np.where(front, (fy * y) / zs + cy, np.nan)
    return uv, z.copy()


def nearest_pixel(uv) -> tuple[np.ndarray, np.ndarray]:
    """The pixel whose centre is nearest: ``col = floor(u + 0.5)``, ``row = floor(v + 0.5)``.

    A coordinate exactly half-way between two centres goes to the higher index. NaN gives -1.

    Args:
        uv: (..., 2) [px].

    Returns:
        ``(col, row)``, each (...) int64.
    """
    uv = _points("uv", uv, 2)
    ok = np.isfinite(uv)
    f = np.floor(np.where(ok, uv, -1.0) + 0.5)
    f = np.clip(f, -1.0, 2.0**31)
    return f[..., 0].astype(np.int64), f[..., 1].astype(np.int64)


def visibility(uv, z, exact_depth, labels, *, finger_of_keypoint, tol_m, palm_is_own=None) -> np.ndarray:
    """Visibility of keypoints in one frame of one stream, against its exact depth and labels.

    At the keypoint's nearest pixel (:func:`nearest_pixel`) the camera sees depth d and label l:

    - ``OFF_IMAGE`` if z <= 0 or the pixel is outside the image;
    - ``VISIBLE`` if nothing is seen there (d = 0), or d >= z (what is seen lies behind the
      keypoint), or l is the keypoint's own part (its digit, 10 + k; the palm, 9, where
      ``palm_is_own``) and d >= z - tol (its own surface, over it);
    - otherwise occluded by what is seen: ``OCCLUDED_BY_BOX`` (2), ``OCCLUDED_BY_TABLE`` (1),
      ``OCCLUDED_BY_HAND`` (9 and up: another part of the hand, or its own part more than tol in front).

    Comparisons in float64 of the float32 depth; no arithmetic but ``z - tol``.

    Args:
        uv: Pixel coordinates, (N, 2) [px] (:func:`project`).
        z: Depth along the optical axis, (N,) [m].
        exact_depth: The frame's noise-free depth, (H, W) float32 [m], 0 where nothing is seen.
        labels: The frame's label image, (H, W) uint8 (``benchmark.camera.scene``'s values).
        finger_of_keypoint: Digit of each keypoint (thumb 0), -1 for a palm point, (N,) int.
        tol_m: How far in front of the keypoint its own part's surface may be, scalar or (N,), [m].
        palm_is_own: Where the palm's surface (label 9) counts as the keypoint's own too, (N,)
            bool; None: where ``finger_of_keypoint`` is -1.

    Returns:
        Codes (N,) uint8: :data:`VISIBLE`, :data:`OCCLUDED_BY_BOX`, :data:`OCCLUDED_BY_HAND`,
        :data:`OFF_IMAGE`, :data:`OCCLUDED_BY_TABLE`.

    Raises:
        BenchmarkError: On mismatched shapes, a depth that is not float32, or a label with no class.
    """
    uv = _points("uv", uv, 2)
    if uv.ndim != 2:
        raise BenchmarkError(f"uv must have shape (N, 2) (one frame), got {uv.shape}")
    n = uv.shape[0]
    z = np.asarray(z, dtype=np.float64)
    depth = np.asarray(exact_depth)
    lab = np.asarray(labels)
    if z.shape != (n,):
        raise BenchmarkError(f"z must have shape ({n},), got {z.shape}")
    if depth.ndim != 2 or depth.dtype != np.float32:
        raise BenchmarkError(f"exact_depth must be one (H, W) float32 frame, got {depth.shape} {depth.dtype}")
    if lab.shape != depth.shape or lab.dtype != np.uint8:
        raise BenchmarkError(f"labels must be (H, W) = {depth.shape} uint8, got {lab.shape} {lab.dtype}")
    finger = np.asarray(finger_of_keypoint)
    if finger.shape != (n,) or not np.issubdtype(finger.dtype, np.integer) or np.any(finger < -1) \
            or np.any(finger >= _NUM_FINGERS):
        raise BenchmarkError(f"finger_of_keypoint must be ({n},) integers in [-1, {_NUM_FINGERS - 1}], got {finger!r}")
    tol = np.broadcast_to(np.asarray(tol_m, dtype=np.float64), (n,)) if np.ndim(tol_m) == 0 else np.asarray(tol_m, np.float64)
    if tol.shape != (n,) or not np.all(np.isfinite(tol) & (tol >= 0)):
        raise BenchmarkError(f"tol_m must be a non-negative scalar or ({n},) [m], got {tol_m!r}")
    palm = finger < 0 if palm_is_own is None else np.asarray(palm_is_own)
    if palm.shape != (n,) or palm.dtype != np.bool_:
        raise BenchmarkError(f"palm_is_own must be ({n},) bool, got {palm_is_own!r}")
    H, W = depth.shape
    col, row = nearest_pixel(uv)
    inside = (z > 0.0) & (col >= 0) & (col < W) & (row >= 0) & (row < H)
    codes = np.full(n, OFF_IMAGE, dtype=np.uint8)
    idx = np.flatnonzero(inside)
    d = depth[row[idx], col[idx]].astype(np.float64)
    seen = lab[row[idx], col[idx]]
    own = (seen == (LABEL_FINGER0 + finger[idx])) | (palm[idx] & (seen == LABEL_PALM))
    vis = (d == 0.0) | (d >= z[idx]) | (own & (d >= z[idx] - tol[idx]))
    occluder = _OCCLUDER_LUT[seen]
    bad = ~vis & (occluder == _UNKNOWN)
    if np.any(bad):
        raise BenchmarkError(f"label {int(seen[bad][0])} has no occluder class; accepted labels: 1, 2, 9-14")
    codes[idx] = np.where(vis, VISIBLE, occluder)
    return codes


def keypoint_visibility(uv, z, exact_depth, labels, hand) -> np.ndarray:
    """:func:`visibility` of the 21 keypoints of ``benchmark.camera.keypoints`` for a hand model:
    ``finger_of_keypoint = KEYPOINT_FINGER``, ``palm_is_own = KEYPOINT_ON_PALM`` and
    ``tol_m = keypoint_tolerance(hand)`` (1.5 local radii). Returns (21,) uint8 codes."""
    return visibility(uv, z, exact_depth, labels, finger_of_keypoint=KEYPOINT_FINGER, tol_m=keypoint_tolerance(hand),
                      palm_is_own=KEYPOINT_ON_PALM)


def segmentation(labels) -> np.ndarray:
    """Coarse segmentation classes of label images: 0 background, 1 table, 2 box, 3 hand.

    Label values (the fine segmentation, ``benchmark.camera.scene``): 0 nothing -> 0, 1 table -> 1,
    2 box -> 2, 9 palm and 10 + k finger k (k = 0..4, thumb first) -> 3.

    Args:
        labels: Label images, any shape, uint8.

    Returns:
        Classes, same shape, uint8.

    Raises:
        BenchmarkError: If a label value has no class (3-8, 15 and up) or the dtype is not uint8.
    """
    lab = np.asarray(labels)
    if lab.dtype != np.uint8:
        raise BenchmarkError(f"labels must be uint8, got {lab.dtype}")
    out = _SEG_LUT[lab]
    if np.any(out == _UNKNOWN):
        raise BenchmarkError(f"label {int(lab[out == _UNKNOWN][0])} has no class; accepted: 0, 1, 2, 9-14")
    return out


def _quat_rot(quat) -> np.ndarray:
    """Rotation matrices of quaternions (w, x, y, z), normalised, in a fixed order: (T, 3, 3)."""
    q = _points("box_quat", quat, 4)
    n = np.sqrt(((q[..., 0] * q[..., 0] + q[..., 1] * q[..., 1]) + q[..., 2] * q[..., 2]) + q[..., 3] * q[..., 3])
    if np.any(~(n > 0)):
        raise BenchmarkError("box_quat has a zero or non-finite quaternion")
    w, x, y, z = (q[..., i] / n for i in range(4))
    R = np.empty(q.shape[:-1] + (3, 3))
    R[..., 0, 0] = 1.0 - 2.0 * (y * y + z * z)
    R[..., 0, 1] = 2.0 * (x * y - w * z)
    R[..., 0, 2] = 2.0 * (x * z + w * y)
    R[..., 1, 0] = 2.0 * (x * y + w * z)
    R[..., 1, 1] = 1.0 - 2.0 * (x * x + z * z)
    R[..., 1, 2] = 2.0 * (y * z - w * x)
    R[..., 2, 0] = 2.0 * (x * z - w * y)
    R[..., 2, 1] = 2.0 * (y * z + w * x)
    R[..., 2, 2] = 1.0 - 2.0 * (x * x + y * y)
    return R


def _cam_rot(R_world_obj: np.ndarray, calib: Calibration) -> np.ndarray:
    """cam_R_obj = R^T world_R_obj: entry (i, j) = (R[0,i] W[0,j] + R[1,i] W[1,j]) + R[2,i] W[2,j]."""
    R = calib.T_world_cam[:3, :3]
    out = np.empty(R_world_obj.shape)
    for i in range(3):
        for j in range(3):
            out[..., i, j] = (R[0, i] * R_world_obj[..., 0, j] + R[1, i] * R_world_obj[..., 1, j]) \
                + R[2, i] * R_world_obj[..., 2, j]
    return out


def _rotate(M: np.ndarray, v: np.ndarray) -> np.ndarray:
    """M v in a fixed order: out[i] = (M[i,0] v0 + M[i,1] v1) + M[i,2] v2 (M broadcast against v)."""
    out = np.empty(np.broadcast_shapes(M.shape[:-1], v.shape))
    for i in range(3):
        out[..., i] = (M[..., i, 0] * v[..., 0] + M[..., i, 1] * v[..., 1]) + M[..., i, 2] * v[..., 2]
    return out


def bop_pose(box_pos, box_quat, calib: Calibration) -> tuple[np.ndarray, np.ndarray]:
    """The box's pose in a stream's camera in BOP's convention (``scene_gt.json``).

    The model frame is the box's: origin at its centre of mass (the box's centre), axes along its
    edges (``Truth``'s object frame). A model point X [mm] is in the camera at
    ``cam_R_m2c X + cam_t_m2c`` [mm]. ``cam_R_m2c = R^T world_R_object`` and
    ``cam_t_m2c = 1000 R^T (box_pos - t)``, ``T_world_cam = [R t]``.

    Args:
        box_pos: Box centre of mass per frame, world, (T, 3), [m].
        box_quat: world_q_object (w, x, y, z) per frame, (T, 4) (normalised here).
        calib: The stream's calibration.

    Returns:
        ``(cam_R_m2c (T, 3, 3), cam_t_m2c (T, 3) [mm])``; BOP stores ``cam_R_m2c`` row-major as
        9 numbers: ``cam_R_m2c[k].ravel()``.
    """
    calib = _calib(calib)
    pos = _points("box_pos", box_pos, 3)
    Rwo = _quat_rot(box_quat)
    if pos.shape[:-1] != Rwo.shape[:-2]:
        raise BenchmarkError(f"box_pos {pos.shape} and box_quat {np.shape(box_quat)} must have the same frames")
    return _cam_rot(Rwo, calib), camera_from_world(pos, calib) * 1000.0


def bop_scene_gt(cam_R_m2c, cam_t_m2c, obj_id: int = 1) -> dict:
    """``scene_gt.json``'s content: ``{"k": [{"cam_R_m2c": [9], "cam_t_m2c": [3], "obj_id": obj_id}]}``
    per frame k (one object), from :func:`bop_pose`."""
    R, t = np.asarray(cam_R_m2c, np.float64), np.asarray(cam_t_m2c, np.float64)
    if R.ndim != 3 or R.shape[1:] != (3, 3) or t.shape != (R.shape[0], 3):
        raise BenchmarkError(f"cam_R_m2c must be (T, 3, 3) and cam_t_m2c (T, 3), got {R.shape}, {t.shape}")
    return {str(k): [{"cam_R_m2c": [float(v) for v in R[k].ravel()], "cam_t_m2c": [float(v) for v in t[k]],
                      "obj_id": int(obj_id)}] for k in range(R.shape[0])}


def contacts_in_camera(truth, calib: Calibration) -> dict:
    """Every finger's contact point, normal and force in a stream's camera frame.

    The truth holds them in the object frame (the box's pose per frame): ``point_cam = cam_R_m2c p +
    R^T (box_pos - t)``, ``normal_cam = cam_R_m2c n``, ``force_cam = cam_R_m2c f``, with
    ``cam_R_m2c`` of :func:`bop_pose` (metres here, not BOP's millimetres). Frames where a finger
    does not touch keep the truth's values (zero force; ``truth.contact_active`` says which).

    Args:
        truth: A :class:`benchmark.world.truth.Truth`.
        calib: The stream's calibration.

    Returns:
        ``{"point_cam": (T, K, 3) [m], "normal_cam": (T, K, 3) unit, "force_cam": (T, K, 3) [N]}``
        float64 (force of the finger on the box).
    """
    calib = _calib(calib)
    M = _cam_rot(_quat_rot(truth.box_quat), calib)[:, None]  # (T, 1, 3, 3)
    origin = camera_from_world(truth.box_pos, calib)[:, None]  # (T, 1, 3)
    p = _rotate(M, np.asarray(truth.contact_point, np.float64))
    point = np.empty(p.shape)
    for i in range(3):
        point[..., i] = p[..., i] + origin[..., i]
    return {"point_cam": point, "normal_cam": _rotate(M, np.asarray(truth.contact_normal, np.float64)),
            "force_cam": _rotate(M, np.asarray(truth.contact_force, np.float64))}
