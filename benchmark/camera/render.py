"""Depth rendering: what a DS325-like depth camera sees of the simulated scene.

The rendered scene mirrors the MuJoCo geoms one to one (the table, the box, every capsule and
sphere of the hand): each geom's triangle mesh is built once from the MjModel in its body's
frame, and per frame only the bodies' poses (``data.xpos`` / ``data.xmat``) are applied. One
off-screen pass per frame, in pyrender's headless GL context, gives the exact depth along the
optical axis and a label image (which geom is seen where).
The sensor model (:mod:`benchmark.camera.sensor`) then turns the exact depth into a measurement.

Camera conventions: `fsv` and :class:`fsv.Calibration` use OpenCV's pinhole camera (x right,
y down, z forward; pixel centres at integer coordinates). OpenGL uses x right, y up, z backward
and puts pixel centres at half-integers. The conversion happens once, here: the shader works in
the OpenCV camera frame and :func:`clip_from_cam` projects it with the OpenCV intrinsics, the
half-pixel shift and image rows top first; ``GL_FROM_CV`` converts camera poses for OpenGL-style
cameras (pyrender's, MuJoCo's).

Rendering is headless through EGL (Mesa's llvmpipe on a CPU-only machine):
``PYOPENGL_PLATFORM=egl`` is set here before pyrender is imported, unless the caller chose
another platform.
"""

from __future__ import annotations

import ctypes
import importlib.resources
import os
import weakref
from dataclasses import dataclass

import numpy as np
import yaml

from benchmark.world.episode import Episode
from benchmark.errors import BenchmarkError, RenderError
from benchmark.camera.sensor import SensorModel, sensor_preset
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
    """A triangle mesh of one MuJoCo geom in the geom's own frame (not for spheres and capsules).

    Boxes and meshes are exact; planes become a 2 cm thick slab whose top face is the plane
    (z = 0); ellipsoids are scaled icospheres (320 triangles) and cylinders 32-sided, whose facets
    lie within 1.2 % of the radius of the true surface. Spheres and capsules (the whole hand)
    are not meshed: :class:`DepthRenderer` ray-casts them exactly.

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
    if kind == G.mjGEOM_ELLIPSOID:
        mesh = trimesh.creation.icosphere(subdivisions=2, radius=1.0)
        mesh.apply_scale(size)
        return mesh
    if kind == G.mjGEOM_CYLINDER:
        return trimesh.creation.cylinder(radius=size[0], height=2 * size[1], sections=32)
    if kind == G.mjGEOM_MESH:
        mid = int(model.geom_dataid[geom])
        v0, nv = model.mesh_vertadr[mid], model.mesh_vertnum[mid]
        f0, nf = model.mesh_faceadr[mid], model.mesh_facenum[mid]
        return trimesh.Trimesh(vertices=model.mesh_vert[v0 : v0 + nv].copy(), faces=model.mesh_face[f0 : f0 + nf].copy())
    if kind in (G.mjGEOM_SPHERE, G.mjGEOM_CAPSULE):
        raise BenchmarkError(f"geom {geom} is a sphere or capsule: the depth renderer ray-casts those, it has no mesh of them")
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
    A :class:`DepthRenderer`'s own GL objects (buffers, program, framebuffer) are freed when
    it is garbage-collected.
    """
    key = (int(width), int(height))
    if key not in _OFFSCREEN:
        try:
            import pyrender

            _OFFSCREEN[key] = pyrender.OffscreenRenderer(*key)
        except Exception as err:  # PyOpenGL raises ImportError, OSError, RuntimeError or EGL errors
            raise render_error(err) from err
    return _OFFSCREEN[key]


_MESH_VERTEX_SHADER = """
#version 330 core
layout(location = 0) in vec3 position;  // in its body's frame
layout(location = 1) in uvec2 body_label;
uniform mat4 cam_from_body[NUM_BODIES];  // OpenCV camera frame from each body's frame
uniform mat4 clip_from_cam;
out float depth;
flat out uint label;
void main()
{
    vec4 p = cam_from_body[body_label.x] * vec4(position, 1.0);
    depth = p.z;  // affine on a triangle: the perspective-correct interpolation is exact
    label = body_label.y;
    gl_Position = clip_from_cam * p;
}
"""

_MESH_FRAGMENT_SHADER = """
#version 330 core
in float depth;
flat in uint label;
layout(location = 0) out float out_depth;
layout(location = 1) out uint out_label;
void main()
{
    out_depth = depth;
    out_label = label;
}
"""

_CAPSULE_VERTEX_SHADER = """
#version 330 core
layout(location = 0) in vec3 position;  // a corner of the box around the capsule, body frame
layout(location = 1) in uvec2 body_label;
layout(location = 2) in vec4 end_a_radius;  // one end of the axis (body frame) and the radius
layout(location = 3) in vec3 end_b;  // the other end (= end_a for a sphere)
uniform mat4 cam_from_body[NUM_BODIES];
uniform mat4 clip_from_cam;
flat out vec3 a;
flat out vec3 b;
flat out float radius;
flat out uint label;
void main()
{
    mat4 M = cam_from_body[body_label.x];
    a = (M * vec4(end_a_radius.xyz, 1.0)).xyz;
    b = (M * vec4(end_b, 1.0)).xyz;
    radius = end_a_radius.w;
    label = body_label.y;
    gl_Position = clip_from_cam * (M * vec4(position, 1.0));
}
"""

_CAPSULE_FRAGMENT_SHADER = """
#version 330 core
flat in vec3 a;
flat in vec3 b;
flat in float radius;
flat in uint label;
uniform mat3 ray_from_pixel;  // K^-1: the ray (x/z, y/z, 1) through an OpenCV pixel
uniform vec2 ndc_from_depth;  // normalised device depth = x + y / depth
layout(location = 0) out float out_depth;
layout(location = 1) out uint out_label;

// Ray parameter s of the first hit of the ray o + s d (s >= -|o|/|d|) on the sphere (c, r), or 1e30.
float sphere_hit(vec3 o, vec3 d, float dd, vec3 c, float rr)
{
    vec3 oc = o - c;
    float p = dot(d, oc);
    float h = p * p - dd * (dot(oc, oc) - rr);
    return h < 0.0 ? 1e30 : (-p - sqrt(h)) / dd;
}

void main()
{
    vec3 d = ray_from_pixel * vec3(gl_FragCoord.xy - 0.5, 1.0);  // d.z = 1: s is depth
    float dd = dot(d, d);
    float tc = dot(0.5 * (a + b), d) / dd;  // solve near the capsule: no cancellation at range
    vec3 o = tc * d;
    float rr = radius * radius;
    float s = min(sphere_hit(o, d, dd, a, rr), sphere_hit(o, d, dd, b, rr));
    vec3 ba = b - a;
    vec3 oa = o - a;
    float baba = dot(ba, ba);
    float bard = dot(ba, d);
    float baoa = dot(ba, oa);
    float A = baba * dd - bard * bard;
    if (A > 0.0) {  // the side of the cylinder, where its axis coordinate lies between the ends
        float B = baba * dot(d, oa) - baoa * bard;
        float C = baba * dot(oa, oa) - baoa * baoa - rr * baba;
        float h = B * B - A * C;
        if (h >= 0.0) {
            float t = (-B - sqrt(h)) / A;
            float y = baoa + t * bard;
            if (y > 0.0 && y < baba) s = min(s, t);
        }
    }
    if (s > 1e29) discard;
    float depth = tc + s;
    out_depth = depth;
    out_label = label;
    gl_FragDepth = 0.5 * (ndc_from_depth.x + ndc_from_depth.y / depth) + 0.5;
}
"""

CAPSULE_BOX_MARGIN = 1.02
"""Half-size of the box drawn around a capsule or sphere, in radii across its axis (and beyond
its ends): every pixel whose ray meets the capsule lies inside the box's outline."""


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


def _compile_program(GL, vertex_shader: str, fragment_shader: str, num_bodies: int):
    """Links a shader program for `num_bodies` body transforms."""
    shaders = []
    for kind, source in ((GL.GL_VERTEX_SHADER, vertex_shader), (GL.GL_FRAGMENT_SHADER, fragment_shader)):
        shader = GL.glCreateShader(kind)
        GL.glShaderSource(shader, source.replace("NUM_BODIES", str(num_bodies)))
        GL.glCompileShader(shader)
        if not GL.glGetShaderiv(shader, GL.GL_COMPILE_STATUS):
            raise RenderError(f"the depth shader does not compile: {GL.glGetShaderInfoLog(shader).decode(errors='replace')}")
        shaders.append(shader)
    program = GL.glCreateProgram()
    for shader in shaders:
        GL.glAttachShader(program, shader)
    GL.glLinkProgram(program)
    for shader in shaders:
        GL.glDeleteShader(shader)
    if not GL.glGetProgramiv(program, GL.GL_LINK_STATUS):
        raise RenderError(f"the depth shader does not link: {GL.glGetProgramInfoLog(program).decode(errors='replace')}")
    return program


class _GLObjects:
    """The GL objects of one DepthRenderer (programs, vertex arrays, framebuffer), freed on collection."""

    def __init__(self, gl):
        self.gl = gl
        self.programs = []
        self.vaos = []
        self.buffers = []
        self.fbo = None
        self.renderbuffers = []

    def free(self):
        from OpenGL import GL

        try:
            self.gl._platform.make_current()
        except Exception:  # the context is gone (interpreter shutdown): nothing left to free
            return
        if self.fbo is not None:
            GL.glDeleteFramebuffers(1, [self.fbo])
        if self.renderbuffers:
            GL.glDeleteRenderbuffers(len(self.renderbuffers), self.renderbuffers)
        if self.buffers:
            GL.glDeleteBuffers(len(self.buffers), self.buffers)
        if self.vaos:
            GL.glDeleteVertexArrays(len(self.vaos), self.vaos)
        GL.glUseProgram(0)  # a program in use is only flagged for deletion (renders bind their own)
        for program in self.programs:
            GL.glDeleteProgram(program)


def _upload(GL, gl: _GLObjects, attributes, faces) -> int:
    """A vertex array of float or uint attributes (list of (V, k) arrays) and triangles; its id."""
    vao = GL.glGenVertexArrays(1)
    gl.vaos.append(int(vao))
    GL.glBindVertexArray(vao)
    for location, data in enumerate(attributes):
        buffer = GL.glGenBuffers(1)
        gl.buffers.append(int(buffer))
        GL.glBindBuffer(GL.GL_ARRAY_BUFFER, buffer)
        GL.glBufferData(GL.GL_ARRAY_BUFFER, data.nbytes, np.ascontiguousarray(data), GL.GL_STATIC_DRAW)
        GL.glEnableVertexAttribArray(location)
        if data.dtype == np.uint32:
            GL.glVertexAttribIPointer(location, data.shape[1], GL.GL_UNSIGNED_INT, 0, None)
        else:
            GL.glVertexAttribPointer(location, data.shape[1], GL.GL_FLOAT, GL.GL_FALSE, 0, None)
    buffer = GL.glGenBuffers(1)
    gl.buffers.append(int(buffer))
    GL.glBindBuffer(GL.GL_ELEMENT_ARRAY_BUFFER, buffer)
    GL.glBufferData(GL.GL_ELEMENT_ARRAY_BUFFER, faces.nbytes, np.ascontiguousarray(faces), GL.GL_STATIC_DRAW)
    GL.glBindVertexArray(0)
    return int(vao)


class DepthRenderer:
    """Exact depth and label images of a MuJoCo model's geoms from one camera.

    Build once per model, then call :meth:`render` per frame with the bodies' world poses.
    Every drawn geom is uploaded once, in its body's frame (geoms welded to the world, like the
    table, in the world frame), each vertex carrying its body's index and its label; a frame
    uploads only the bodies' poses (one 4 x 4 matrix per body) and draws two calls of two
    minimal shaders into a single-sample framebuffer that holds the depth along the optical axis
    (a float per pixel) and the label (a byte per pixel), read back as they are (no multisample
    resolve, depth-buffer linearisation or row flip):

    - boxes, planes and meshes as triangles, whose depth is interpolated from the vertices'
      exact camera-frame depth (exact on a flat face);
    - capsules and spheres (the hand) exactly: a box around each is drawn, and the fragment
      shader intersects each pixel's ray with the true capsule (discarding the pixels that miss
      it) and writes the depth of the hit, also into the depth buffer (no tessellation error;
      only the box's faces towards the camera are drawn, so a camera inside a box, within about
      a radius of the capsule, would not see it).

    The GL context is pyrender's (the process's shared ``pyrender.OffscreenRenderer``, see
    :func:`_offscreen`); pyrender's own forward pass costs several times more per frame at this
    resolution (its lighting-capable shaders, per-node state and the multisampled read-back).

    Args:
        model: A compiled ``mujoco.MjModel``.
        camera: The camera.
        labels: Label per geom, shape (ngeom,), uint8; geoms with label 0 are not drawn
            (see :func:`world_labels`).
    """

    def __init__(self, model, camera: Camera, labels: np.ndarray):
        import mujoco
        import trimesh
        from OpenGL import GL

        labels = np.asarray(labels)
        if labels.shape != (model.ngeom,):
            raise BenchmarkError(f"labels must have shape ({model.ngeom},), one per geom, got {labels.shape}")
        self._gl = _offscreen(camera.width, camera.height)
        self.camera = camera
        G = mujoco.mjtGeom
        cube = trimesh.creation.box(extents=(2.0, 2.0, 2.0))  # corners at +-1, faces outward
        meshes = {"position": [], "body_label": [], "faces": []}
        capsules = {"position": [], "body_label": [], "end_a_radius": [], "end_b": [], "faces": []}
        for g in np.flatnonzero(labels):
            T = np.eye(4)  # pose of the geom in its body's frame (in the world for welded bodies)
            mat = np.zeros(9)
            mujoco.mju_quat2Mat(mat, model.geom_quat[g])
            T[:3, :3] = mat.reshape(3, 3)
            T[:3, 3] = model.geom_pos[g]
            body = int(model.geom_bodyid[g])
            if model.body_weldid[body] == 0 and model.body_mocapid[body] < 0:  # welded to the world
                T = _body_pose0(model, body) @ T
                body = 0  # the world body: identity pose
            kind = int(model.geom_type[g])
            if kind in (G.mjGEOM_CAPSULE, G.mjGEOM_SPHERE):
                r = float(model.geom_size[g, 0])
                half = float(model.geom_size[g, 1]) if kind == G.mjGEOM_CAPSULE else 0.0
                corners = cube.vertices * CAPSULE_BOX_MARGIN * np.array([r, r, half + r])
                part = capsules
                ends = np.array([[0.0, 0.0, -half], [0.0, 0.0, half]]) @ T[:3, :3].T + T[:3, 3]
                part["end_a_radius"].append(np.tile(np.append(ends[0], r), (len(corners), 1)))
                part["end_b"].append(np.tile(ends[1], (len(corners), 1)))
                vertices, faces = corners @ T[:3, :3].T + T[:3, 3], cube.faces
            else:
                mesh = geom_trimesh(model, int(g))
                mesh.apply_transform(T)
                part = meshes
                vertices, faces = mesh.vertices, mesh.faces
            start = sum(len(p) for p in part["position"])
            part["position"].append(vertices)
            part["body_label"].append(np.tile([body, labels[g]], (len(vertices), 1)))
            part["faces"].append(np.asarray(faces) + start)
        self.triangles = sum(len(f) for part in (meshes, capsules) for f in part["faces"])
        W, H = camera.width, camera.height
        cam_from_world = np.linalg.inv(camera.T_world_cam)
        self._R_cw, self._t_cw = cam_from_world[:3, :3].copy(), cam_from_world[:3, 3].copy()
        self._poses = np.zeros((model.nbody, 4, 4), dtype=np.float32)  # cam_from_body per body
        self._poses[:, 3, 3] = 1.0
        self._rot = np.empty((model.nbody, 3, 3))
        self._clear_depth = np.zeros(4, dtype=np.float32)
        self._clear_label = np.zeros(4, dtype=np.uint32)
        self._clear_z = np.ones(1, dtype=np.float32)

        self._gl._platform.make_current()
        max_components = int(GL.glGetIntegerv(GL.GL_MAX_VERTEX_UNIFORM_COMPONENTS))
        if 16 * (model.nbody + 1) > max_components:
            raise RenderError(
                f"the model has {model.nbody} bodies; this GL driver's vertex shaders hold at most "
                f"{max_components // 16 - 1} body poses"
            )
        gl = self._objects = _GLObjects(self._gl)
        weakref.finalize(self, gl.free).atexit = False
        P = clip_from_cam(camera)
        self._draws = []  # (program, location of cam_from_body, vertex array, index count)
        for part, (vs, fs) in (
            (meshes, (_MESH_VERTEX_SHADER, _MESH_FRAGMENT_SHADER)),
            (capsules, (_CAPSULE_VERTEX_SHADER, _CAPSULE_FRAGMENT_SHADER)),
        ):
            if not part["faces"]:
                continue
            program = _compile_program(GL, vs, fs, model.nbody)
            gl.programs.append(program)
            GL.glUseProgram(program)
            GL.glUniformMatrix4fv(GL.glGetUniformLocation(program, "clip_from_cam"), 1, GL.GL_TRUE, P.astype(np.float32))
            if part is capsules:
                K_inv = np.linalg.inv(camera.K).astype(np.float32)
                GL.glUniformMatrix3fv(GL.glGetUniformLocation(program, "ray_from_pixel"), 1, GL.GL_TRUE, K_inv)
                GL.glUniform2f(GL.glGetUniformLocation(program, "ndc_from_depth"), P[2, 2], P[2, 3])
            attributes = [
                np.concatenate(part[name]).astype(np.uint32 if name == "body_label" else np.float32)
                for name in part
                if name != "faces"
            ]
            faces = np.concatenate(part["faces"]).astype(np.uint32)
            vao = _upload(GL, gl, attributes, faces)
            self._draws.append((program, GL.glGetUniformLocation(program, "cam_from_body"), vao, faces.size))
        self.draw_calls = len(self._draws)
        gl.renderbuffers = [int(b) for b in GL.glGenRenderbuffers(3)]
        gl.fbo = GL.glGenFramebuffers(1)
        GL.glBindFramebuffer(GL.GL_FRAMEBUFFER, gl.fbo)
        for rb, fmt, attachment in zip(
            gl.renderbuffers,
            (GL.GL_R32F, GL.GL_R8UI, GL.GL_DEPTH_COMPONENT32F),
            (GL.GL_COLOR_ATTACHMENT0, GL.GL_COLOR_ATTACHMENT1, GL.GL_DEPTH_ATTACHMENT),
        ):
            GL.glBindRenderbuffer(GL.GL_RENDERBUFFER, rb)
            GL.glRenderbufferStorage(GL.GL_RENDERBUFFER, fmt, W, H)
            GL.glFramebufferRenderbuffer(GL.GL_FRAMEBUFFER, attachment, GL.GL_RENDERBUFFER, rb)
        GL.glDrawBuffers(2, [GL.GL_COLOR_ATTACHMENT0, GL.GL_COLOR_ATTACHMENT1])
        status = GL.glCheckFramebufferStatus(GL.GL_FRAMEBUFFER)
        GL.glBindFramebuffer(GL.GL_FRAMEBUFFER, 0)
        if status != GL.GL_FRAMEBUFFER_COMPLETE:
            raise RenderError(f"the GL driver cannot render depth and labels offscreen (framebuffer status {status:#x})")

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

        n = self._poses.shape[0]
        xpos = np.asarray(xpos, dtype=np.float64)
        xmat = np.asarray(xmat, dtype=np.float64).reshape(-1, 3, 3)
        if xpos.shape != (n, 3) or xmat.shape[0] != n:
            raise BenchmarkError(
                f"render takes xpos (nbody, 3) and xmat (nbody, 9) with nbody = {n}, got {xpos.shape}, {xmat.shape}"
            )
        np.matmul(self._R_cw, xmat, out=self._rot)
        self._poses[:, :3, :3] = self._rot
        self._poses[:, :3, 3] = xpos @ self._R_cw.T + self._t_cw
        H, W = self.camera.height, self.camera.width
        depth = np.empty((H, W), dtype=np.float32)
        labels = np.empty((H, W), dtype=np.uint8)
        self._gl._platform.make_current()
        GL.glBindFramebuffer(GL.GL_FRAMEBUFFER, self._objects.fbo)
        GL.glViewport(0, 0, W, H)
        GL.glEnable(GL.GL_DEPTH_TEST)
        GL.glDepthFunc(GL.GL_LESS)
        GL.glDepthMask(GL.GL_TRUE)
        GL.glDepthRange(0.0, 1.0)
        GL.glDisable(GL.GL_BLEND)
        GL.glEnable(GL.GL_CULL_FACE)
        GL.glCullFace(GL.GL_BACK)
        GL.glFrontFace(GL.GL_CW)
        GL.glClearBufferfv(GL.GL_COLOR, 0, self._clear_depth)
        GL.glClearBufferuiv(GL.GL_COLOR, 1, self._clear_label)
        GL.glClearBufferfv(GL.GL_DEPTH, 0, self._clear_z)
        for program, loc_poses, vao, count in self._draws:
            GL.glUseProgram(program)
            GL.glUniformMatrix4fv(loc_poses, n, GL.GL_TRUE, self._poses)
            GL.glBindVertexArray(vao)
            GL.glDrawElements(GL.GL_TRIANGLES, count, GL.GL_UNSIGNED_INT, None)
        GL.glBindVertexArray(0)
        GL.glPixelStorei(GL.GL_PACK_ALIGNMENT, 1)
        GL.glReadBuffer(GL.GL_COLOR_ATTACHMENT0)
        GL.glReadPixels(0, 0, W, H, GL.GL_RED, GL.GL_FLOAT, depth)
        GL.glReadBuffer(GL.GL_COLOR_ATTACHMENT1)
        GL.glReadPixels(0, 0, W, H, GL.GL_RED_INTEGER, GL.GL_UNSIGNED_BYTE, labels)
        GL.glBindFramebuffer(GL.GL_FRAMEBUFFER, 0)
        return depth, labels


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
        sensor: A :class:`benchmark.camera.sensor.SensorModel`.
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
    """Renders the depth video the scenario's depth camera would record of a simulated episode.

    Args:
        episode: A simulated episode (its truth gives the box and hand pose per frame).
        sensor: The sensor model; default the scenario's preset with its noise,
            ``sensor_preset(scenario.sensor, scenario.noise_m)`` (docs/scenarios.md). Its
            ``noise_m`` must equal the scenario's.
        camera: The camera; default ``sim_assets/camera.yaml``.

    Returns:
        The episode with ``depth`` (T frames at the scenario's fps, T = len(truth.t)),
        ``calib`` and the truth-side ``labels`` (T, H, W) uint8 (never handed to `fsv`).
        The noise comes from the scenario's "depth" random stream: same scenario, same bits.
    """
    from benchmark.world.assets import build_world, set_frame

    sc = episode.scenario
    sensor = sensor_preset(sc.sensor, sc.noise_m) if sensor is None else sensor
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
