"""The compiled normal equations of the hand fit against the same residuals written with NumPy arrays."""

import numpy as np
import pytest
from raycast import look_at_calibration

from benchmark.world.hand import hand_model
from fsv import ObjectModel
from fsv.linalg import gram, rows_mt, tmv, vm
from fsv.rotation import exp_so3
from fsv.track.articulation import add_row, add_row_span, joint_spans, mirror_upper, point_row
from fsv.track.camera import CameraRays
from fsv.track.capsules import closest_on_capsules, ray_capsules
from fsv.track.hand import HandKinematics, HandState, HandTracker, HandTrackerConfig
from fsv.track.hand_system import box_sdf, box_signed_distance, hand_normal_equations

SIZE = np.array([0.171, 0.111, 0.060])
BOX = ObjectModel(size_m=SIZE, mass_kg=0.4, inertia=ObjectModel.solid_box_inertia(SIZE, 0.4), friction=0.8)
CALIB = look_at_calibration([0.20, -0.48, 0.36], [0.0, 0.0, 0.08])
HAND = hand_model(1.0)


def _reference(tracker: HandTracker, st: HandState, rays, z_obs, free, box_pos, box_rot, sigma):
    """The data, free-space, interpenetration and closure terms as vectorised formulas: rays cast
    and nearest capsules for every point at once, Jacobians as (P, 6 + n) arrays, ``gram``/``tmv``."""
    c, m, kin = tracker.config, tracker.model, tracker.kin
    pose = kin.pose(st)
    a, b = kin.capsules(pose[0], pose[1])
    D = 6 + m.num_joints
    A, g, cost, explained = np.zeros((D, D)), np.zeros(D), 0.0, 0.0
    k = c.cauchy_k * sigma

    def add(J, r, w):
        nonlocal A, g
        A += gram(J, w)
        g -= tmv(J, w * r)

    pts = tracker.rays.origin + z_obs[:, None] * rays
    zh, geom, x, nrm = ray_capsules(tracker.rays.origin, rays, a, b, m.geom_radius)
    r = z_obs - zh
    front = (geom >= 0) & (r > -3 * sigma)
    nd = np.einsum("ni,ni->n", nrm[front], rays[front])
    J = -kin.point_jacobian(x[front], m.geom_segment[geom[front]], nrm[front], pose) / nd[:, None]
    add(J, r[front], 1.0 / (1.0 + (r[front] / k) ** 2))
    cost += 0.5 * k**2 * np.sum(np.log1p((r[front] / k) ** 2))
    explained = np.sum(front & (np.abs(r) < 2 * sigma))
    rest = ~front
    gi, dist, cp, n2 = closest_on_capsules(pts[rest], a, b, m.geom_radius)
    use = dist < c.assign_max_m
    explained += np.sum(use & (np.abs(dist) < 2 * sigma))
    add(-kin.point_jacobian(cp, m.geom_segment[gi], n2, pose), dist, np.where(use, 1.0 / (1.0 + (dist / k) ** 2), 0.0))
    cost += 0.5 * k**2 * np.sum(np.log1p((np.minimum(np.abs(dist), c.assign_max_m) / k) ** 2))
    explained /= z_obs.size
    f_rays, f_z = free
    zh, geom, x, nrm = ray_capsules(tracker.rays.origin, f_rays, a, b, m.geom_radius)
    hit = geom >= 0
    nd = np.einsum("ni,ni->n", nrm[hit], f_rays[hit])
    rf = f_z[hit] - zh[hit]
    add(-kin.point_jacobian(x[hit], m.geom_segment[geom[hit]], nrm[hit], pose) / nd[:, None], rf, 1.0 / (1.0 + (rf / k) ** 2))
    cost += 0.5 * k**2 * np.sum(np.log1p((rf / k) ** 2))
    xs = pose[0][tracker.pen_segment] + np.einsum("pij,pj->pi", pose[1][tracker.pen_segment], tracker.pen_local)
    sd, grad = box_signed_distance(vm(xs - box_pos, box_rot), tracker.half)
    pen = tracker.pen_radius - sd
    hit = pen > 0
    wp = (sigma / c.penetration_m) ** 2
    add(-kin.point_jacobian(xs[hit], tracker.pen_segment[hit], rows_mt(grad[hit], box_rot), pose), pen[hit],
        np.full(int(hit.sum()), wp))
    cost += 0.5 * wp * np.sum(pen[hit] ** 2)
    tips = kin.fingertips(pose[0], pose[1])
    sd_t, grad_t = box_signed_distance(vm(tips - box_pos, box_rot), tracker.half)
    gap = sd_t - m.fingertip_radius
    close = tracker.hidden & (gap > 0) & (gap < c.closure_range_m)
    Jc = kin.point_jacobian(tips[close], m.fingertip_segment[close], rows_mt(grad_t[close], box_rot), pose)
    Jc[:, :6] = 0.0
    Jc[:, 6:] *= tracker.flexion[None, :]
    wc = (sigma / c.closure_m) ** 2
    add(Jc, gap[close], np.full(Jc.shape[0], wc))
    cost += 0.5 * wc * np.sum(gap[close] ** 2)
    return A, g, cost, explained, int(hit.sum()), int(close.sum())


def _scene(seed):
    """A hand near the box (fingers touching and pressing into it) and the depth of a displaced
    copy: candidates both on and off the hand's surface, and scene pixels its capsules cover."""
    rng = np.random.default_rng(seed)
    q = np.mean(HAND.joint_range, 1) + rng.normal(0.0, 0.3, HAND.num_joints)
    st = HandState(np.array([0.0, -0.02, 0.105]) + rng.normal(0.0, 0.01, 3), exp_so3([np.pi, 0.0, 0.0]) @ exp_so3(rng.normal(0, 0.2, 3)),
                   np.clip(q, *HAND.joint_range.T))
    tracker = HandTracker(CALIB, HAND, BOX, st, config=HandTrackerConfig())
    tracker.hidden = rng.random(len(HAND.finger_names)) < 0.6
    kin = tracker.kin
    pos, rot, _, _ = kin.pose(st)
    a, b = kin.capsules(pos, rot)
    rays = CameraRays.from_calibration(CALIB)
    zh, geom, _, _ = ray_capsules(rays.origin, rays.ray, a, b, HAND.geom_radius + 0.01, surface=False)
    near = np.flatnonzero(geom >= 0)
    idx = rng.choice(near, 600, replace=False)
    z_obs = zh[idx] + rng.normal(0.0, 0.006, idx.size) + 0.004
    free_idx = rng.choice(near, 300, replace=False)
    f_z = zh[free_idx] + rng.uniform(-0.01, 0.05, free_idx.size)
    box_pos, box_rot = np.array([0.0, -0.03, 0.08]), exp_so3([0.0, 0.0, 0.1])
    return tracker, st, rays.ray[idx], z_obs, (rays.ray[free_idx], f_z), box_pos, box_rot


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_compiled_normal_equations_equal_the_vectorised_formulas(seed):
    tracker, st, rays, z_obs, free, box_pos, box_rot = _scene(seed)
    sigma = 0.005
    ref_A, ref_g, ref_cost, ref_expl, n_pen, n_close = _reference(tracker, st, rays, z_obs, free, box_pos, box_rot, sigma)
    pos, rot, axis, pivot = tracker.kin.pose(st)
    c = tracker.config
    A, g, cost, expl = hand_normal_equations(
        pos, rot, axis, pivot, tracker.kin.moves, tracker._geom_segment, tracker._geom_fromto, tracker._geom_radius,
        tracker.rays.origin, rays, z_obs, free[0], free[1], sigma, c.cauchy_k, c.assign_max_m, tracker.pen_local,
        tracker.pen_segment, tracker.pen_radius, c.penetration_m, box_pos, box_rot, tracker.half, tracker.hidden,
        tracker._tip_segment, tracker._tip_offset, tracker._tip_radius, tracker.flexion, c.closure_m, c.closure_range_m)
    mirror_upper(A)
    assert n_pen > 0  # every kind of row is exercised
    scale = np.max(np.abs(ref_A))
    np.testing.assert_allclose(A, ref_A, rtol=0, atol=1e-10 * scale)
    np.testing.assert_allclose(g, ref_g, rtol=0, atol=1e-10 * np.max(np.abs(ref_g)))
    assert cost == pytest.approx(ref_cost, rel=1e-12)
    assert expl == pytest.approx(ref_expl, rel=1e-12) and 0 < expl < 1


def test_some_scene_has_closure_rows():
    assert any(_reference(*_scene(s)[:2], *_scene(s)[2:], 0.005)[5] > 0 for s in range(4))


def test_point_rows_equal_gram_of_the_point_jacobian():
    kin = HandKinematics(HAND)
    st = HandState(np.array([0.0, -0.01, 0.13]), exp_so3([np.pi, 0.0, 0.0]), np.mean(HAND.joint_range, 1))
    pose = kin.pose(st)
    rng = np.random.default_rng(2)
    P = 300
    seg = rng.integers(0, len(HAND.segment_names), P)
    x = pose[0][seg] + rng.normal(0.0, 0.02, (P, 3))
    direction, factor, r = rng.normal(size=(P, 3)), rng.normal(size=P), rng.normal(size=P)
    w = np.where(rng.random(P) < 0.2, 0.0, rng.random(P))
    J = factor[:, None] * kin.point_jacobian(x, seg, direction, pose)
    D = 6 + HAND.num_joints
    A, g = np.zeros((D, D)), np.zeros(D)
    row = np.empty(D)
    for p in range(P):
        point_row(row, *x[p], int(seg[p]), *direction[p], factor[p], pose[0][0], kin.moves, pose[2], pose[3])
        add_row(A, g, row, w[p], r[p])
    mirror_upper(A)
    np.testing.assert_allclose(A, gram(J, w), rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(g, -tmv(J, w * r), rtol=1e-12, atol=1e-14)


def test_joint_spans_are_each_segments_hinges():
    kin = HandKinematics(HAND)
    spans = joint_spans(kin.moves)
    for s, (lo, hi) in enumerate(spans):
        hinges = np.flatnonzero(kin.moves[s])
        assert list(range(lo - 6, hi - 6)) == list(hinges), s  # the hand's chains: consecutive hinges
    assert tuple(spans[0]) == (6, 6)  # the palm: no hinge moves it
    scattered = np.zeros((2, 5), bool)
    scattered[0, [1, 3]] = True
    scattered[1, [2]] = True
    assert joint_spans(scattered).tolist() == [[6, 11], [8, 9]]  # not consecutive: every hinge entry


def test_a_spanned_row_adds_the_bits_of_the_whole_row():
    """Point rows of every segment, weights and residuals of every sign, rows with a zero in their
    span, and weights whose products are not finite (inf times a hinge entry that is 0 is NaN, which
    the whole row adds): ``A`` and ``g`` equal :func:`add_row`'s bit for bit, NaN where it has NaN."""
    kin = HandKinematics(HAND)
    st = HandState(np.array([0.0, -0.01, 0.13]), exp_so3([np.pi, 0.0, 0.0]), np.mean(HAND.joint_range, 1))
    pose = kin.pose(st)
    spans = joint_spans(kin.moves)
    rng = np.random.default_rng(5)
    D = 6 + HAND.num_joints
    for trial in range(3):
        A, g, A2, g2 = np.zeros((D, D)), np.zeros(D), np.zeros((D, D)), np.zeros(D)
        row = np.empty(D)
        for p in range(400):
            s = int(rng.integers(0, len(HAND.segment_names)))
            x = pose[0][s] + rng.normal(0.0, 0.02, 3)
            point_row(row, *x, s, *rng.normal(size=3), rng.normal(), pose[0][0], kin.moves, pose[2], pose[3])
            if p % 7 == 0:
                row[int(rng.integers(0, 6))] = 0.0
            w = rng.random() * (np.inf if trial == 2 and p == 200 else 1.0)
            r = rng.normal()
            add_row(A, g, row, w, r)
            add_row_span(A2, g2, row, w, r, spans[s, 0], spans[s, 1])
        assert A.tobytes() == A2.tobytes() and g.tobytes() == g2.tobytes(), trial
    assert np.isnan(A).any() and not np.isnan(A[0, 0])  # the last trial's infinite weight reached A


def test_box_distance_gradient_matches_differences_and_faces():
    rng = np.random.default_rng(0)
    half = SIZE / 2
    pts = rng.uniform(-0.15, 0.15, (400, 3))
    d, grad = box_signed_distance(pts, half)
    inside = np.all(np.abs(pts) < half, axis=1)
    assert inside.any() and (~inside).any()
    assert np.all(d[inside] < 0) and np.all(d[~inside] > 0)
    h = 1e-7
    for p, gp in zip(pts[:50], grad[:50]):
        num = [(box_signed_distance((p + h * e)[None], half)[0][0] - box_signed_distance((p - h * e)[None], half)[0][0]) / (2 * h)
               for e in np.eye(3)]
        np.testing.assert_allclose(num, gp, atol=1e-5)
    out = np.empty(3)
    assert box_sdf(0.0, 0.0, 0.0, half, out) == pytest.approx(-half.min())
    np.testing.assert_array_equal(out, [0.0, 0.0, 1.0])  # the nearest face of the centre: +z (the thinnest side)
