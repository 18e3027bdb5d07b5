"""The skin's per-frame kernels: skinning, pressed pulps and flattening (benchmark.camera.skin_kernels)."""

from __future__ import annotations

import numpy as np
import pytest

from benchmark.camera import skin_kernels as sk
from fsv.rotation import quat_to_rot


def _rot(rng):
    q = rng.normal(size=4)
    return quat_to_rot(q / np.linalg.norm(q))


def test_skinning_is_rigid_when_parent_and_child_move_together_and_blends_otherwise():
    rng = np.random.default_rng(0)
    local = rng.normal(size=(50, 3))
    R, t = _rot(rng), rng.normal(size=3)
    # body 1 sits at (R1, t1) in body 0: parent coordinates of a vertex are R1 p + t1
    R1, t1 = _rot(rng), rng.normal(size=3)
    parent_local = local @ R1.T + t1
    body, pbody = np.ones(50, np.int64), np.zeros(50, np.int64)
    w = rng.uniform(0, 0.5, 50)
    rot = np.stack([R, R @ R1])
    trans = np.stack([t, R @ t1 + t])
    out = np.empty((50, 3))
    sk.skin_points(local, body, parent_local, pbody, w, rot, trans, out)
    assert np.allclose(out, local @ (R @ R1).T + R @ t1 + t, atol=1e-12)
    rot[1] = rot[1] @ _rot(rng)  # the child turns: the blend lies between the two poses
    sk.skin_points(local, body, parent_local, pbody, w, rot, trans, out)
    child = local @ rot[1].T + trans[1]
    parent = parent_local @ rot[0].T + trans[0]
    assert np.allclose(out, (1 - w)[:, None] * child + w[:, None] * parent, atol=1e-12)


def test_flattening_moves_inside_points_to_the_nearest_face_and_leaves_the_rest():
    rng = np.random.default_rng(1)
    R, t, half = _rot(rng), rng.normal(size=3), np.array([0.0855, 0.0555, 0.03])
    q = rng.uniform(-1.3, 1.3, size=(2000, 3)) * half
    pts = q @ R.T + t
    out = pts.copy()
    sk.flatten_on_box(out, R, t, half)
    inside = np.all(np.abs(q) < half, axis=1)
    assert inside.sum() > 500 and np.array_equal(out[~inside], pts[~inside])
    qo = (out - t) @ R
    assert np.all(np.max(np.abs(qo) / half, axis=1)[inside] == pytest.approx(1.0, abs=1e-12))
    moved = np.linalg.norm(out - pts, axis=1)[inside]
    room = np.min(half - np.abs(q[inside]), axis=1)
    assert np.allclose(moved, room, atol=1e-12)  # to the nearest face, straight along its normal


def test_a_pulp_is_pushed_fully_at_its_centre_of_pressure_and_not_beyond_its_reach():
    verts = np.array([[0.0, 0, 0], [0.005, 0, 0], [0.02, 0, 0], [0.0, 0, 0]])
    finger, pulp = np.array([0, 0, 0, 1]), np.array([True, True, True, True])
    centre, push, reach = np.zeros((2, 3)), np.array([[0.0, 0, -0.002], [0.0, 0, 0]]), np.array([0.016, 0.016])
    sk.press_pulps(verts, finger, pulp, centre, push, reach)
    assert verts[0, 2] == -0.002 and verts[3, 2] == 0.0 and verts[2, 2] == 0.0
    assert verts[1, 2] == pytest.approx(-0.002 * (1 - (0.005 / 0.016) ** 2) ** 2)


def test_pulp_presses_are_the_contact_in_the_world_pushed_by_the_compression():
    from benchmark.world.skin import PULP_EXPONENT_PER_MM, PULP_STIFFNESS_N_PER_MM, pulp_indentation_m

    rng = np.random.default_rng(2)
    T, K = 4, 5
    q = rng.normal(size=(T, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    pos, point = rng.normal(size=(T, 3)), rng.normal(size=(T, K, 3))
    normal = rng.normal(size=(T, K, 3))
    normal /= np.linalg.norm(normal, axis=2, keepdims=True)
    force = rng.normal(size=(T, K, 3)) * 3
    active = rng.uniform(size=(T, K)) < 0.7
    centre, push = np.empty((T, K, 3)), np.empty((T, K, 3))
    sk.pulp_presses(pos, q, point, normal, force, active, PULP_STIFFNESS_N_PER_MM, PULP_EXPONENT_PER_MM, centre, push)
    R = np.stack([quat_to_rot(x) for x in q])
    assert np.allclose(centre, np.einsum("tij,tkj->tki", R, point) + pos[:, None], atol=1e-12)
    fn = np.einsum("tkj,tkj->tk", force, normal)
    d = np.where(active, pulp_indentation_m(fn), 0.0)
    assert np.allclose(push, d[..., None] * np.einsum("tij,tkj->tki", R, normal), atol=1e-15)
    assert np.any(d > 0) and np.any(active & (fn < 0))  # pulling contacts do not press
