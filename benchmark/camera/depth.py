"""The depth renderer: exact depth along the optical axis and a label image, on the CPU.

Rasterised by this project's own kernels (:mod:`benchmark.camera.raster_kernels`): every pixel's
depth is the exact hit of its OpenCV ray on the scene's surfaces, computed in float64 in a fixed
order. No GPU, driver or GL library takes part, so the depth of a scenario is the same bits on
every machine, with or without a GPU (a GPU's rasteriser and Mesa's differ in the last bits of
interpolated depth and in silhouette pixels, and each driver version may differ again).
"""

from __future__ import annotations

import numpy as np

from benchmark.camera.camera import Camera
from benchmark.camera.scene import body_pose0, geom_trimesh
from benchmark.errors import BenchmarkError

RASTERISER = "fsv-bench cpu raster v1"
"""The name of the rasteriser, recorded with every rendered episode (its bits are pinned by
``tests/test_render.py``)."""


def _geometry(model, labels: np.ndarray) -> tuple:
    """The drawn geoms, ``(triangles, capsules)`` in their bodies' frames (in the world for geoms
    welded to it): triangles as a dict of ``vertices`` (V, 3), ``vertex_body`` (V,), ``faces`` (F, 3)
    and ``face_label`` (F,); capsules and spheres as ``ends`` (C, 2, 3), ``body`` (C,), ``radius``
    (C,) and ``label`` (C,)."""
    import mujoco

    G = mujoco.mjtGeom
    verts, vbody, faces, flabel = [], [], [], []
    ends, cbody, radius, clabel = [], [], [], []
    count = 0
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
            half = float(model.geom_size[g, 1]) if kind == G.mjGEOM_CAPSULE else 0.0
            ends.append(np.array([[0.0, 0.0, -half], [0.0, 0.0, half]]) @ T[:3, :3].T + T[:3, 3])
            cbody.append(body)
            radius.append(float(model.geom_size[g, 0]))
            clabel.append(labels[g])
        else:
            mesh = geom_trimesh(model, int(g))
            mesh.apply_transform(T)
            verts.append(np.asarray(mesh.vertices, dtype=np.float64))
            vbody.append(np.full(len(mesh.vertices), body))
            faces.append(np.asarray(mesh.faces, dtype=np.int64) + count)
            flabel.append(np.full(len(mesh.faces), labels[g]))
            count += len(mesh.vertices)

    def stack(parts, shape, dtype):
        return np.ascontiguousarray(np.concatenate(parts).astype(dtype)) if parts else np.zeros(shape, dtype)

    triangles = {"vertices": stack(verts, (0, 3), np.float64), "vertex_body": stack(vbody, (0,), np.int64),
                 "faces": stack(faces, (0, 3), np.int64), "face_label": stack(flabel, (0,), np.uint8)}
    capsules = {"ends": np.ascontiguousarray(np.asarray(ends, dtype=np.float64).reshape(-1, 2, 3)),
                "body": np.asarray(cbody, dtype=np.int64).reshape(-1),
                "radius": np.asarray(radius, dtype=np.float64), "label": np.asarray(clabel, dtype=np.uint8)}
    return triangles, capsules


class DepthRenderer:
    """Exact depth and label images of a MuJoCo model's geoms from one camera, on the CPU.

    Build once per model, then call :meth:`render` per frame with the bodies' world poses. Every
    drawn geom is kept in its body's frame (geoms welded to the world, like the table, in the
    world frame); a frame moves the vertices and capsule axes by the bodies' poses and draws:

    - boxes, planes and meshes as triangles (front faces only), each pixel's depth the exact hit
      of its ray on the triangle's plane;
    - capsules and spheres (the hand) exactly: each pixel's ray is intersected with the true
      capsule (no tessellation).

    Pixels are sampled at their centres (no anti-aliasing); the nearest surface wins, the first
    drawn on an exact tie.

    Args:
        model: A compiled ``mujoco.MjModel``.
        camera: The camera.
        labels: Label per geom, shape (ngeom,), uint8; geoms with label 0 are not drawn
            (see :func:`benchmark.camera.scene.world_labels`).
    """

    def __init__(self, model, camera: Camera, labels: np.ndarray):
        labels = np.asarray(labels)
        if labels.shape != (model.ngeom,):
            raise BenchmarkError(f"labels must have shape ({model.ngeom},), one per geom, got {labels.shape}")
        self.camera = camera
        self._tri, self._cap = _geometry(model, labels.astype(np.uint8))
        self.triangles = len(self._tri["faces"])
        self.capsules = len(self._cap["radius"])
        cam_from_world = np.linalg.inv(camera.T_world_cam)
        self._R_cw, self._t_cw = cam_from_world[:3, :3].copy(), cam_from_world[:3, 3].copy()
        self._nbody = model.nbody
        K = np.asarray(camera.K, dtype=np.float64)
        self._intrinsics = (float(K[0, 0]), float(K[1, 1]), float(K[0, 2]), float(K[1, 2]))
        H, W = camera.height, camera.width
        self._zbuf = np.empty((H, W))
        self._lbuf = np.empty((H, W), dtype=np.uint8)
        self._verts = np.empty_like(self._tri["vertices"])
        self._ends = np.empty_like(self._cap["ends"])
        self._end_body = np.ascontiguousarray(np.repeat(self._cap["body"], 2))
        self._rot = np.empty((model.nbody, 3, 3))
        self._trans = np.empty((model.nbody, 3))

    def render(self, xpos: np.ndarray, xmat: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Renders one frame.

        Args:
            xpos: World positions of all bodies, shape (nbody, 3), [m] (``data.xpos``).
            xmat: World orientations of all bodies, shape (nbody, 9) or (nbody, 3, 3) (``data.xmat``).

        Returns:
            ``(depth, labels)``: exact depth along the optical axis, shape (H, W), float32 metres
            (0 where nothing is seen), and the label of the geom seen at each pixel, (H, W) uint8.
        """
        from benchmark.camera import raster_kernels as rk

        n = self._nbody
        xpos = np.ascontiguousarray(xpos, dtype=np.float64)
        xmat = np.ascontiguousarray(xmat, dtype=np.float64).reshape(-1, 3, 3)
        if xpos.shape != (n, 3) or xmat.shape[0] != n:
            raise BenchmarkError(
                f"render takes xpos (nbody, 3) and xmat (nbody, 9) with nbody = {n}, got {xpos.shape}, {xmat.shape}"
            )
        rk.camera_from_bodies(self._R_cw, self._t_cw, xpos, xmat, self._rot, self._trans)
        fx, fy, cx, cy = self._intrinsics
        cam = self.camera
        self._zbuf.fill(np.inf)
        self._lbuf.fill(0)
        rk.transform_points(self._tri["vertices"], self._tri["vertex_body"], self._rot, self._trans, self._verts)
        rk.draw_triangles(self._verts, self._tri["faces"], self._tri["face_label"], fx, fy, cx, cy, cam.znear,
                          cam.zfar, self._zbuf, self._lbuf)
        ends = self._cap["ends"]
        rk.transform_points(ends.reshape(-1, 3), self._end_body, self._rot, self._trans,
                            self._ends.reshape(-1, 3))
        rk.draw_capsules(self._ends, self._cap["radius"], self._cap["label"], fx, fy, cx, cy, cam.znear, cam.zfar,
                         self._zbuf, self._lbuf)
        depth = np.empty((cam.height, cam.width), dtype=np.float32)
        labels = np.empty((cam.height, cam.width), dtype=np.uint8)
        rk.finish(self._zbuf, self._lbuf, depth, labels)
        return depth, labels
