"""Depth rendering: what a DS325-like depth camera sees of the simulated scene.

A pyrender scene mirrors the MuJoCo geoms one to one (the table, the box, every capsule and
sphere of the hand): each geom's mesh is built once from the MjModel in its body's frame, and
per frame only the bodies' poses (``data.xpos`` / ``data.xmat``) are applied. One off-screen pass
per frame gives the exact depth along the optical axis and a label image (which geom is seen
where).
The sensor model (:mod:`benchmark.sensor`) then turns the exact depth into a measurement.

Camera conventions: `fsv` and :class:`fsv.Calibration` use OpenCV's pinhole camera (x right,
y down, z forward; pixel centres at integer coordinates). pyrender uses OpenGL's (x right, y up,
z backward; pixel centres at half-integers). The conversion happens once, here:
``T_world_glcam = T_world_cam @ GL_FROM_CV`` and ``(cx, cy)_gl = (cx, cy)_cv + 0.5``.

Rendering is headless through EGL (Mesa's llvmpipe on a CPU-only machine):
``PYOPENGL_PLATFORM=egl`` is set here before pyrender is imported, unless the caller chose
another platform.
"""

from __future__ import annotations

import ctypes
import importlib.resources
import os
from dataclasses import dataclass

import numpy as np
import yaml

from benchmark.episode import Episode
from benchmark.errors import BenchmarkError, RenderError
from benchmark.sensor import SensorModel
from fsv import Calibration, DepthVideo

os.environ.setdefault("PYOPENGL_PLATFORM", "egl")

LABEL_NONE = 0
LABEL_TABLE = 1
LABEL_BOX = 2
LABEL_PALM = 9
LABEL_FINGER0 = 10
"""Label image values: 0 nothing, 1 table, 2 box, 9 palm, 10 + k finger k (thumb first)."""

GL_FROM_CV = np.diag([1.0, -1.0, -1.0, 1.0])
"""Maps OpenCV camera coordinates to OpenGL camera coordinates (and back: it is its own inverse)."""

PLANE_HALF_EXTENT_M = 5.0
"""Half size of the rendered table when its MuJoCo plane is infinite (size 0)."""

_DEBIAN_PACKAGES = "libegl1 libgl1-mesa-dri"


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
    if np.linalg.norm(z) < 1e-9:
        raise BenchmarkError(f"camera position and look_at coincide: {p}")
    z /= np.linalg.norm(z)
    x = np.cross(z, u)
    if np.linalg.norm(x) < 1e-9:
        raise BenchmarkError(f"camera up {u} is parallel to the optical axis {z}")
    x /= np.linalg.norm(x)
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


def world_labels(world) -> np.ndarray:
    """Which label each geom of a :class:`benchmark.world.World` gets in the label image.

    The table geom is 1, the box geom 2, hand geoms 10 + k on finger k (thumb first) and 9 on the
    palm; any other geom that can collide is static environment and drawn as table (1); geoms
    that cannot collide (``contype == conaffinity == 0``, e.g. markers) are not drawn (0).

    Returns:
        Labels, shape (ngeom,), uint8.
    """
    m = world.model
    labels = np.where((m.geom_contype != 0) | (m.geom_conaffinity != 0), LABEL_TABLE, LABEL_NONE).astype(np.uint8)
    hand = np.asarray(world.geom_segment) >= 0
    finger = np.asarray(world.geom_finger)
    labels[hand] = np.where(finger[hand] >= 0, LABEL_FINGER0 + finger[hand], LABEL_PALM)
    labels[world.table_geom] = LABEL_TABLE
    labels[world.box_geom] = LABEL_BOX
    return labels


def geom_trimesh(model, geom: int):
    """A triangle mesh of one MuJoCo geom in the geom's own frame.

    Spheres and ellipsoids are icospheres (320 triangles), capsules 24-sided with 12 rings per
    cap, cylinders 32-sided: the facets lie within 1.2 % of the radius of the true surface (0.1 mm
    for a finger). Planes become a 2 cm thick slab whose top face is the plane (z = 0).

    Args:
        model: A compiled ``mujoco.MjModel``.
        geom: Geom index.

    Returns:
        A ``trimesh.Trimesh``.
    """
    import mujoco
    import trimesh

    kind = int(model.geom_type[geom])
    size = np.asarray(model.geom_size[geom], dtype=float)
    G = mujoco.mjtGeom
    if kind == G.mjGEOM_PLANE:
        hx = size[0] if size[0] > 0 else PLANE_HALF_EXTENT_M
        hy = size[1] if size[1] > 0 else PLANE_HALF_EXTENT_M
        return trimesh.creation.box(
            extents=(2 * hx, 2 * hy, 0.02), transform=trimesh.transformations.translation_matrix((0, 0, -0.01))
        )
    if kind == G.mjGEOM_BOX:
        return trimesh.creation.box(extents=2 * size)
    if kind == G.mjGEOM_SPHERE:
        return trimesh.creation.icosphere(subdivisions=2, radius=size[0])
    if kind == G.mjGEOM_ELLIPSOID:
        mesh = trimesh.creation.icosphere(subdivisions=2, radius=1.0)
        mesh.apply_scale(size)
        return mesh
    if kind == G.mjGEOM_CAPSULE:
        return trimesh.creation.capsule(height=2 * size[1], radius=size[0], count=(24, 12))
    if kind == G.mjGEOM_CYLINDER:
        return trimesh.creation.cylinder(radius=size[0], height=2 * size[1], sections=32)
    if kind == G.mjGEOM_MESH:
        mid = int(model.geom_dataid[geom])
        v0, nv = model.mesh_vertadr[mid], model.mesh_vertnum[mid]
        f0, nf = model.mesh_faceadr[mid], model.mesh_facenum[mid]
        return trimesh.Trimesh(vertices=model.mesh_vert[v0 : v0 + nv].copy(), faces=model.mesh_face[f0 : f0 + nf].copy())
    raise BenchmarkError(
        f"geom {geom} has MuJoCo type {kind}, which the depth renderer does not draw; "
        "accepted: plane, sphere, capsule, ellipsoid, cylinder, box, mesh"
    )


def _missing_libraries() -> list[str]:
    missing = []
    for lib in ("libEGL.so.1", "libGL.so.1"):
        try:
            ctypes.CDLL(lib)
        except OSError:
            missing.append(lib)
    return missing


def render_error(cause: BaseException) -> RenderError:
    """The error raised when no OpenGL context can be made, saying what to install."""
    missing = _missing_libraries()
    what = (
        f"the system library {' and '.join(missing)} cannot be loaded"
        if missing
        else "EGL loaded but found no usable driver (Mesa's DRI drivers, e.g. swrast/llvmpipe, may be missing)"
    )
    return RenderError(
        f"cannot create a headless OpenGL context through EGL (PYOPENGL_PLATFORM="
        f"{os.environ.get('PYOPENGL_PLATFORM')}): {what}. On Debian/Ubuntu install them with "
        f"`apt-get install {_DEBIAN_PACKAGES}`. ({type(cause).__name__}: {cause})"
    )


_OFFSCREEN: dict[tuple[int, int], object] = {}


def _offscreen(width: int, height: int):
    """The process's pyrender OffscreenRenderer for one image size, made on first use.

    It is shared and never deleted: pyrender's ``delete()`` terminates the EGL display, which
    would invalidate every other GL context of the process (other renderers', MuJoCo's).
    Meshes of a scene that is no longer rendered are freed when the next scene is rendered.
    """
    key = (int(width), int(height))
    if key not in _OFFSCREEN:
        try:
            import pyrender

            _OFFSCREEN[key] = pyrender.OffscreenRenderer(*key)
        except Exception as err:  # PyOpenGL raises ImportError, OSError, RuntimeError or EGL errors
            raise render_error(err) from err
    return _OFFSCREEN[key]


class _MovingLabel:
    """One label's moving geoms as one triangle mesh whose vertices are posed per frame.

    Attributes:
        local: Vertices in their bodies' frames, (V, 3).
        ranges: ``(body, start, stop)`` rows of `local` per body.
        world: Posed vertices, (V, 3) float32, rewritten per frame.
        primitive: The pyrender primitive drawn (positions only).
    """

    def __init__(self, parts, pyrender):
        import trimesh

        self.ranges, start = [], 0
        for body, mesh in parts:
            self.ranges.append((body, start, start + len(mesh.vertices)))
            start += len(mesh.vertices)
        merged = trimesh.util.concatenate([mesh for _, mesh in parts])
        self.local = np.asarray(merged.vertices, dtype=np.float64)
        self.world = self.local.astype(np.float32)
        self.primitive = pyrender.Primitive(
            positions=self.world, indices=np.asarray(merged.faces, dtype=np.uint32), mode=pyrender.GLTF.TRIANGLES
        )

    def pose(self, xpos: np.ndarray, xmat: np.ndarray) -> None:
        for body, start, stop in self.ranges:
            self.world[start:stop] = self.local[start:stop] @ xmat[body].T + xpos[body]


class DepthRenderer:
    """Exact depth and label images of a MuJoCo model's geoms from one camera.

    Build once per model, then call :meth:`render` per frame with the bodies' world poses.
    Geoms fixed to the world (the table) are static meshes. All moving geoms that share a label
    (the box; the palm; each finger's segments) form one mesh whose vertices are posed on the
    CPU and streamed into its vertex buffer each frame, so a frame costs one draw call per label
    rather than per body (pyrender's per-draw cost dominates at this resolution). The GL context
    is the process's shared one (see :func:`_offscreen`).

    Args:
        model: A compiled ``mujoco.MjModel``.
        camera: The camera.
        labels: Label per geom, shape (ngeom,), uint8; geoms with label 0 are not drawn
            (see :func:`world_labels`).
    """

    def __init__(self, model, camera: Camera, labels: np.ndarray):
        import mujoco
        import pyrender
        import trimesh

        labels = np.asarray(labels)
        if labels.shape != (model.ngeom,):
            raise BenchmarkError(f"labels must have shape ({model.ngeom},), one per geom, got {labels.shape}")
        self._gl = _offscreen(camera.width, camera.height)
        self.camera = camera
        self.scene = pyrender.Scene(bg_color=(0, 0, 0, 0), ambient_light=(0, 0, 0))
        K = camera.K
        cam = pyrender.IntrinsicsCamera(
            fx=K[0, 0], fy=K[1, 1], cx=K[0, 2] + 0.5, cy=K[1, 2] + 0.5, znear=camera.znear, zfar=camera.zfar
        )
        self.scene.add(cam, pose=camera.T_world_cam @ GL_FROM_CV)
        static: dict[int, list] = {}
        moving: dict[int, list] = {}
        for g in np.flatnonzero(labels):
            T_body_geom = np.eye(4)
            mat = np.zeros(9)
            mujoco.mju_quat2Mat(mat, model.geom_quat[g])
            T_body_geom[:3, :3] = mat.reshape(3, 3)
            T_body_geom[:3, 3] = model.geom_pos[g]
            mesh = geom_trimesh(model, int(g))
            mesh.apply_transform(T_body_geom)
            body = int(model.geom_bodyid[g])
            if model.body_weldid[body] == 0 and model.body_mocapid[body] < 0:  # welded to the world
                mesh.apply_transform(_body_pose0(model, body))
                static.setdefault(int(labels[g]), []).append(mesh)
            else:
                moving.setdefault(int(labels[g]), []).append((body, mesh))
        self._seg = {}
        for label, meshes in static.items():
            node = self.scene.add(pyrender.Mesh.from_trimesh(trimesh.util.concatenate(meshes), smooth=False))
            self._seg[node] = (label,) * 3
        self._moving = []
        for label, parts in moving.items():
            group = _MovingLabel(parts, pyrender)
            node = self.scene.add(pyrender.Mesh([group.primitive]))
            self._seg[node] = (label,) * 3
            self._moving.append(group)
        self.draw_calls = len(self._seg)
        self._flags = pyrender.RenderFlags.SEG

    def render(self, xpos: np.ndarray, xmat: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Renders one frame.

        Args:
            xpos: World positions of all bodies, shape (nbody, 3), [m] (``data.xpos``).
            xmat: World orientations of all bodies, shape (nbody, 9) or (nbody, 3, 3) (``data.xmat``).

        Returns:
            ``(depth, labels)``: exact depth along the optical axis, shape (H, W), float32 metres
            (0 where nothing is seen), and the label of the geom seen at each pixel, (H, W) uint8
            (sampled at pixel centres, no anti-aliasing).
        """
        from OpenGL import GL

        xpos = np.asarray(xpos)
        xmat = np.asarray(xmat).reshape(-1, 3, 3)
        self._gl._platform.make_current()
        for group in self._moving:
            group.pose(xpos, xmat)
            prim = group.primitive
            prim.positions = group.world  # uploaded with the mesh when it (re-)enters the GL context
            if prim._vaid is not None:  # already in the context: stream the new vertices
                GL.glBindBuffer(GL.GL_ARRAY_BUFFER, prim._buffers[0])
                GL.glBufferSubData(GL.GL_ARRAY_BUFFER, 0, group.world.nbytes, group.world)
        color, depth = self._gl.render(self.scene, flags=self._flags, seg_node_map=self._seg)
        return np.ascontiguousarray(depth, dtype=np.float32), np.ascontiguousarray(color[..., 0])


def _body_pose0(model, body: int) -> np.ndarray:
    """World pose (4, 4) of a body welded to the world, from the model alone."""
    import mujoco

    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    T = np.eye(4)
    T[:3, :3] = data.xmat[body].reshape(3, 3)
    T[:3, 3] = data.xpos[body]
    return T


def render_video(model, set_frame, num_frames: int, *, camera: Camera, labels: np.ndarray, sensor, rng):
    """Renders and measures a depth video of a MuJoCo model.

    Args:
        model: A compiled ``mujoco.MjModel``.
        set_frame: ``set_frame(data, k)`` puts frame k's kinematic state into ``data`` (qpos and
            mocap poses) and runs ``mujoco.mj_kinematics``.
        num_frames: Number of frames T.
        camera: The camera.
        labels: Label per geom, (ngeom,) uint8 (see :func:`world_labels`).
        sensor: A :class:`benchmark.sensor.SensorModel`.
        rng: Generator of the sensor noise (the scenario's "depth" stream).

    Returns:
        ``(depth, label_images)``: measured depth (T, H, W) float32 metres (0 = no measurement)
        and the exact label images (T, H, W) uint8 (from the noise-free render).
    """
    import mujoco

    if int(num_frames) < 1:
        raise BenchmarkError(f"num_frames must be >= 1, got {num_frames}")
    data = mujoco.MjData(model)
    shape = (int(num_frames), camera.height, camera.width)
    depth = np.empty(shape, dtype=np.float32)
    label_images = np.empty(shape, dtype=np.uint8)
    renderer = DepthRenderer(model, camera, labels)
    for k in range(shape[0]):
        set_frame(data, k)
        exact, label_images[k] = renderer.render(data.xpos, data.xmat)
        depth[k] = sensor.measure(exact, camera.K, rng)
    return depth, label_images


def render(episode: Episode, *, sensor: SensorModel | None = None, camera: Camera | None = None) -> Episode:
    """Renders the depth video a DS325-like camera would record of a simulated episode.

    Args:
        episode: A simulated episode (its truth gives the box and hand pose per frame).
        sensor: The sensor model; default ``SensorModel(noise_m=scenario.noise_m)`` (the README's
            defaults). Its ``noise_m`` must equal the scenario's.
        camera: The camera; default ``sim_assets/camera.yaml``.

    Returns:
        The episode with ``depth`` (T frames at the scenario's fps, T = len(truth.t)),
        ``calib`` and the truth-side ``labels`` (T, H, W) uint8 (never handed to `fsv`).
        The noise comes from the scenario's "depth" random stream: same scenario, same bits.
    """
    from benchmark.world import build_world, set_frame

    sc = episode.scenario
    sensor = SensorModel(noise_m=sc.noise_m) if sensor is None else sensor
    if sensor.noise_m != sc.noise_m:
        raise BenchmarkError(
            f"sensor.noise_m = {sensor.noise_m} differs from the scenario's noise_m = {sc.noise_m}; "
            "the scenario sets the noise"
        )
    camera = load_camera() if camera is None else camera
    world = build_world(sc)
    truth = episode.truth

    def set_k(data, k):
        set_frame(world, data, truth.box_pos[k], truth.box_quat[k], truth.hand_qpos[k])

    depth, labels = render_video(
        world.model, set_k, len(truth.t), camera=camera, labels=world_labels(world), sensor=sensor, rng=sc.rng("depth")
    )
    return episode.with_depth(DepthVideo(depth_m=depth, fps=sc.fps), camera.calibration(), labels)


# --- the command-line stage (benchmark.cli appends it to its STAGES) --------------------------


def add_cli_arguments(parser) -> None:
    """Options of the render stage of ``fsv-bench``."""
    parser.add_argument("--no-gif", action="store_true", help="write the PNG depth preview but no animated GIF")


def run_cli_stage(run) -> None:
    """Renders ``run.episode``, writes the depth preview to ``run.out`` and adds a "render" block.

    Args:
        run: The command's ``benchmark.cli.Run`` (its episode is replaced by the rendered one).
    """
    from benchmark.preview import write_preview

    run.episode = render(run.episode)
    depth = run.episode.depth
    paths = write_preview(depth.depth_m, depth.fps, run.out, gif=not run.args.no_gif)
    T, H, W = depth.depth_m.shape
    block = {
        "frames": T,
        "width": W,
        "height": H,
        "fps": depth.fps,
        "noise_m": run.scenario.noise_m,
        "valid_fraction": float(np.mean(depth.depth_m > 0)),
        "box_pixels_median": float(np.median(np.sum(run.episode.labels == LABEL_BOX, axis=(1, 2)))),
        "preview": [p.name for p in paths],
    }
    run.summary["render"] = block
    run.lines.append(
        f"render: {T} depth frames {W}x{H} at {depth.fps:g} Hz, noise {run.scenario.noise_m:g} m, "
        f"{100 * block['valid_fraction']:.0f} % of pixels measured, box on {block['box_pixels_median']:.0f} px; "
        f"preview {paths[0]}"
    )
