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
