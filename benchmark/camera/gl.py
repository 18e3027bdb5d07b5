"""The OpenGL depth renderer: one off-screen pass per frame, headless through EGL, gives the exact
depth along the optical axis and a label image.

``PYOPENGL_PLATFORM=egl`` is set here before pyrender is imported, unless the caller chose
another platform."""

from __future__ import annotations

import ctypes
import os
import weakref

import numpy as np

from benchmark.camera.camera import Camera, clip_from_cam
from benchmark.camera.scene import body_pose0, geom_trimesh
from benchmark.errors import BenchmarkError, RenderError

os.environ.setdefault("PYOPENGL_PLATFORM", "egl")

_DEBIAN_PACKAGES = "libegl1 libgl1-mesa-dri"


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


def _geometry(model, labels: np.ndarray) -> tuple:
    """The drawn geoms' vertex attributes and triangles, ``(meshes, capsules)``: each a dict of lists
    (``position``, ``body_label``, for capsules ``end_a_radius`` and ``end_b``, and ``faces``), in
    each geom's body frame (in the world for geoms welded to it)."""
    import mujoco
    import trimesh

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
            T = body_pose0(model, body) @ T
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
    return meshes, capsules


def _framebuffer(GL, gl: _GLObjects, W: int, H: int) -> None:
    """A single-sample framebuffer of depth along the optical axis (float), labels (byte) and a depth buffer."""
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
        from OpenGL import GL

        labels = np.asarray(labels)
        if labels.shape != (model.ngeom,):
            raise BenchmarkError(f"labels must have shape ({model.ngeom},), one per geom, got {labels.shape}")
        self._gl = _offscreen(camera.width, camera.height)
        self.camera = camera
        meshes, capsules = _geometry(model, labels)
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
        _framebuffer(GL, gl, W, H)

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
