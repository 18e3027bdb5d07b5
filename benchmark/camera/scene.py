"""The rendered scene: a triangle mesh per MuJoCo geom, in its body's frame, and the label of each."""

from __future__ import annotations

import mujoco
import numpy as np

from benchmark.errors import BenchmarkError

LABEL_NONE = 0
LABEL_TABLE = 1
LABEL_BOX = 2
LABEL_PALM = 9
LABEL_FINGER0 = 10
"""Label image values: 0 nothing, 1 table, 2 box, 9 palm, 10 + k finger k (thumb first)."""

PLANE_HALF_EXTENT_M = 5.0
"""Half size of the rendered table when its MuJoCo plane is infinite (size 0)."""

def world_labels(world) -> np.ndarray:
    """Which label each geom of a :class:`benchmark.world.assets.World` gets in the label image.

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


_BOX_VERTICES = ((0.0, 0.0, 0.0), (0.0, 0.0, 1.0), (0.0, 1.0, 0.0), (0.0, 1.0, 1.0), (1.0, 0.0, 0.0), (1.0, 0.0, 1.0),
                 (1.0, 1.0, 0.0), (1.0, 1.0, 1.0))
_BOX_FACES = ((1, 3, 0), (4, 1, 0), (0, 3, 2), (2, 4, 0), (1, 7, 3), (5, 1, 4), (5, 7, 1), (3, 7, 2), (6, 4, 2), (2, 7, 6),
              (6, 5, 4), (7, 5, 6))
"""trimesh's unit cube (``trimesh.creation.box``, trimesh 4-5): its corners and its triangles in its order."""


def geom_mesh(model, geom: int, pose: np.ndarray) -> tuple:
    """``(vertices (V, 3) float64, faces (F, 3) int64)``: :func:`geom_trimesh` of a geom moved by
    ``pose`` (4, 4), the same numbers. Boxes and planes (every meshed geom of the benchmark's
    worlds) are built here as trimesh builds and moves them, without importing trimesh (0.3 s of
    CPU at the start of every render worker); the other kinds go through trimesh."""
    kind = int(model.geom_type[geom])
    size = np.asarray(model.geom_size[geom], dtype=float)
    G = mujoco.mjtGeom
    if kind == G.mjGEOM_PLANE:
        hx = size[0] if size[0] > 0 else PLANE_HALF_EXTENT_M
        hy = size[1] if size[1] > 0 else PLANE_HALF_EXTENT_M
        lower = np.eye(4)
        lower[2, 3] = -0.01
        vertices, faces = _moved(*_box((2 * hx, 2 * hy, 0.02)), lower)
    elif kind == G.mjGEOM_BOX:
        vertices, faces = _box(2 * size)
    else:
        mesh = geom_trimesh(model, geom)
        mesh.apply_transform(pose)
        return np.asarray(mesh.vertices, dtype=np.float64), np.asarray(mesh.faces, dtype=np.int64)
    return _moved(vertices, faces, pose)


def _box(extents) -> tuple:
    """``trimesh.creation.box(extents=extents)``'s vertices and faces."""
    vertices = np.array(_BOX_VERTICES, order="C", dtype=np.float64)
    vertices -= 0.5
    vertices *= np.asanyarray(extents, dtype=np.float64)
    return vertices, np.array(_BOX_FACES, order="C", dtype=np.int64)


def _moved(vertices: np.ndarray, faces: np.ndarray, matrix) -> tuple:
    """``trimesh.Trimesh.apply_transform`` (trimesh 5) on vertices and faces: the same products (its
    ``np.dot`` of the homogeneous points, once per geom), its tests for an identity and a mirror."""
    matrix = np.asanyarray(matrix, order="C", dtype=np.float64)
    if float(np.ptp(matrix - np.eye(4))) < 1e-8:
        return vertices, faces
    if np.abs(matrix - np.eye(4)).max() < 1e-8:
        moved = np.ascontiguousarray(vertices.copy())
    else:
        moved = np.dot(matrix, np.column_stack((vertices, np.ones(len(vertices)))).T).T[:, :3]
    rotates = not float(np.ptp(matrix[:3, :3] - np.eye(3))) < 1e-6
    if rotates and bool(np.linalg.det(matrix[:3, :3]) < 0.0):
        faces = np.ascontiguousarray(np.fliplr(faces))
    return np.ascontiguousarray(moved, dtype=np.float64), faces


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
    import trimesh  # lazy: trimesh (0.5 s) off `fsv-bench`'s start-up

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


def body_pose0(model, body: int) -> np.ndarray:
    """World pose (4, 4) of a body welded to the world, from the model alone."""

    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    T = np.eye(4)
    T[:3, :3] = data.xmat[body].reshape(3, 3)
    T[:3, 3] = data.xpos[body]
    return T
