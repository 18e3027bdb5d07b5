"""The depth renderer: exact depth along the optical axis and a label image, on the CPU.

Rasterised by this project's own kernels (:mod:`benchmark.camera.raster_kernels`): every pixel's
depth is the exact hit of its OpenCV ray on the scene's surfaces, computed in float64 in a fixed
order. No GPU, driver or GL library takes part, so the depth of a scenario is the same bits on
every machine, with or without a GPU (a GPU's rasteriser and Mesa's differ in the last bits of
interpolated depth and in silhouette pixels, and each driver version may differ again).
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from benchmark.camera import raster_kernels as rk
from benchmark.camera import skin_kernels as sk
from benchmark.camera.camera import Camera
from benchmark.camera.scene import LABEL_PALM, body_pose0, geom_mesh
from benchmark.errors import BenchmarkError
from benchmark.world.skin import PULP_EXPONENT_PER_MM, PULP_REACH, PULP_STIFFNESS_N_PER_MM, Skin, skin_of
from fsv.linalg import mm, mv, rigid_inverse

RASTERISER = "fsv-bench cpu raster v1"
"""The name of the rasteriser, recorded with every rendered episode (its bits are pinned by
``tests/test_render.py``)."""


def _geometry(model, labels: np.ndarray) -> tuple:
    """The drawn geoms, ``(triangles, capsules)`` in their bodies' frames (in the world for geoms
    welded to it): triangles as a dict of ``vertices`` (V, 3), ``vertex_body`` (V,), ``faces`` (F, 3)
    and ``face_label`` (F,); capsules and spheres as ``ends`` (C, 2, 3), ``body`` (C,), ``radius``
    (C,) and ``label`` (C,)."""

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
            T = mm(body_pose0(model, body), T)
            body = 0  # the world body: identity pose
        kind = int(model.geom_type[g])
        if kind in (G.mjGEOM_CAPSULE, G.mjGEOM_SPHERE):
            half = float(model.geom_size[g, 1]) if kind == G.mjGEOM_CAPSULE else 0.0
            ends.append(np.stack([mv(T[:3, :3], np.array([0.0, 0.0, z])) for z in (-half, half)]) + T[:3, 3])
            cbody.append(body)
            radius.append(float(model.geom_size[g, 0]))
            clabel.append(labels[g])
        else:
            vertices, tri = geom_mesh(model, int(g), T)
            verts.append(vertices)
            vbody.append(np.full(len(vertices), body))
            faces.append(tri + count)
            flabel.append(np.full(len(tri), labels[g]))
            count += len(vertices)

    def stack(parts, shape, dtype):
        return np.ascontiguousarray(np.concatenate(parts).astype(dtype)) if parts else np.zeros(shape, dtype)

    triangles = {"vertices": stack(verts, (0, 3), np.float64), "vertex_body": stack(vbody, (0,), np.int64),
                 "faces": stack(faces, (0, 3), np.int64), "face_label": stack(flabel, (0,), np.uint8)}
    capsules = {"ends": np.ascontiguousarray(np.asarray(ends, dtype=np.float64).reshape(-1, 2, 3)),
                "body": np.asarray(cbody, dtype=np.int64).reshape(-1),
                "radius": np.asarray(radius, dtype=np.float64), "label": np.asarray(clabel, dtype=np.uint8)}
    return triangles, capsules


@dataclass(frozen=True)
class HandSkin:
    """A skin to draw instead of the hand's primitives, and what it needs from the model.

    Attributes:
        skin: The person's :class:`benchmark.world.skin.Skin`.
        segment_body: Body of each hand segment in the model, (B,) int64.
        box_body: Body of the box (the skin is flattened on its faces).
        box_half: The box's half extents, (3,) [m]; its geom sits at its body's origin, unrotated.
    """

    skin: Skin
    segment_body: np.ndarray
    box_body: int
    box_half: np.ndarray


def hand_skin(world) -> HandSkin:
    """The skin of a :class:`benchmark.world.assets.World`'s hand, as the renderer draws it."""
    return HandSkin(skin=skin_of(world.hand), segment_body=np.asarray(world.segment_body, dtype=np.int64),
                    box_body=int(world.box_body), box_half=np.asarray(world.obj.half_extents, dtype=np.float64))


def drawn_hand(world, truth, hand_surface: str) -> tuple:
    """How every renderer draws the hand of a scenario: ``(skin, pulps)``.

    ``(None, None)`` for ``"capsules"`` (the primitives); the person's :func:`hand_skin` for
    ``"skin-rigid"``, with its pulps pressed (:func:`pulp_presses`) for ``"skin"``.
    """
    if hand_surface == "capsules":
        return None, None
    return hand_skin(world), (pulp_presses(truth) if hand_surface == "skin" else None)


def pulp_presses(truth) -> tuple[np.ndarray, np.ndarray]:
    """Per frame and finger, the world-frame centre of pressure and the pulp's push (its compression
    along the contact normal, :func:`benchmark.world.skin.pulp_indentation_m`), each (T, K, 3) [m]."""

    T, K = truth.contact_point.shape[:2]
    centre, push = np.empty((T, K, 3)), np.empty((T, K, 3))
    sk.pulp_presses(np.ascontiguousarray(truth.box_pos, dtype=np.float64),
                    np.ascontiguousarray(truth.box_quat, dtype=np.float64),
                    np.ascontiguousarray(truth.contact_point, dtype=np.float64),
                    np.ascontiguousarray(truth.contact_normal, dtype=np.float64),
                    np.ascontiguousarray(truth.contact_force, dtype=np.float64),
                    np.ascontiguousarray(truth.contact_active, dtype=np.bool_),
                    float(PULP_STIFFNESS_N_PER_MM), float(PULP_EXPONENT_PER_MM), centre, push)
    return centre, push


class DepthRenderer:
    """Exact depth and label images of a MuJoCo model's geoms from one camera, on the CPU.

    Build once per model, then call :meth:`render` per frame with the bodies' world poses. Every
    drawn geom is kept in its body's frame (geoms welded to the world, like the table, in the
    world frame); a frame moves the vertices and capsule axes by the bodies' poses and draws:

    - boxes, planes and meshes as triangles (front faces only), each pixel's depth the exact hit
      of its ray on the triangle's plane;
    - capsules and spheres (the hand) exactly: each pixel's ray is intersected with the true
      capsule (no tessellation).

    - with a ``skin``, the hand as its skin instead of its primitives: skinned on the bodies'
      poses, each pressed pulp pushed into the face it presses, every vertex that would enter the
      box moved onto its nearest face, then drawn as triangles (:mod:`benchmark.camera.skin_kernels`).

    Pixels are sampled at their centres (no anti-aliasing); the nearest surface wins, the first
    drawn on an exact tie.

    Args:
        model: A compiled ``mujoco.MjModel``.
        camera: The camera.
        labels: Label per geom, shape (ngeom,), uint8; geoms with label 0 are not drawn
            (see :func:`benchmark.camera.scene.world_labels`).
        skin: Draw the hand as this skin (its primitives, labels 9 and up, are then not drawn);
            None draws the primitives.
    """

    def __init__(self, model, camera: Camera, labels: np.ndarray, skin: HandSkin | None = None):
        labels = np.asarray(labels)
        if labels.shape != (model.ngeom,):
            raise BenchmarkError(f"labels must have shape ({model.ngeom},), one per geom, got {labels.shape}")
        self.camera = camera
        labels = labels.astype(np.uint8)
        if skin is not None:
            labels = np.where(labels >= LABEL_PALM, 0, labels).astype(np.uint8)
        self._tri, self._cap = _geometry(model, labels)
        self._skin = skin
        if skin is not None:
            s = skin.skin
            if not (np.allclose(model.geom_pos[model.body_geomadr[skin.box_body]], 0)
                    and np.allclose(model.geom_quat[model.body_geomadr[skin.box_body]], [1, 0, 0, 0])):
                raise BenchmarkError("the skin is flattened on a box geom at its body's origin, unrotated")
            seg_body = np.asarray(skin.segment_body, dtype=np.int64)
            self._skin_body = np.ascontiguousarray(seg_body[s.segment])
            self._skin_parent_body = np.ascontiguousarray(seg_body[s.parent])
            self._skin_verts = np.empty_like(s.local)
            self._reach = np.ascontiguousarray(PULP_REACH * s.pad_radius)
            self._box_half = np.ascontiguousarray(skin.box_half, dtype=np.float64)
            self._world_body = np.zeros(len(s.pad_radius), dtype=np.int64)
            self._centre_cam = np.empty((len(s.pad_radius), 3))
            self._push_cam = np.empty((len(s.pad_radius), 3))
            self._no_trans = np.zeros((1, 3))
        self.triangles = len(self._tri["faces"])
        self.capsules = len(self._cap["radius"])
        cam_from_world = rigid_inverse(camera.T_world_cam)
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

    def render(self, xpos: np.ndarray, xmat: np.ndarray, pulp_centre: np.ndarray | None = None,
               pulp_push: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Renders one frame.

        Args:
            xpos: World positions of all bodies, shape (nbody, 3), [m] (``data.xpos``).
            xmat: World orientations of all bodies, shape (nbody, 9) or (nbody, 3, 3) (``data.xmat``).
            pulp_centre: With a skin, each finger's centre of pressure, world frame, (K, 3) [m].
            pulp_push: With a skin, each pulp's push into its face, world frame, (K, 3) [m]
                (zero where the finger does not press; :func:`pulp_presses`). None: no pulp pressed.

        Returns:
            ``(depth, labels)``: exact depth along the optical axis, shape (H, W), float32 metres
            (0 where nothing is seen), and the label of the geom seen at each pixel, (H, W) uint8.
        """

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
        if self._skin is not None:
            self._draw_skin(pulp_centre, pulp_push, fx, fy, cx, cy)
        ends = self._cap["ends"]
        rk.transform_points(ends.reshape(-1, 3), self._end_body, self._rot, self._trans,
                            self._ends.reshape(-1, 3))
        rk.draw_capsules(self._ends, self._cap["radius"], self._cap["label"], fx, fy, cx, cy, cam.znear, cam.zfar,
                         self._zbuf, self._lbuf)
        depth = np.empty((cam.height, cam.width), dtype=np.float32)
        labels = np.empty((cam.height, cam.width), dtype=np.uint8)
        rk.finish(self._zbuf, self._lbuf, depth, labels)
        return depth, labels

    @property
    def skin(self) -> Skin | None:
        """The skin drawn for the hand, or None when the hand is drawn as its primitives."""
        return None if self._skin is None else self._skin.skin

    def _pose_skin(self, pulp_centre, pulp_push) -> None:
        s = self._skin.skin
        sk.skin_points(s.local, self._skin_body, s.parent_local, self._skin_parent_body, s.parent_weight,
                       self._rot, self._trans, self._skin_verts)
        if pulp_push is not None:
            K = len(self._reach)
            centre = np.ascontiguousarray(pulp_centre, dtype=np.float64)
            push = np.ascontiguousarray(pulp_push, dtype=np.float64)
            if centre.shape != (K, 3) or push.shape != (K, 3):
                raise BenchmarkError(f"pulp_centre and pulp_push must have shape ({K}, 3), got {centre.shape}, {push.shape}")
            rk.transform_points(centre, self._world_body, self._rot, self._trans, self._centre_cam)
            rk.transform_points(push, self._world_body, self._rot, self._no_trans, self._push_cam)
            sk.press_pulps(self._skin_verts, s.finger, s.pulp, self._centre_cam, self._push_cam, self._reach)
        b = self._skin.box_body
        sk.flatten_on_box(self._skin_verts, self._rot[b], self._trans[b], self._box_half)

    def _draw_skin(self, pulp_centre, pulp_push, fx, fy, cx, cy) -> None:
        self._pose_skin(pulp_centre, pulp_push)
        s = self._skin.skin
        cam = self.camera
        rk.draw_triangles(self._skin_verts, s.faces, s.face_label, fx, fy, cx, cy, cam.znear, cam.zfar,
                          self._zbuf, self._lbuf)
