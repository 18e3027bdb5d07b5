"""The colour camera: linear radiance of the scene on the CPU, motion blur, and the sensor.

Geometry is the depth renderer's (:class:`benchmark.camera.depth.DepthRenderer`: the same meshes,
capsules, skin posing and draw order), rasterised by :mod:`benchmark.camera.colour_kernels`, which
also keep each pixel's outward normal; so from the same camera the depth and labels are the same
bits as the depth renderer's. Each pixel is then shaded with

    L = albedo(p) * (ambient_rgb + sum_i light_rgb_i * max(0, -n . dir_i))

(p the ray's first hit, n its outward unit normal, dir_i the direction light i travels; no
shadows, no specular, no inter-reflection: stated limits), the albedo by label: the person's skin
on the hand (labels 9 and up), the box's printed face (looked up by p in the box geom's frame),
the table's texture (by p's world x, y) on the table and other static geoms, and the far wall's
constant radiance where nothing is hit (:mod:`benchmark.camera.appearance`). Normals are the
triangles' own (flat shading, also on the skin's mesh) and the capsules' exact ones.

Frame k is exposed over [t_k - e/2, t_k + e/2] (e the sensor's exposure); its radiance is the
mean of S sub-renders at s_j = e ((j + 0.5) / S - 0.5), j = 0..S-1, S odd so the middle one lies
at t_k (rendered last, so the renderer's buffers and ``data`` end at t_k; the radiance is summed in
float32 in that order). S adapts to the frame's motion: the largest image displacement d [px] of any drawn
vertex or capsule end between the exposure's start and end, S = ceil(d / blur_step_px) made odd,
between 1 and the sensor's ``max_samples`` (a still frame costs one render). The pulps are pressed
as at t_k in every sub-render. The labels and the depth of a frame are the middle sub-render's
(noise-free, at t_k).

Speed: the leading triangles welded to the world (the table) are drawn and shaded once per camera
(their pixels' depth, labels, normals and radiance kept); every sub-render starts from those
buffers and draws the moving geometry in the depth renderer's order, so the bits are those of a
full render, and only the pixels a moving primitive covers are shaded again.

The states within the exposure come from the caller's ``set_state(data, k, s)``; the truth holds
frames only at t_k, and :func:`interpolated_state` interpolates it (what :func:`render_colour` does).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

from benchmark.camera import colour_kernels as ck
from benchmark.camera import raster_kernels as rk
from benchmark.camera.appearance import appearance_of
from benchmark.camera.camera import Camera
from benchmark.camera.colour_sensor import ColourSensor, colour_camera, colour_preset
from benchmark.camera.depth import DepthRenderer, HandSkin, drawn_hand
from benchmark.camera.scene import LABEL_BOX, world_labels
from benchmark.camera.views import camera_of
from benchmark.errors import BenchmarkError
from benchmark.world.assets import build_world, set_frame
from fsv import Calibration, ColourVideo


@dataclass(frozen=True)
class ColourFrames:
    """A rendered colour video and its truth-side images.

    Attributes:
        rgb: sRGB images, (T, H, W, 3) uint8.
        labels: Label images of the middle sub-render (at t_k, noise-free), (T, H, W) uint8.
        calib: The colour camera's calibration.
        fps: Frame rate [Hz]; frame k at t_k = k / fps.
        exposure_s: Exposure time [s].
        samples: Sub-renders per frame, (T,) int64.
        t_s: Each frame's time, the middle of its exposure, (T,) [s] (k / fps).
    """

    rgb: np.ndarray
    labels: np.ndarray
    calib: Calibration
    fps: float
    exposure_s: float
    samples: np.ndarray
    t_s: np.ndarray

    @property
    def video(self) -> ColourVideo:
        """The colour stream as `fsv` receives it (:class:`fsv.ColourVideo`)."""
        return ColourVideo(rgb=self.rgb, fps=self.fps, calib=self.calib, t_s=self.t_s, exposure_s=self.exposure_s)


def _mat3_mul(A, B) -> np.ndarray:
    """A @ B for 3 x 3, in a fixed order (no BLAS)."""
    return np.array([[A[r, 0] * B[0, c] + A[r, 1] * B[1, c] + A[r, 2] * B[2, c] for c in range(3)] for r in range(3)])


def _mat3_vec(A, x) -> np.ndarray:
    """A @ x for 3 x 3 and (3,), in a fixed order (no BLAS)."""
    return np.array([A[r, 0] * x[0] + A[r, 1] * x[1] + A[r, 2] * x[2] for r in range(3)])


class ColourRenderer:
    """Linear-RGB radiance, exact depth and labels of a MuJoCo model's geoms from one camera, on the CPU.

    Args:
        model: A compiled ``mujoco.MjModel``.
        camera: The colour camera (:func:`benchmark.camera.colour_sensor.colour_camera`).
        labels: Label per geom, (ngeom,) uint8 (:func:`benchmark.camera.scene.world_labels`); at
            most one geom labelled box (2), a MuJoCo box, whose frame carries the print.
        appearance: The :class:`benchmark.camera.appearance.Appearance`.
        skin: Draw the hand as this skin (as :class:`DepthRenderer`).
    """

    def __init__(self, model, camera: Camera, labels: np.ndarray, appearance, *, skin: HandSkin | None = None):
        self._g = DepthRenderer(model, camera, labels, skin=skin)
        self.camera = camera
        self.appearance = appearance
        labels = np.asarray(labels)
        box = np.flatnonzero(labels == LABEL_BOX)
        if len(box) > 1:
            raise BenchmarkError(f"the colour renderer prints one box; {len(box)} geoms are labelled box ({LABEL_BOX})")
        self._box_body = -1
        self._box_R_bg, self._box_t_bg = np.eye(3), np.zeros(3)
        self._box_half = np.ones(3)
        if len(box):
            g = int(box[0])
            if int(model.geom_type[g]) != int(mujoco.mjtGeom.mjGEOM_BOX):
                raise BenchmarkError(f"the geom labelled box ({g}) must be a MuJoCo box, got type {model.geom_type[g]}")
            mat = np.zeros(9)
            mujoco.mju_quat2Mat(mat, model.geom_quat[g])
            self._box_body = int(model.geom_bodyid[g])
            self._box_R_bg, self._box_t_bg = mat.reshape(3, 3).copy(), np.array(model.geom_pos[g], dtype=np.float64)
            self._box_half = np.array(model.geom_size[g], dtype=np.float64)
        H, W = camera.height, camera.width
        self._nbuf = np.zeros((H, W, 3))
        self._ibuf = np.empty((H, W), dtype=np.int32)
        self._acc = np.zeros((H, W, 3), dtype=np.float32)
        R_wc = np.ascontiguousarray(camera.T_world_cam[:3, :3], dtype=np.float64)
        self._R_wc, self._t_wc = R_wc, np.ascontiguousarray(camera.T_world_cam[:3, 3], dtype=np.float64)
        light = appearance.lighting
        R_cw = np.ascontiguousarray(R_wc.T)
        self._light_dir = np.ascontiguousarray([_mat3_vec(R_cw, d) for d in np.asarray(light.direction)], dtype=np.float64)
        self._light_rgb = np.ascontiguousarray(light.rgb, dtype=np.float64)
        self._ambient = np.ascontiguousarray(light.ambient, dtype=np.float64)
        a = appearance
        self._box_base = np.ascontiguousarray(a.box_base)
        self._box_ink = np.ascontiguousarray(a.box_ink)
        self._box_par = np.ascontiguousarray(a.box_par)
        tri = self._g._tri
        self._ntri = len(tri["faces"])
        self._nskin = 0 if skin is None else len(skin.skin.faces)
        # the static prefix: the leading triangles welded to the world (the table), drawn and shaded
        # once per camera pose; every render starts from them and draws the rest in the same order
        on_world = np.all(tri["vertex_body"][tri["faces"]] == 0, axis=1) if self._ntri else np.zeros(0, bool)
        moving = np.flatnonzero(~on_world)
        self._n_static = int(moving[0]) if len(moving) else self._ntri
        self._dyn_faces = np.ascontiguousarray(tri["faces"][self._n_static:])
        self._dyn_labels = np.ascontiguousarray(tri["face_label"][self._n_static:])
        self._static_key = None
        self._static_z = np.empty((H, W))
        self._static_l = np.empty((H, W), dtype=np.uint8)
        self._static_i = np.empty((H, W), dtype=np.int32)
        self._static_n = np.zeros((H, W, 3))
        self._static_rad = np.zeros((H, W, 3), dtype=np.float32)

    @property
    def skin(self):
        """The skin drawn for the hand, or None (as :attr:`DepthRenderer.skin`)."""
        return self._g.skin

    def _pose(self, xpos, xmat) -> None:
        g = self._g
        n = g._nbody
        xpos = np.ascontiguousarray(xpos, dtype=np.float64)
        xmat = np.ascontiguousarray(xmat, dtype=np.float64).reshape(-1, 3, 3)
        if xpos.shape != (n, 3) or xmat.shape[0] != n:
            raise BenchmarkError(
                f"render takes xpos (nbody, 3) and xmat (nbody, 9) with nbody = {n}, got {xpos.shape}, {xmat.shape}"
            )
        rk.camera_from_bodies(g._R_cw, g._t_cw, xpos, xmat, g._rot, g._trans)

    def _build_static(self) -> None:
        """Draws and shades the static prefix (with the world body's pose of this render)."""
        g = self._g
        fx, fy, cx, cy = g._intrinsics
        cam = self.camera
        g._zbuf.fill(np.inf)
        g._lbuf.fill(0)
        self._ibuf.fill(-1)
        ck.draw_triangles(g._verts, g._tri["faces"][: self._n_static], g._tri["face_label"][: self._n_static], 0,
                          fx, fy, cx, cy, cam.znear, cam.zfar, g._zbuf, g._lbuf, self._nbuf, self._ibuf)
        self._static_z[:] = g._zbuf
        self._static_l[:] = g._lbuf
        self._static_i[:] = self._ibuf
        self._static_n[:] = self._nbuf
        self._static_rad.fill(0.0)
        self._shade_into(self._static_rad, -1)
        self._static_key = (g._rot[0].copy(), g._trans[0].copy())

    def _raster(self, xpos, xmat, pulp_centre, pulp_push) -> None:
        """Depth, labels, normals and ids of one pose into the buffers (the depth renderer's order)."""
        g = self._g
        self._pose(xpos, xmat)
        fx, fy, cx, cy = g._intrinsics
        cam = self.camera
        rk.transform_points(g._tri["vertices"], g._tri["vertex_body"], g._rot, g._trans, g._verts)
        key = self._static_key
        if key is None or not (np.array_equal(key[0], g._rot[0]) and np.array_equal(key[1], g._trans[0])):
            self._build_static()
        g._zbuf[:] = self._static_z
        g._lbuf[:] = self._static_l
        self._ibuf[:] = self._static_i
        ck.draw_triangles(g._verts, self._dyn_faces, self._dyn_labels, self._n_static, fx, fy, cx, cy, cam.znear,
                          cam.zfar, g._zbuf, g._lbuf, self._nbuf, self._ibuf)
        if g._skin is not None:
            g._pose_skin(pulp_centre, pulp_push)
            s = g._skin.skin
            ck.draw_triangles(g._skin_verts, s.faces, s.face_label, self._ntri, fx, fy, cx, cy, cam.znear, cam.zfar,
                              g._zbuf, g._lbuf, self._nbuf, self._ibuf)
        ends = g._cap["ends"]
        rk.transform_points(ends.reshape(-1, 3), g._end_body, g._rot, g._trans, g._ends.reshape(-1, 3))
        ck.draw_capsules(g._ends, g._cap["radius"], g._cap["label"], self._ntri + self._nskin, fx, fy, cx, cy,
                         cam.znear, cam.zfar, g._zbuf, g._lbuf, self._nbuf, self._ibuf)

    def _shade(self) -> None:
        """Adds the radiance of the buffers' render to the accumulator."""
        self._shade_into(self._acc, self._n_static)

    def _shade_into(self, acc, n_static: int) -> None:
        g, a = self._g, self.appearance
        fx, fy, cx, cy = g._intrinsics
        if self._box_body >= 0:
            b = self._box_body
            box_R = _mat3_mul(g._rot[b], self._box_R_bg)
            box_t = _mat3_vec(g._rot[b], self._box_t_bg) + g._trans[b]
        else:
            box_R, box_t = np.eye(3), np.zeros(3)
        ck.shade(g._zbuf, g._lbuf, self._nbuf, self._ibuf, int(n_static), self._static_rad, fx, fy, cx, cy,
                 self._light_dir, self._light_rgb, self._ambient, a.background, a.skin_albedo, box_R, box_t,
                 self._box_half, self._box_base, self._box_ink, self._box_par, bool(a.box_print), self._R_wc,
                 self._t_wc, a.table_base, a.table_grain, a.table_par, bool(a.table_texture), acc)

    def _points(self, xpos, xmat) -> np.ndarray:
        """Camera-frame points of the drawn geometry at a pose (vertices, unpressed skin, capsule
        ends), (N, 3): what the motion of a frame is measured on."""
        g = self._g
        self._pose(xpos, xmat)
        rk.transform_points(g._tri["vertices"], g._tri["vertex_body"], g._rot, g._trans, g._verts)
        parts = [g._verts]
        if g._skin is not None:
            g._pose_skin(None, None)
            parts.append(g._skin_verts)
        ends = g._cap["ends"]
        rk.transform_points(ends.reshape(-1, 3), g._end_body, g._rot, g._trans, g._ends.reshape(-1, 3))
        parts.append(g._ends.reshape(-1, 3))
        return np.concatenate(parts)

    def render(self, xpos: np.ndarray, xmat: np.ndarray, pulp_centre: np.ndarray | None = None,
               pulp_push: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Renders one instant (no exposure).

        Args:
            xpos, xmat, pulp_centre, pulp_push: As :meth:`DepthRenderer.render`.

        Returns:
            ``(radiance, depth, labels)``: linear-RGB radiance (H, W, 3) float32, exact depth along
            the optical axis (H, W) float32 [m] (0: nothing), labels (H, W) uint8.
        """
        self._acc.fill(0.0)
        self._raster(xpos, xmat, pulp_centre, pulp_push)
        self._shade()
        cam = self.camera
        radiance = np.empty((cam.height, cam.width, 3), dtype=np.float32)
        ck.mean_radiance(self._acc, 1.0, radiance)
        depth = np.empty((cam.height, cam.width), dtype=np.float32)
        labels = np.empty((cam.height, cam.width), dtype=np.uint8)
        rk.finish(self._g._zbuf, self._g._lbuf, depth, labels)
        return radiance, depth, labels

    def render_exposure(self, set_state, data, k: int, sensor: ColourSensor, pulp_centre: np.ndarray | None = None,
                        pulp_push: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
        """Renders frame k's exposure: the mean radiance of its sub-renders (module docstring).

        Args:
            set_state: ``set_state(data, k, s)`` poses ``data`` at t_k + s and runs ``mj_kinematics``.
            data: A ``mujoco.MjData`` of the model (posed by ``set_state``; left at t_k).
            k: Frame index.
            sensor: Its ``exposure_s``, ``blur_step_px`` and ``max_samples`` set the sub-renders.
            pulp_centre, pulp_push: As :meth:`render`, frame k's (the same in every sub-render).

        Returns:
            ``(radiance, depth, labels, samples)``: the mean radiance (H, W, 3) float32, the
            middle sub-render's (at t_k) depth (H, W) float32 and labels (H, W) uint8, and the
            number of sub-renders.
        """
        cam = self.camera
        e = float(sensor.exposure_s)
        S = 1
        if e > 0:
            fx, fy, cx, cy = self._g._intrinsics
            set_state(data, k, -0.5 * e)
            p0 = self._points(data.xpos, data.xmat).copy()
            set_state(data, k, 0.5 * e)
            p1 = self._points(data.xpos, data.xmat)
            S = samples_for(ck.max_shift_px(p0, p1, fx, fy, cx, cy, cam.znear), sensor)
        mid = (S - 1) // 2
        depth = np.empty((cam.height, cam.width), dtype=np.float32)
        labels = np.empty((cam.height, cam.width), dtype=np.uint8)
        self._acc.fill(0.0)
        for j in range(S):
            if j != mid:
                set_state(data, k, e * ((j + 0.5) / S - 0.5))
                self._raster(data.xpos, data.xmat, pulp_centre, pulp_push)
                self._shade()
        set_state(data, k, 0.0)  # the middle one last: data is left at t_k
        self._raster(data.xpos, data.xmat, pulp_centre, pulp_push)
        self._shade()
        rk.finish(self._g._zbuf, self._g._lbuf, depth, labels)
        radiance = np.empty((cam.height, cam.width, 3), dtype=np.float32)
        ck.mean_radiance(self._acc, float(S), radiance)
        return radiance, depth, labels, S

    def normals(self) -> np.ndarray:
        """The outward unit normals (camera frame) of the last render, (H, W, 3) float64 (only
        meaningful where something is seen)."""
        static = (self._ibuf < self._n_static)[..., None]
        return np.where(static, self._static_n, self._nbuf)


def samples_for(shift_px: float, sensor: ColourSensor) -> int:
    """Sub-renders of a frame whose drawn points move ``shift_px`` pixels over the exposure: the
    fewest (odd) that keep the motion between two within ``sensor.blur_step_px``, at most
    ``sensor.max_samples``, 1 without exposure."""
    if sensor.exposure_s == 0 or not shift_px > sensor.blur_step_px:
        return 1
    n = int(math.ceil(shift_px / sensor.blur_step_px))
    n += 1 - n % 2
    return min(n, sensor.max_samples)


def render_colour_video(model, set_state, num_frames: int, *, camera: Camera, labels: np.ndarray, appearance,
                        sensor: ColourSensor, fps: float, rng: np.random.Generator | None,
                        skin: HandSkin | None = None, pulps: tuple | None = None, observe=None,
                        out: tuple | None = None) -> ColourFrames:
    """Renders, blurs and measures a colour video of a MuJoCo model.

    Args:
        model: A compiled ``mujoco.MjModel``.
        set_state: ``set_state(data, k, s)`` poses ``data`` at time t_k + s (s [s] within the
            exposure, 0 at t_k) and runs ``mujoco.mj_kinematics`` (e.g. with :func:`interpolated_state`).
        num_frames: Number of frames T.
        camera: The colour camera.
        labels: Label per geom, (ngeom,) uint8.
        appearance: The :class:`benchmark.camera.appearance.Appearance`.
        sensor: The :class:`benchmark.camera.colour_sensor.ColourSensor` (its size must be the camera's).
        fps: Frame rate [Hz].
        rng: Generator of the sensor noise (the scenario's "colour" stream; None without noise).
        skin, pulps: As :func:`benchmark.camera.render.render_video`.
        observe: Called as ``observe(k, exact_depth, labels)`` per frame with the middle
            sub-render's exact depth (H, W) float32 [m] and labels (nothing keeps a video of depth).
        out: ``(rgb, labels)``: arrays of shape (T, H, W, 3) and (T, H, W) uint8 to render into
            (e.g. memory shared with another process); None allocates them.

    Returns:
        The :class:`ColourFrames`; its ``rgb`` is read-only (so that :attr:`ColourFrames.video`
        hands it on without a copy).
    """

    T = int(num_frames)
    if T < 1:
        raise BenchmarkError(f"num_frames must be >= 1, got {num_frames}")
    if not (np.isfinite(fps) and fps > 0):
        raise BenchmarkError(f"fps must be a finite number > 0 [Hz], got {fps!r}")
    if (camera.width, camera.height) != (sensor.width, sensor.height):
        raise BenchmarkError(f"the camera's size {camera.width}x{camera.height} differs from the sensor's "
                             f"{sensor.width}x{sensor.height}")
    data = mujoco.MjData(model)
    H, W = camera.height, camera.width
    if out is None:
        rgb, label_images = np.empty((T, H, W, 3), dtype=np.uint8), np.empty((T, H, W), dtype=np.uint8)
    else:
        rgb, label_images = out
        if rgb.shape != (T, H, W, 3) or label_images.shape != (T, H, W) or (rgb.dtype, label_images.dtype) != (
                np.uint8, np.uint8):
            raise BenchmarkError(f"out must be uint8 arrays of shapes {(T, H, W, 3)} and {(T, H, W)}, got "
                                 f"{rgb.dtype} {rgb.shape} and {label_images.dtype} {label_images.shape}")
    samples = np.empty(T, dtype=np.int64)
    renderer = ColourRenderer(model, camera, labels, appearance, skin=skin)
    for k in range(T):
        centre, push = (None, None) if pulps is None else (pulps[0][k], pulps[1][k])
        radiance, depth, label_images[k], samples[k] = renderer.render_exposure(set_state, data, k, sensor, centre, push)
        if observe is not None:
            observe(k, depth, label_images[k])
        sensor.measure(radiance, rng, appearance.lighting, out=rgb[k])
    e = float(sensor.exposure_s)
    rgb.setflags(write=False)  # finished: fsv.ColourVideo takes it as it is (a writable one it would copy, 0.3 GB)
    return ColourFrames(rgb=rgb, labels=label_images, calib=camera.calibration(), fps=float(fps),
                        exposure_s=e, samples=samples, t_s=np.arange(T) / float(fps))


def _nlerp(q0: np.ndarray, q1: np.ndarray, f: float) -> np.ndarray:
    """Normalised linear interpolation of unit quaternions (the shorter way)."""
    if q0[0] * q1[0] + q0[1] * q1[1] + q0[2] * q1[2] + q0[3] * q1[3] < 0.0:
        q1 = -q1
    q = q0 + f * (q1 - q0)
    return q / math.sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3])


def interpolated_state(truth, k: int, s: float, fps: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The box and hand state at t_k + s, interpolated between the truth's neighbouring frames.

    Positions and joint angles are interpolated linearly, the box's and the palm's quaternions
    (``hand_qpos[3:7]``) by normalised linear interpolation; times before the first frame or
    after the last are clamped to it. At a frame time the truth's values are returned exactly.

    Args:
        truth: A :class:`benchmark.world.truth.Truth` (frames at t_k = k / fps).
        k: Frame index.
        s: Offset from t_k [s].
        fps: Frame rate [Hz].

    Returns:
        ``(box_pos (3,), box_quat (4,), hand_qpos (7 + n,))``.
    """
    T = len(truth.t)
    if not 0 <= int(k) < T:
        raise BenchmarkError(f"frame k must be in 0..{T - 1}, got {k!r}")
    x = int(k) + float(s) * float(fps)
    i, f = (0, 0.0) if x <= 0 else (T - 1, 0.0) if x >= T - 1 else (int(math.floor(x)), x - math.floor(x))
    pos, quat, hand = truth.box_pos, truth.box_quat, truth.hand_qpos
    if f == 0.0:
        return np.array(pos[i], dtype=float), np.array(quat[i], dtype=float), np.array(hand[i], dtype=float)
    box_pos = pos[i] + f * (pos[i + 1] - pos[i])
    box_quat = _nlerp(np.asarray(quat[i], float), np.asarray(quat[i + 1], float), f)
    hand_qpos = hand[i] + f * (hand[i + 1] - hand[i])
    hand_qpos[3:7] = _nlerp(np.asarray(hand[i, 3:7], float), np.asarray(hand[i + 1, 3:7], float), f)
    return box_pos, box_quat, hand_qpos


def register_to_depth(rgb: np.ndarray, colour_calib: Calibration, depth_m: np.ndarray,
                      depth_calib: Calibration) -> np.ndarray:
    """The colour of each depth pixel: the nearest colour pixel of its back-projected point.

    No occlusion test: a depth point hidden from the colour camera (a few pixels beside
    silhouettes, the cameras being a few cm apart) takes the colour of what hides it.

    Args:
        rgb: Colour image, (Hc, Wc, 3) uint8.
        colour_calib: The colour camera's calibration.
        depth_m: Depth image, (Hd, Wd) [m] (0: no measurement).
        depth_calib: The depth camera's calibration.

    Returns:
        (Hd, Wd, 3) uint8; 0 where the depth is 0 or the point falls outside the colour image.
    """
    rgb = np.ascontiguousarray(rgb)
    depth = np.ascontiguousarray(depth_m, dtype=np.float32)
    if rgb.dtype != np.uint8 or rgb.shape != (colour_calib.height, colour_calib.width, 3):
        raise BenchmarkError(f"rgb must be uint8 of shape ({colour_calib.height}, {colour_calib.width}, 3), "
                             f"got {rgb.dtype} {rgb.shape}")
    if depth.shape != (depth_calib.height, depth_calib.width):
        raise BenchmarkError(f"depth_m must have shape ({depth_calib.height}, {depth_calib.width}), got {depth.shape}")
    out = np.empty(depth.shape + (3,), dtype=np.uint8)
    f64 = lambda a: np.ascontiguousarray(a, dtype=np.float64)  # noqa: E731
    Tc, Td = colour_calib.T_world_cam, depth_calib.T_world_cam
    ck.register(rgb, f64(colour_calib.K), f64(Tc[:3, :3]), f64(Tc[:3, 3]), depth, f64(depth_calib.K),
                f64(Td[:3, :3]), f64(Td[:3, 3]), out)
    return out


def render_colour(episode, *, sensor: ColourSensor | None = None, appearance=None,
                  camera: Camera | None = None, observe=None, out: tuple | None = None) -> ColourFrames:
    """Renders the colour video of a simulated episode, beside its scenario's depth camera.

    Args:
        episode: A simulated :class:`benchmark.world.episode.Episode`.
        sensor: The colour sensor; default :func:`colour_preset` of the scenario's sensor.
        appearance: Default :func:`benchmark.camera.appearance.appearance_of` of the scenario.
        camera: The depth camera the colour camera sits beside (:func:`colour_camera`); default
            the scenario's view's (:func:`benchmark.camera.views.camera_of`).
        observe: Called as ``observe(k, exact_depth, labels)`` with each frame's exact depth along
            the colour camera's axis at t_k, (H, W) float32 [m] (0: nothing), and its labels (e.g.
            :meth:`benchmark.camera.labelling.Labeller.see`).
        out: Arrays to render into, as :func:`render_colour_video`'s.

    Returns:
        The :class:`ColourFrames` (T = len(truth.t) frames at the scenario's fps). The noise comes
        from the scenario's "colour" stream; the hand is drawn as the scenario's ``hand_surface``
        says, as for the depth (:func:`benchmark.camera.render.render`).
    """

    sc = episode.scenario
    sensor = colour_preset(sc.sensor) if sensor is None else sensor
    appearance = appearance_of(sc) if appearance is None else appearance
    colour_cam = colour_camera(camera_of(sc.view) if camera is None else camera, sensor)
    world = build_world(sc)
    truth = episode.truth

    def set_state(data, k, s):
        box_pos, box_quat, hand_qpos = interpolated_state(truth, k, s, sc.fps)
        set_frame(world, data, box_pos, box_quat, hand_qpos)

    skin, pulps = drawn_hand(world, truth, sc.hand_surface)
    return render_colour_video(world.model, set_state, len(truth.t), camera=colour_cam, labels=world_labels(world),
                               appearance=appearance, sensor=sensor, fps=sc.fps, rng=sc.rng("colour"), skin=skin,
                               pulps=pulps, observe=observe, out=out)
