"""benchmark.camera.annotations: projection, visibility, segmentation, BOP pose and contacts in the
camera, on a simulated 1 s lift rendered by the depth renderer (exact depth and labels)."""

import mujoco
import numpy as np
import pytest
from raycast import _box_t, _capsule_t

from benchmark.camera.annotations import (
    OCCLUDED_BY_BOX,
    OCCLUDED_BY_HAND,
    OCCLUDED_BY_TABLE,
    OFF_IMAGE,
    SEGMENTATION_CLASSES,
    VISIBILITY_CODES,
    VISIBLE,
    bop_pose,
    bop_scene_gt,
    camera_from_world,
    contacts_in_camera,
    keypoint_visibility,
    nearest_pixel,
    project,
    segmentation,
    visibility,
)
from benchmark.camera.depth import DepthRenderer, pulp_presses
from benchmark.camera.keypoints import KEYPOINT_FINGER, KEYPOINT_ON_PALM, keypoint_tolerance, keypoints_world
from benchmark.camera.render import hand_skin
from benchmark.camera.scene import world_labels
from benchmark.camera.views import camera_of
from benchmark.errors import BenchmarkError
from benchmark.world.assets import build_world, set_frame
from benchmark.world.scenario import Scenario
from benchmark.world.simulate import simulate
from fsv import Calibration
from fsv.rotation import quat_to_rot


def _rendered(surface, view=0):
    sc = Scenario(task="lift", duration_s=1.0, hand_surface=surface, view=view)
    ep = simulate(sc)
    world = build_world(sc)
    cam = camera_of(view)
    skin = None if surface == "capsules" else hand_skin(world)
    pulps = pulp_presses(ep.truth) if surface == "skin" else None
    renderer = DepthRenderer(world.model, cam, world_labels(world), skin=skin)
    data = mujoco.MjData(world.model)
    T = len(ep.truth.t)
    depth = np.empty((T, cam.height, cam.width), np.float32)
    labels = np.empty(depth.shape, np.uint8)
    poses = []
    for k in range(T):
        set_frame(world, data, ep.truth.box_pos[k], ep.truth.box_quat[k], ep.truth.hand_qpos[k])
        centre, push = (None, None) if pulps is None else (pulps[0][k], pulps[1][k])
        depth[k], labels[k] = renderer.render(data.xpos, data.xmat, centre, push)
        poses.append((data.geom_xpos.copy(), data.geom_xmat.copy()))
    return dict(world=world, truth=ep.truth, calib=cam.calibration(), depth=depth, labels=labels, poses=poses,
                kp=keypoints_world(world, ep.truth), znear=cam.znear)


@pytest.fixture(scope="module")
def capsules():
    return _rendered("capsules")


@pytest.fixture(scope="module")
def skin():
    return _rendered("skin")


def _codes(r):
    uv, z = project(r["kp"], r["calib"])
    return uv, z, np.array([keypoint_visibility(uv[k], z[k], r["depth"][k], r["labels"][k], r["world"].hand)
                            for k in range(len(z))])


def test_project_is_the_pinhole_of_the_calibration():
    K = np.array([[300.0, 0.0, 159.5], [0.0, 280.0, 119.5], [0.0, 0.0, 1.0]])
    T = np.eye(4)
    T[:3, :3] = quat_to_rot(np.array([0.9, 0.1, -0.3, 0.2]))
    T[:3, 3] = [0.1, -0.2, 0.5]
    calib = Calibration(K=K, T_world_cam=T, width=320, height=240)
    pc = np.array([[0.01, -0.02, 0.4], [0.0, 0.0, 1.0], [0.05, 0.03, -0.2]])  # camera frame
    pw = pc @ T[:3, :3].T + T[:3, 3]
    uv, z = project(pw, calib)
    np.testing.assert_allclose(z, pc[:, 2], atol=1e-15)
    np.testing.assert_allclose(uv[0], [300 * 0.01 / 0.4 + 159.5, 280 * -0.02 / 0.4 + 119.5], atol=1e-12)
    np.testing.assert_allclose(uv[1], [159.5, 119.5], atol=1e-12)  # the optical axis: the principal point
    assert np.isnan(uv[2]).all()  # behind the camera
    col, row = nearest_pixel(np.array([[0.49, 0.5], [-0.5, 239.49], [np.nan, 3.0]]))
    assert col.tolist() == [0, 0, -1] and row.tolist() == [1, 239, 3]  # half-way goes up
    with pytest.raises(BenchmarkError, match="no skew"):
        project(pw, Calibration(K=K + [[0, 1, 0], [0, 0, 0], [0, 0, 0]], T_world_cam=T, width=320, height=240))


def _box_corners(half):
    return np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)], float) * half


def _hull_distance(points, pix):
    """Signed distance of pixel centres to the convex hull of points (positive inside), [px]."""
    pts = sorted(map(tuple, points))
    def half(seq):
        out = []
        for p in seq:
            while len(out) >= 2 and ((out[-1][0] - out[-2][0]) * (p[1] - out[-2][1])
                                     - (out[-1][1] - out[-2][1]) * (p[0] - out[-2][0])) <= 0:
                out.pop()
            out.append(p)
        return out
    hull = np.array(half(pts)[:-1] + half(pts[::-1])[:-1])  # counter-clockwise in (u, v)
    dist = np.full(len(pix), np.inf)
    for a, b in zip(hull, np.roll(hull, -1, axis=0)):
        e = b - a
        dist = np.minimum(dist, (e[0] * (pix[:, 1] - a[1]) - e[1] * (pix[:, 0] - a[0])) / np.hypot(*e))
    return dist


@pytest.mark.parametrize("surface", ["capsules", "skin"])
def test_box_corners_project_onto_the_border_of_the_box_label(surface, capsules, skin):
    """The box's image is the convex hull of its 8 projected corners: every pixel whose centre lies more
    than 0.01 px inside it sees the box or the hand in front, every pixel more than 0.01 px outside
    does not see the box (measured: 0 pixels of the 31 frames disagree, even at 0 px, with ~178 box
    pixels a frame within 1 px of the hull's border; the corners shifted by a quarter pixel give 1201)."""
    r = capsules if surface == "capsules" else skin
    truth, calib, world = r["truth"], r["calib"], r["world"]
    corners = _box_corners(world.obj.half_extents)
    v, u = np.mgrid[0 : calib.height, 0 : calib.width]
    pix = np.stack([u.ravel(), v.ravel()], 1).astype(float)
    R = quat_to_rot(truth.box_quat)
    wrong = 0
    for k in range(len(truth.t)):
        uv, z = project(corners @ R[k].T + truth.box_pos[k], calib)
        assert (z > 0).all()
        d = _hull_distance(uv, pix)
        lab = r["labels"][k].ravel()
        wrong += int(((d > 0.01) & (lab != 2) & (lab < 9)).sum() + ((d < -0.01) & (lab == 2)).sum())
    assert wrong == 0


def test_visible_keypoints_carry_their_own_label(capsules, skin):
    """A visible joint's pixel shows its own digit (or the palm, for the wrist and the base joints);
    a visible tip lies on the silhouette, so its own label is within 2 px (measured: within 1 px, on
    the pixel itself for 24 of the 55 visible tips)."""
    for r in (capsules, skin):
        uv, z, codes = _codes(r)
        col, row = nearest_pixel(uv)
        T = len(z)
        n_joint = n_tip = 0
        for k in range(T):
            lab = r["labels"][k]
            for i in np.flatnonzero(codes[k] == VISIBLE):
                own = {10 + KEYPOINT_FINGER[i]} if KEYPOINT_FINGER[i] >= 0 else set()
                own |= {9} if KEYPOINT_ON_PALM[i] else set()
                if i % 4 == 0 and i > 0:  # a tip
                    win = lab[max(row[k, i] - 2, 0) : row[k, i] + 3, max(col[k, i] - 2, 0) : col[k, i] + 3]
                    assert own & set(win.ravel().tolist()), (k, i)
                    n_tip += 1
                else:
                    assert int(lab[row[k, i], col[k, i]]) in own, (k, i, lab[row[k, i], col[k, i]])
                    n_joint += 1
        assert n_joint > 250 and n_tip > 40  # measured 321 and 55 (capsules), 304 and 55 (skin) of 651


def _brute_force_codes(r, k, uv, z):
    """Each keypoint's pixel ray cast against the box, the table and every hand primitive (analytic, in
    the world frame), then the documented rule, one keypoint at a time."""
    world, calib = r["world"], r["calib"]
    m = world.model
    gpos, gmat = r["poses"][k]
    K, T = calib.K, calib.T_world_cam
    col, row = nearest_pixel(uv)
    tol = keypoint_tolerance(world.hand)
    geom_label = world_labels(world)
    out = []
    for i in range(len(z)):
        if not (z[i] > 0 and 0 <= col[i] < calib.width and 0 <= row[i] < calib.height):
            out.append(OFF_IMAGE)
            continue
        d_cam = np.array([(col[i] - K[0, 2]) / K[0, 0], (row[i] - K[1, 2]) / K[1, 1], 1.0])
        o, d = T[:3, 3], (T[:3, :3] @ d_cam)[None]  # the ray's parameter is the depth (d_cam.z = 1)
        hits = []
        tz = -o[2] / d[0, 2]
        p = o + tz * d[0]
        if tz > 0 and abs(p[0]) <= 0.6 and abs(p[1]) <= 0.45:
            hits.append((tz, 1))
        bg = world.box_geom
        hits.append((_box_t(o, d, gpos[bg], gmat[bg].reshape(3, 3), m.geom_size[bg])[0], 2))
        for g in np.flatnonzero(np.asarray(world.geom_segment) >= 0):
            c, ax = gpos[g], gmat[g].reshape(3, 3)[:, 2]
            half = m.geom_size[g, 1] if m.geom_type[g] == mujoco.mjtGeom.mjGEOM_CAPSULE else 0.0
            hits.append((_capsule_t(o, d, c - half * ax, c + half * ax, m.geom_size[g, 0])[0], int(geom_label[g])))
        hits = [h for h in hits if np.isfinite(h[0]) and h[0] >= r["znear"]]
        if not hits:
            out.append(VISIBLE)
            continue
        depth, label = min(hits)
        depth = float(np.float32(depth))
        own = label == 10 + KEYPOINT_FINGER[i] or (label == 9 and KEYPOINT_ON_PALM[i])
        if depth >= z[i] or (own and depth >= z[i] - tol[i]):
            out.append(VISIBLE)
        else:
            out.append({1: OCCLUDED_BY_TABLE, 2: OCCLUDED_BY_BOX}.get(label, OCCLUDED_BY_HAND))
    return np.array(out)


def test_visibility_agrees_with_a_brute_force_ray_cast(capsules):
    """Every 3rd frame: the codes from the rendered image equal those of an analytic ray cast of the
    primitives (measured: all 231 agree; 136 visible, 93 occluded by the hand, 2 by the box)."""
    uv, z, codes = _codes(capsules)
    frames = range(0, len(z), 3)
    brute = np.array([_brute_force_codes(capsules, k, uv[k], z[k]) for k in frames])
    np.testing.assert_array_equal(codes[list(frames)], brute)
    counts = np.bincount(brute.ravel(), minlength=5)
    assert counts[VISIBLE] > 80 and counts[OCCLUDED_BY_HAND] > 80 and counts[OCCLUDED_BY_BOX] > 0


def test_visibility_codes_on_a_synthetic_frame():
    """One keypoint per case against a hand-made 4 x 4 frame."""
    depth = np.full((4, 4), 0.5, np.float32)
    labels = np.full((4, 4), 1, np.uint8)  # table at 0.5 m
    depth[0, 0], labels[0, 0] = 0.30, 2  # box
    depth[0, 1], labels[0, 1] = 0.30, 11  # index finger
    depth[0, 2], labels[0, 2] = 0.30, 9  # palm
    depth[0, 3], labels[0, 3] = 0.0, 0  # nothing
    uv = np.array([[0, 0], [1, 0], [1, 0], [1, 0], [2, 0], [2, 0], [3, 0], [2, 2], [4, 0], [0, -0.6], [1.2, 2.3]])
    z = np.array([0.35, 0.31, 0.31, 0.40, 0.31, 0.31, 0.9, 0.6, 0.3, 0.3, 0.45])
    finger = np.array([1, 1, 2, 1, 1, 1, 1, 1, 1, 1, 1])
    palm = np.array([False, False, False, False, True, False, False, False, False, False, False])
    codes = visibility(uv, z, depth, labels, finger_of_keypoint=finger, tol_m=0.02, palm_is_own=palm)
    assert codes.tolist() == [OCCLUDED_BY_BOX, VISIBLE, OCCLUDED_BY_HAND, OCCLUDED_BY_HAND, VISIBLE, OCCLUDED_BY_HAND,
                              VISIBLE, OCCLUDED_BY_TABLE, OFF_IMAGE, OFF_IMAGE, VISIBLE]
    z_behind = z.copy()
    z_behind[0] = -0.1
    assert visibility(uv, z_behind, depth, labels, finger_of_keypoint=finger, tol_m=0.02, palm_is_own=palm)[0] == OFF_IMAGE
    with pytest.raises(BenchmarkError, match="float32"):
        visibility(uv, z, depth.astype(float), labels, finger_of_keypoint=finger, tol_m=0.02)


def test_segmentation_classes():
    assert SEGMENTATION_CLASSES == {0: "background", 1: "table", 2: "box", 3: "hand"}
    assert sorted(VISIBILITY_CODES) == [VISIBLE, OCCLUDED_BY_BOX, OCCLUDED_BY_HAND, OFF_IMAGE, OCCLUDED_BY_TABLE]
    labels = np.array([[0, 1, 2, 9], [10, 11, 12, 14]], np.uint8)
    assert segmentation(labels).tolist() == [[0, 1, 2, 3], [3, 3, 3, 3]]
    with pytest.raises(BenchmarkError, match="label 5 has no class"):
        segmentation(np.array([5], np.uint8))


def test_segmentation_of_a_rendered_frame(skin):
    seg = segmentation(skin["labels"])
    lab = skin["labels"]
    assert seg.dtype == np.uint8 and seg.shape == lab.shape
    assert np.array_equal(seg == 3, lab >= 9) and np.array_equal(seg == 2, lab == 2)
    assert (seg == 3).any() and (seg == 0).sum() == (lab == 0).sum()


@pytest.mark.parametrize("view", [0, 7])
def test_bop_pose_maps_model_corners_like_the_world_route(view, capsules):
    truth = capsules["truth"]
    calib = camera_of(view).calibration()
    R, t_mm = bop_pose(truth.box_pos, truth.box_quat, calib)
    corners = _box_corners(capsules["world"].obj.half_extents)  # model frame [m]
    via_bop = (np.einsum("tij,cj->tci", R, corners * 1000.0) + t_mm[:, None]) / 1000.0
    world_pts = np.einsum("tij,cj->tci", quat_to_rot(truth.box_quat), corners) + truth.box_pos[:, None]
    via_world = camera_from_world(world_pts, calib)
    assert np.abs(via_bop - via_world).max() < 1e-9  # measured 2.2e-16 m
    np.testing.assert_allclose(np.einsum("tij,tkj->tik", R, R), np.broadcast_to(np.eye(3), R.shape), atol=1e-12)
    assert np.all(np.linalg.det(R) > 0) and 200 < np.linalg.norm(t_mm, axis=-1).min() < 1500  # mm, not m: 486 (view 0), 527 (view 7)
    gt = bop_scene_gt(R, t_mm, obj_id=3)
    assert gt["0"][0]["obj_id"] == 3 and gt["0"][0]["cam_R_m2c"] == R[0].ravel().tolist() and len(gt) == len(R)


def test_contacts_in_camera_match_einsum(capsules):
    truth = capsules["truth"]
    calib = capsules["calib"]
    out = contacts_in_camera(truth, calib)
    Rwo = quat_to_rot(truth.box_quat)
    Rcw = calib.T_world_cam[:3, :3].T
    tw = calib.T_world_cam[:3, 3]
    point = np.einsum("ij,tkj->tki", Rcw, np.einsum("tij,tkj->tki", Rwo, truth.contact_point) + truth.box_pos[:, None] - tw)
    normal = np.einsum("ij,tjl,tkl->tki", Rcw, Rwo, truth.contact_normal)
    force = np.einsum("ij,tjl,tkl->tki", Rcw, Rwo, truth.contact_force)
    assert truth.contact_active.any()
    for key, want in (("point_cam", point), ("normal_cam", normal), ("force_cam", force)):
        assert out[key].shape == truth.contact_point.shape
        assert np.abs(out[key] - want).max() < 1e-12, key  # measured 2.2e-16 (points, m)
    # the force's size and the normal force survive the rotation
    np.testing.assert_allclose(np.linalg.norm(out["force_cam"], axis=-1), np.linalg.norm(truth.contact_force, axis=-1),
                               atol=1e-12)
