"""pyrender as a second renderer of the depth camera's scene: the oracle of the CPU rasteriser in
the tests, and an optional path through OpenGL (``--renderer pyrender``, :func:`render_pyrender`).

The scene is the one :class:`benchmark.camera.depth.DepthRenderer` draws (its
:func:`~benchmark.camera.depth._geometry` and, with a skin, its posed skin), drawn by pyrender on
OpenGL (EGL: Mesa's llvmpipe on a CPU machine, the driver's rasteriser on a GPU). The depth and the
labels therefore come from an independent rasteriser: a GL pipeline that interpolates the window
depth of tessellated surfaces in float32 into a 24-bit depth buffer, against this project's exact
per-pixel ray casts in float64. They agree to a few micrometres on surfaces and differ on a few
silhouette pixels (``tests/test_pyrender_backend.py`` states the measured values); they are NOT the
same bits on every machine, which is why the CPU rasteriser stays the default renderer.

Speed: on Mesa's llvmpipe (2-core AMD EPYC) pyrender draws 39 frames/s of the capsule hand
(16k triangles a capsule) and 102 of the skinned hand at 320 x 240 (20 and 55 at 640 x 480; the
shaded render, two passes, 7-40), where the CPU rasteriser draws 450-2250: it is a fast path only
where a GPU draws it, and the per-frame read-back and skin upload still cost milliseconds there.

What differs from the CPU renderer by construction:

- capsules and spheres (the hand's primitives) are tessellated (:data:`CAPSULE_COUNT`): the
  facets lie inside the true surface by at most :data:`CAPSULE_FACET_ERROR` of the radius
  (6.1e-4 r: 4.2-7.5 um for the hand's radii of 7-12.5 mm), so the hand's depth is deeper by up to that;
- the depth is read back from a 24-bit buffer (znear 0.05 m, zfar 10 m: one step is 4.3e-7 m
  at 0.6 m) and linearised by pyrender in float32.

Camera: pyrender's :class:`IntrinsicsCamera` builds its projection from (fx, fy, cx, cy) with
OpenGL's pixel centres at half-integers, where ours (OpenCV) are at integers
(:func:`benchmark.camera.camera.clip_from_cam`): a point at OpenCV pixel (u, v) must land at window
(u + 0.5, H - v - 0.5) before pyrender flips the rows, which its projection gives for the principal
point (cx + 0.5, cy + 0.5) (:data:`HALF_PIXEL`); the camera node's pose is
``T_world_cam @ GL_FROM_CV``.

Shading: pyrender's own shader is physically based (metallic-roughness, with its own light
fall-off and tone), not the design's Lambert equation, so it is not used. Instead pyrender renders
two things exactly: (1) a segmentation pass whose per-node colour encodes the node's index (which
gives the label and the body of every pixel, and the depth), and (2) a flat pass whose vertex
colours encode each vertex's outward unit normal in its node's frame ((128 + 127 n) / 255, 8 bits
a component: a normal is off by at most 0.4 degrees, axis-aligned ones are exact). Both passes sample each pixel once at its centre
(4x multisampling, which pyrender turns on for non-segmentation passes, is kept off, see
:func:`_single_sample`). The radiance is then the design note's equation in numpy (colour-design.md):

    L = albedo[label] * (ambient + sum_i light_i * max(0, -n . dir_i)),   L = background where nothing.

What this oracle checks of a CPU colour renderer: which surface each pixel sees and its normal
(GL's rasterisation, independent of ours), and the shading equation applied to uniform albedo per
label; it does not check textures (the box's print, the table's), the sensor or the exposure.

pyrender is imported lazily (only here, never by ``fsv/`` or by the default command); it needs
PyOpenGL's platform set before import: this module sets ``PYOPENGL_PLATFORM=egl`` when unset.
"""

from __future__ import annotations

import contextlib
import os
from dataclasses import dataclass

import mujoco
import numpy as np
import trimesh

from benchmark.camera import raster_kernels as rk
from benchmark.camera.camera import GL_FROM_CV, Camera
from benchmark.camera.depth import DepthRenderer, HandSkin, _geometry, drawn_hand
from benchmark.camera.render import scenario_sensor
from benchmark.camera.scene import LABEL_PALM, world_labels
from benchmark.camera.views import camera_of
from benchmark.errors import BenchmarkError
from benchmark.world.assets import build_world, set_frame
from fsv import DepthVideo

RENDERER = "pyrender"
"""The renderer's name as the command line gives it (``--renderer pyrender``)."""

CAPSULE_COUNT = (64, 128)
"""Tessellation of a capsule or sphere: (latitude steps over the two hemispheres' half-circle,
longitude steps around), ``trimesh.creation.capsule``'s ``count``: steps of pi/64 and 2 pi/128,
both 2.8 degrees, 16k triangles a capsule."""

CAPSULE_FACET_ERROR = 6.1e-4
"""Largest distance of a capsule's facet inside the true surface, as a fraction of its radius: the
middle of a facet's diagonal, which spans angle sqrt(a^2 + b^2) for angular steps a = b = pi/64,
lies 1 - cos(sqrt(2) pi / 128) = 6.02e-4 inside (sampled on the mesh: 6.02e-4)."""

HALF_PIXEL = 0.5
"""Added to (cx, cy) for pyrender's projection: OpenGL's pixel centres are at half-integers."""


@dataclass(frozen=True)
class Shading:
    """The lighting of the design note's shading equation with a uniform albedo per label.

    Attributes:
        albedo: Linear-RGB albedo per label, {label: (r, g, b)} in [0, 1]; every label drawn
            (other than 0) needs one.
        ambient: Ambient radiance, (3,) linear RGB.
        light_dir: Unit direction each directional light travels, world frame, (L, 3).
        light_rgb: Radiance of each light, (L, 3) linear RGB.
        background: Radiance where nothing is seen (label 0), (3,) linear RGB.
    """

    albedo: dict
    ambient: np.ndarray
    light_dir: np.ndarray
    light_rgb: np.ndarray
    background: np.ndarray

    def __post_init__(self):
        albedo = {}
        for label, rgb in dict(self.albedo).items():
            rgb = np.asarray(rgb, dtype=np.float64)
            if not (isinstance(label, (int, np.integer)) and 0 < int(label) < 256):
                raise BenchmarkError(f"shading albedo keys must be labels 1-255, got {label!r}")
            if rgb.shape != (3,) or not np.all((rgb >= 0) & (rgb <= 1)):
                raise BenchmarkError(f"albedo of label {label} must be linear RGB (3,) in [0, 1], got {rgb}")
            albedo[int(label)] = rgb
        object.__setattr__(self, "albedo", albedo)
        for name in ("ambient", "background"):
            v = np.asarray(getattr(self, name), dtype=np.float64)
            if v.shape != (3,) or not np.all(np.isfinite(v) & (v >= 0)):
                raise BenchmarkError(f"shading {name} must be a non-negative (3,) linear RGB, got {v}")
            object.__setattr__(self, name, v)
        d = np.asarray(self.light_dir, dtype=np.float64).reshape(-1, 3)
        c = np.asarray(self.light_rgb, dtype=np.float64).reshape(-1, 3)
        if len(d) != len(c):
            raise BenchmarkError(f"light_dir and light_rgb need one row per light, got {len(d)} and {len(c)}")
        if not np.allclose(np.sqrt((d * d).sum(axis=1)), 1.0, atol=1e-9):
            raise BenchmarkError(f"light directions must be unit vectors, got {d}")
        if not np.all(np.isfinite(c) & (c >= 0)):
            raise BenchmarkError(f"light colours must be non-negative, got {c}")
        object.__setattr__(self, "light_dir", d)
        object.__setattr__(self, "light_rgb", c)

    def radiance(self, labels: np.ndarray, normals: np.ndarray) -> np.ndarray:
        """The equation per pixel: labels (H, W) uint8, world unit normals (H, W, 3) -> (H, W, 3)
        float32 linear RGB (basic arithmetic and max only, in a fixed order)."""
        missing = sorted(set(np.unique(labels).tolist()) - {0} - set(self.albedo))
        if missing:
            raise BenchmarkError(f"shading has no albedo for labels {missing}")
        albedo = np.zeros((256, 3))
        for label, rgb in self.albedo.items():
            albedo[label] = rgb
        n = normals.astype(np.float64)
        irradiance = np.broadcast_to(self.ambient, n.shape).copy()
        for d, c in zip(self.light_dir, self.light_rgb):
            cos = np.maximum(0.0, -(n[..., 0] * d[0] + n[..., 1] * d[1] + n[..., 2] * d[2]))
            irradiance += cos[..., None] * c
        out = albedo[labels] * irradiance
        out[labels == 0] = self.background
        return out.astype(np.float32)


def _import_pyrender():
    os.environ.setdefault("PYOPENGL_PLATFORM", "egl")
    try:
        import pyrender  # lazy: optional pyrender (0.8 s)
    except ImportError as e:  # not installed, or no GL platform to load
        raise BenchmarkError(
            f"the pyrender renderer needs the package pyrender-maintained (pip install 'fsv-bench[pyrender]') "
            f"and an EGL library (libEGL.so.1); importing it failed: {e}"
        ) from e
    return pyrender


@contextlib.contextmanager
def _single_sample(pyrender):
    """pyrender turns 4x multisampling on for every pass but segmentation, which blends the
    colours of silhouette and crease pixels; within this block its ``glEnable(GL_MULTISAMPLE)`` is
    skipped (and multisampling switched off), so each pixel is one sample at its centre."""
    from OpenGL import GL  # lazy: with the optional pyrender

    module = pyrender.renderer
    enable = module.glEnable

    def gl_enable(cap):
        if cap != GL.GL_MULTISAMPLE:
            enable(cap)

    module.glEnable = gl_enable
    try:
        yield
    finally:
        module.glEnable = enable


def _capsule_mesh(half: float, radius: float):
    """A tessellated capsule (axis z, from -half to +half, sphere for half = 0) and each vertex's
    true outward normal, in the geom's frame: ``(vertices (V, 3), faces (F, 3), normals (V, 3))``."""

    mesh = trimesh.creation.capsule(height=2 * half, radius=radius, count=list(CAPSULE_COUNT))
    v = np.asarray(mesh.vertices, dtype=np.float64)
    axis = np.zeros_like(v)
    axis[:, 2] = np.clip(v[:, 2], -half, half)
    n = v - axis
    n /= np.sqrt((n * n).sum(axis=1))[:, None]
    return v, np.asarray(mesh.faces, dtype=np.int64), n


def _flat(vertices: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Unshared vertices (3F, 3) of triangles and each one's face normal (3F, 3) (counter-clockwise
    seen from outside)."""
    p = vertices[faces]
    n = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    length = np.sqrt((n * n).sum(axis=1))
    n /= np.where(length > 0, length, 1.0)[:, None]
    return p.reshape(-1, 3), np.repeat(n, 3, axis=0)


def _encode_normals(normals: np.ndarray) -> np.ndarray:
    """Vertex colours (V, 4) float32 carrying unit normals as (128 + 127 n) / 255, alpha 1 (0 and
    +-1 are exact 8-bit values; :func:`_decode_normals` inverts it)."""
    return np.concatenate([(128.0 + 127.0 * normals) / 255.0, np.ones((len(normals), 1))], axis=1).astype(np.float32)


def _decode_normals(colour: np.ndarray) -> np.ndarray:
    """Normals (..., 3) float64, not normalised, from 8-bit colours (..., 3) of :func:`_encode_normals`."""
    return (colour.astype(np.float64) - 128.0) / 127.0


class PyrenderRenderer:
    """The depth, labels and (optionally) Lambert radiance of :class:`DepthRenderer`'s scene, by
    pyrender (OpenGL through EGL).

    Build once per model, call :meth:`render` per frame, :meth:`close` (or use it as a context
    manager) to free its GL context.

    Args:
        model: A compiled ``mujoco.MjModel``.
        camera: The camera.
        labels: Label per geom, (ngeom,) uint8 (:func:`benchmark.camera.scene.world_labels`).
        skin: Draw the hand as this skin (posed per frame as :class:`DepthRenderer` poses it);
            None draws its primitives, tessellated.
        shading: With a :class:`Shading`, :meth:`render` also returns the radiance image.
    """

    def __init__(self, model, camera: Camera, labels: np.ndarray, *, skin: HandSkin | None = None,
                 shading: Shading | None = None):
        pyrender = _import_pyrender()
        labels = np.asarray(labels)
        if labels.shape != (model.ngeom,):
            raise BenchmarkError(f"labels must have shape ({model.ngeom},), one per geom, got {labels.shape}")
        if shading is not None and not isinstance(shading, Shading):
            raise BenchmarkError(f"shading must be a pyrender_backend.Shading or None, got {type(shading).__name__}")
        labels = labels.astype(np.uint8)
        # the skin is posed by a DepthRenderer (its own kernels: the same vertices the CPU renderer draws)
        self._posing = DepthRenderer(model, camera, labels, skin=skin) if skin is not None else None
        if skin is not None:
            labels = np.where(labels >= LABEL_PALM, 0, labels).astype(np.uint8)
        self._pyrender = pyrender
        self.camera = camera
        self.shading = shading
        self._nbody = model.nbody
        tri, cap = _geometry(model, labels)
        self.scene = pyrender.Scene(bg_color=np.zeros(4), ambient_light=np.zeros(3))
        K = np.asarray(camera.K, dtype=np.float64)
        cam = pyrender.IntrinsicsCamera(fx=K[0, 0], fy=K[1, 1], cx=K[0, 2] + HALF_PIXEL, cy=K[1, 2] + HALF_PIXEL,
                                        znear=camera.znear, zfar=camera.zfar)
        self.scene.add(cam, pose=np.asarray(camera.T_world_cam, dtype=np.float64) @ GL_FROM_CV)
        self._nodes, self._node_label, self._node_body = [], [], []  # body -1: the camera frame (the skin)

        def add(vertices, normals, body, label, faces=None):
            prim = pyrender.Primitive(positions=vertices.astype(np.float32), color_0=_encode_normals(normals),
                                      indices=None if faces is None else faces.astype(np.uint32), mode=4)
            node = self.scene.add(pyrender.Mesh([prim]), pose=np.eye(4))
            self._nodes.append(node)
            self._node_label.append(int(label))
            self._node_body.append(int(body))
            return node

        for body in np.unique(tri["vertex_body"]):
            fsel = tri["vertex_body"][tri["faces"][:, 0]] == body
            for label in np.unique(tri["face_label"][fsel]):
                faces = tri["faces"][fsel & (tri["face_label"] == label)]
                add(*_flat(tri["vertices"], faces), body, label)
        for ends, body, radius, label in zip(cap["ends"], cap["body"], cap["radius"], cap["label"]):
            mid, axis = (ends[0] + ends[1]) / 2, ends[1] - ends[0]
            half = float(np.sqrt((axis * axis).sum())) / 2
            z = axis / (2 * half) if half > 0 else np.array([0.0, 0.0, 1.0])
            x = np.cross(z, [1.0, 0.0, 0.0] if abs(z[0]) < 0.9 else [0.0, 1.0, 0.0])
            x /= np.sqrt((x * x).sum())
            R = np.stack([x, np.cross(z, x), z], axis=1)  # capsule frame -> body frame
            v, f, n = _capsule_mesh(half, float(radius))
            add(v @ R.T + mid, n @ R.T, body, label, faces=f)
        self._skin_nodes = []
        self._T_world_cam = np.asarray(camera.T_world_cam, dtype=np.float64)
        self._R_world = np.zeros((model.nbody + 1, 3, 3))  # per body, then the camera (-1)
        self._R_world[-1] = self._T_world_cam[:3, :3]
        self._static = len(self._nodes)
        self._offscreen = pyrender.OffscreenRenderer(camera.width, camera.height)

    @property
    def name(self) -> str:
        """``"pyrender <version> (<GL vendor> <GL renderer>, OpenGL <version>)"`` of this renderer's context."""
        return _name(self._pyrender, self._offscreen)

    def close(self) -> None:
        """Frees the GL context (other GL contexts of the process, MuJoCo's too, live on)."""
        if getattr(self, "_offscreen", None) is not None:
            _release(self._offscreen)
            self._offscreen = None

    def __del__(self):
        try:
            self.close()
        except Exception:
            pass

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def _pose(self, xpos, xmat, pulp_centre, pulp_push) -> None:
        n = self._nbody
        xpos = np.ascontiguousarray(xpos, dtype=np.float64)
        xmat = np.ascontiguousarray(xmat, dtype=np.float64).reshape(-1, 3, 3)
        if xpos.shape != (n, 3) or xmat.shape[0] != n:
            raise BenchmarkError(
                f"render takes xpos (nbody, 3) and xmat (nbody, 9) with nbody = {n}, got {xpos.shape}, {xmat.shape}"
            )
        self._R_world[:n] = xmat
        for node, body in zip(self._nodes[: self._static], self._node_body):
            T = np.eye(4)
            T[:3, :3], T[:3, 3] = xmat[body], xpos[body]
            self.scene.set_pose(node, T)
        if self._posing is None:
            return

        dr = self._posing
        rk.camera_from_bodies(dr._R_cw, dr._t_cw, xpos, xmat, dr._rot, dr._trans)
        dr._pose_skin(pulp_centre, pulp_push)  # camera-frame vertices, as DepthRenderer draws them
        for node in self._skin_nodes:
            self.scene.remove_node(node)
        del self._nodes[self._static:], self._node_label[self._static:], self._node_body[self._static:]
        self._skin_nodes = []
        skin = dr._skin.skin
        pyrender = self._pyrender
        for label in np.unique(skin.face_label):
            v, nrm = _flat(dr._skin_verts, skin.faces[skin.face_label == label])
            prim = pyrender.Primitive(positions=v.astype(np.float32), color_0=_encode_normals(nrm), mode=4)
            node = self.scene.add(pyrender.Mesh([prim]), pose=self._T_world_cam)
            self._nodes.append(node)
            self._node_label.append(int(label))
            self._node_body.append(-1)
            self._skin_nodes.append(node)

    def render(self, xpos: np.ndarray, xmat: np.ndarray, pulp_centre: np.ndarray | None = None,
               pulp_push: np.ndarray | None = None) -> tuple:
        """Renders one frame (arguments as :meth:`DepthRenderer.render`).

        Returns:
            ``(depth, labels)``: depth along the optical axis (H, W) float32 metres (0 = nothing)
            and labels (H, W) uint8; with ``shading``, ``(depth, labels, radiance)`` with the
            radiance (H, W, 3) float32 linear RGB. The world unit normals of the last shaded frame
            are kept in :attr:`normals` (H, W, 3) float32 (0 where nothing).
        """
        pyrender = self._pyrender
        if self._offscreen is None:
            raise BenchmarkError("this PyrenderRenderer is closed")
        self._pose(xpos, xmat, pulp_centre, pulp_push)
        ids = np.arange(1, len(self._nodes) + 1)
        seg = {node: [(i & 255), (i >> 8) & 255, (i >> 16) & 255] for node, i in zip(self._nodes, ids.tolist())}
        colour, depth = self._offscreen.render(self.scene, pyrender.RenderFlags.SEG, seg_node_map=seg)
        node = colour[..., 0].astype(np.int64) | (colour[..., 1].astype(np.int64) << 8) | (colour[..., 2].astype(np.int64) << 16)
        node = node - 1  # -1: nothing
        lut = np.asarray(self._node_label + [0], dtype=np.uint8)  # node -1 (nothing) -> label 0
        labels = lut[node]
        depth = np.where(node >= 0, depth, 0.0).astype(np.float32)
        if self.shading is None:
            return depth, labels
        with _single_sample(pyrender):
            encoded, _ = self._offscreen.render(self.scene, pyrender.RenderFlags.FLAT)
        local = _decode_normals(encoded)
        R = self._R_world[np.asarray(self._node_body + [0])[node]]  # (H, W, 3, 3); body -1: the camera
        world = (R[..., 0] * local[..., 0, None] + R[..., 1] * local[..., 1, None] + R[..., 2] * local[..., 2, None])
        length = np.sqrt((world * world).sum(axis=-1))
        world = np.where((node >= 0)[..., None], world / np.where(length > 0, length, 1.0)[..., None], 0.0)
        self.normals = world.astype(np.float32)
        return depth, labels, self.shading.radiance(labels, world)


def renderer_name() -> str:
    """``"pyrender <version> (<GL vendor> <GL renderer>, OpenGL <version>)"`` of a context on this
    machine, for provenance (opens and closes a small offscreen context)."""
    pyrender = _import_pyrender()
    r = pyrender.OffscreenRenderer(8, 8)
    try:
        return _name(pyrender, r)
    finally:
        _release(r)


def _release(offscreen) -> None:
    """Frees an OffscreenRenderer's GL objects and context. pyrender's own ``delete`` also calls
    ``eglTerminate`` on the EGL display, which every EGL context of the process shares (another
    renderer's, MuJoCo's): that would kill them all, so an EGL context is destroyed alone."""
    platform = offscreen._platform
    if platform is None:
        return
    platform.make_current()
    offscreen._renderer.delete()
    if getattr(platform, "_egl_display", None) is not None:
        from OpenGL.EGL import (  # lazy: with the optional pyrender
            EGL_NO_CONTEXT,
            EGL_NO_SURFACE,
            eglDestroyContext,
            eglMakeCurrent,
        )

        eglMakeCurrent(platform._egl_display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT)
        eglDestroyContext(platform._egl_display, platform._egl_context)
        platform._egl_context = platform._egl_display = None
    else:
        platform.delete_context()
    offscreen._renderer = offscreen._platform = None  # its __del__ then finds nothing to delete


def _name(pyrender, offscreen) -> str:
    from OpenGL import GL  # lazy: with the optional pyrender

    offscreen._platform.make_current()
    s = [GL.glGetString(k).decode() for k in (GL.GL_VENDOR, GL.GL_RENDERER, GL.GL_VERSION)]
    return f"{RENDERER} {pyrender.__version__} ({s[0]} {s[1]}, OpenGL {s[2]})"


def render_pyrender(episode, *, sensor=None, camera: Camera | None = None):
    """:func:`benchmark.camera.render.render` with pyrender drawing the exact depth: the same scene
    (hand as the scenario's ``hand_surface`` says), the same sensor model and noise stream.

    Args:
        episode: A simulated episode.
        sensor: The sensor model; default the scenario's preset with its noise (as ``render``).
        camera: The camera; default the scenario's view's.

    Returns:
        The episode with ``depth``, ``calib`` and ``labels`` (T, H, W) uint8, as ``render`` gives
        them; the depth differs from ``render``'s in the last bits and on silhouette pixels.
    """
    sc = episode.scenario
    sensor = scenario_sensor(sc, sensor)
    camera = camera_of(sc.view) if camera is None else camera
    world = build_world(sc)
    truth = episode.truth
    skin, pulps = drawn_hand(world, truth, sc.hand_surface)
    data = mujoco.MjData(world.model)
    T = len(truth.t)
    shape = (T, camera.height, camera.width)
    depth = np.empty(shape, dtype=np.float32)
    labels = np.empty(shape, dtype=np.uint8)
    rng = sc.rng("depth")
    with PyrenderRenderer(world.model, camera, world_labels(world), skin=skin) as renderer:
        for k in range(T):
            set_frame(world, data, truth.box_pos[k], truth.box_quat[k], truth.hand_qpos[k])
            centre, push = (None, None) if pulps is None else (pulps[0][k], pulps[1][k])
            exact, labels[k] = renderer.render(data.xpos, data.xmat, centre, push)
            depth[k] = sensor.measure(exact, camera.K, rng)
    return episode.with_depth(DepthVideo(depth_m=depth, fps=sc.fps), camera.calibration(), labels)
