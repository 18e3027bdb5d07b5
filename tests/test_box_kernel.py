"""The box tracker's compiled kernels against the vectorised NumPy model they replace.

``_reference_box_depth`` below is the NumPy implementation the box tracker used before its hot path
was compiled with numba (``fsv.track.box_kernels._box_depth_kernel``): the prediction of the depth, the
soft coverage, the extended face plane and the depth's Jacobian must agree with it to rounding;
the Jacobian must agree with central differences of the depth away from silhouette corners and face
edges; the fused normal equations (``_box_normal_equations``) must equal ``gram`` and ``tmv`` of
the materialised Jacobian, and a whole Gauss-Newton fit must follow the NumPy one.
"""

import numpy as np
import pytest
from raycast import look_at_calibration

from fsv import ObjectModel
from fsv.linalg import dot, gram, mv, tmv, vm
from fsv.rotation import cross, exp_so3
from fsv.track.box_kernels import _FAR_M, _box_depth, _box_normal_equations, _box_rays
from fsv.track.camera import CameraRays
from fsv.track.object import BoxTracker, predict_box_depth

SIZE = np.array([0.171, 0.111, 0.060])
HALF = SIZE / 2
CALIB = look_at_calibration([0.05, -0.45, 0.40], [0.0, 0.0, 0.05])
FX = float(CALIB.K[0, 0])
RAYS = CameraRays.from_calibration(CALIB)
ALL = np.arange(RAYS.ray.shape[0])


def _reference_box_depth(o, d, bg, pos, rot, half, fx, silhouette_px, jacobian, details=False):
    """The NumPy model (fsv.track.box_kernels._box_depth before numba), verbatim; ``details`` also returns
    per pixel the (face, edge axis, edge sign) that set the depth and the coverage margin, and
    whether the pixel is covered (the branches of the model, for the finite differences)."""
    N = d.shape[0]
    d_col = [np.ascontiguousarray(d[:, k]) for k in range(3)]
    dist = {(a, s): s * dot(rot[:, a], o - pos) - half[a] for a in range(3) for s in (1.0, -1.0)}
    rect_best = np.full(N, -np.inf)
    best_z = np.full(N, np.inf)
    best_m = np.full(N, -np.inf)
    best_face = np.full(N, -1)
    cache = []
    faces = []
    for (a, s), dist_f in dist.items():
        if dist_f <= 0:
            continue
        faces.append(2 * a + (s < 0))
        n = s * rot[:, a]
        nd = mv(d, n)
        with np.errstate(divide="ignore", invalid="ignore"):
            z = np.where(nd < -1e-9, -dist_f / nd, np.inf)
        hit = np.isfinite(z)
        z_hit = np.where(hit, z, 0.0)
        p = np.empty((N, 3))
        for k in range(3):
            np.multiply(z_hit, d_col[k], out=p[:, k])
            np.add(o[k], p[:, k], out=p[:, k])
        q = vm(p - pos, rot)
        rect = np.full(N, np.inf)
        sil = np.full(N, np.inf)
        rect_axis = rect_sign = sil_axis = sil_sign = 0.0
        for b in range(3):
            if b == a:
                continue
            for e in (1.0, -1.0):
                m_edge = half[b] - e * q[:, b]
                closer = m_edge < rect
                rect = np.where(closer, m_edge, rect)
                rect_axis, rect_sign = np.where(closer, float(b), rect_axis), np.where(closer, -e, rect_sign)
                if dist[(b, e)] > 0:
                    continue
                closer = m_edge < sil
                sil = np.where(closer, m_edge, sil)
                sil_axis, sil_sign = np.where(closer, float(b), sil_axis), np.where(closer, -e, sil_sign)
        rect = np.where(hit, rect, -np.inf)
        better = rect > rect_best
        rect_best = np.where(better, rect, rect_best)
        best_z = np.where(better, z, best_z)
        inside = rect >= 0
        best_m = np.where(better, np.where(inside, sil, rect), best_m)
        best_face = np.where(better, len(cache), best_face)
        edge_axis = np.where(inside, sil_axis, rect_axis)
        cache.append((n, nd, p, q, edge_axis.astype(int), np.where(inside, sil_sign, rect_sign)))
    no_face = best_face < 0
    z_box = np.where(no_face, 0.0, best_z)
    bg_eff = np.where(np.isfinite(bg), bg, z_box + _FAR_M)
    tau = silhouette_px * np.maximum(z_box, 1e-3) / fx
    w = np.where(no_face | (z_box >= bg_eff), 0.0, 1.0 / (1.0 + np.exp(-np.clip(best_m / tau, -50, 50))))
    depth = w * z_box + (1 - w) * bg_eff
    plane = np.where(no_face, np.inf, z_box)
    out = (depth, w, plane)
    if jacobian:
        J = np.zeros((N, 6))
        for f, (n, nd, p, q, sil_axis, sil_sign) in enumerate(cache):
            sel = (best_face == f) & (w > 0)
            if not np.any(sel):
                continue
            nds, ps = nd[sel], p[sel]
            lever = ps - pos
            cross_n = cross(lever, n)
            Rb = rot[:, sil_axis[sel]].T
            sgn = sil_sign[sel]
            Rb_d = np.einsum("ij,ij->i", Rb, d[sel])
            cross_Rb = cross(Rb, lever)
            ws, zs, ts = w[sel], z_box[sel], tau[sel]
            gain = (zs - bg_eff[sel]) * ws * (1 - ws) / ts
            mz = np.where(np.isfinite(best_m[sel]), best_m[sel], 0.0) / zs
            Jf = np.empty((nds.shape[0], 6))
            for k in range(3):
                dz_dt = n[k] / nds
                dz_dw = cross_n[:, k] / nds
                dm_dt = sgn * (Rb_d * dz_dt - Rb[:, k])
                dm_dw = sgn * (cross_Rb[:, k] + Rb_d * dz_dw)
                Jf[:, k] = ws * dz_dt + gain * (dm_dt - mz * dz_dt)
                Jf[:, 3 + k] = ws * dz_dw + gain * (dm_dw - mz * dz_dw)
            J[sel] = Jf
        out += (J,)
    if details:
        face_id = np.array(faces + [-1])[best_face]
        axis = np.full(N, -1)
        sign = np.zeros(N)
        for f, c in enumerate(cache):
            axis = np.where(best_face == f, c[4], axis)
            sign = np.where(best_face == f, c[5], sign)
        out += (np.stack([face_id, axis, sign, w > 0], 1),)
    return out


def _reference_normal_equations(o, d, bg, z_obs, pos, rot, half, fx, silhouette_px, sigma, robust_k, occluder_k,
                                flying_k):
    """The NumPy IRLS step of ``BoxTracker.fit`` before numba: materialised J, Cauchy weights;
    flying pixels (between the face's plane and the table or 1 m behind it) weigh nothing."""
    zp, _, plane, J = _reference_box_depth(o, d, bg, pos, rot, half, fx, silhouette_px, True)
    r = z_obs - zp
    occluded = z_obs - np.minimum(zp, plane) < -occluder_k * sigma
    back = np.where(np.isfinite(bg), bg, plane + 1.0)
    m = flying_k * sigma
    flying = (m > 0) & np.isfinite(plane) & (plane + m < z_obs) & (z_obs < back - m)
    w = 1.0 / (1.0 + (r / (robust_k * sigma)) ** 2)
    w = np.where((z_obs > 0) & ~occluded & ~flying, w, 0.0)
    return gram(J, w), tmv(J, w * r), J, w, r


def _poses():
    """Box poses: resting on the table, lifted and tilted, sunk half into the table (the table cuts
    the box), near the image border, and random ones around the table."""
    rng = np.random.default_rng(11)
    out = [(np.array([0.0, 0.0, HALF[2]]), exp_so3([0.0, 0.0, 0.4])),
           (np.array([0.01, 0.02, 0.06]), exp_so3([0.1, 0.2, 0.5])),
           (np.array([0.0, 0.01, 0.0]), exp_so3([0.3, -0.2, 0.4])),
           (np.array([0.2, 0.1, 0.05]), exp_so3([1.0, 0.5, -0.3]))]
    for _ in range(4):
        out.append((np.array([0.0, 0.0, 0.05]) + rng.normal(0.0, [0.04, 0.04, 0.03]), exp_so3(rng.normal(0.0, 1.5, 3))))
    return out


POSES = _poses()


def _table(index, sky_every=0):
    """Table depths of the pixels, with every ``sky_every``-th one made +inf (no table seen there)."""
    bg = RAYS.table_depth[index].copy()
    if sky_every:
        bg[::sky_every] = np.inf
    return bg


def _rays(index, away_every=13):
    """The pixels' rays, every ``away_every``-th one reversed: it meets no visible face's plane."""
    d = RAYS.ray[index].copy()
    d[::away_every] *= -1
    return d


def _assert_rows_close(J, Jref, rtol, floor=None):
    """|J - Jref| <= rtol * (the largest |entry| of Jref's row, at least ``floor``, by default 1e-12 of
    the largest entry overall)."""
    scale = np.maximum(np.abs(Jref).max(1), 1e-12 * np.abs(Jref).max() if floor is None else floor)
    bad = np.abs(J - Jref).max(1) > rtol * scale
    assert not bad.any(), (np.flatnonzero(bad)[:10], (np.abs(J - Jref).max(1) / scale).max())


@pytest.mark.parametrize("k", range(len(POSES)))
@pytest.mark.parametrize("silhouette_px,sky_every", [(0.5, 0), (2.0, 7)])
def test_kernel_equals_the_numpy_model(k, silhouette_px, sky_every):
    pos, rot = POSES[k]
    o, d, bg = RAYS.origin, _rays(ALL), _table(ALL, sky_every)
    ref = _reference_box_depth(o, d, bg, pos, rot, HALF, FX, silhouette_px, True)
    got = _box_depth(o, d, bg, pos, rot, HALF, FX, silhouette_px, True)
    depth, w, plane, J = got
    z_ref, w_ref, plane_ref, J_ref = ref
    np.testing.assert_allclose(depth, z_ref, rtol=1e-10, atol=0)
    np.testing.assert_allclose(w, w_ref, rtol=0, atol=1e-10)
    assert np.array_equal(np.isinf(plane), np.isinf(plane_ref))
    fin = np.isfinite(plane_ref)
    np.testing.assert_allclose(plane[fin], plane_ref[fin], rtol=1e-10, atol=0)
    assert np.array_equal(J_ref == 0, J == 0) or np.abs(J[(J_ref == 0) != (J == 0)]).max() < 1e-10
    _assert_rows_close(J, J_ref, 1e-10)
    # Without the Jacobian the kernel returns the same depth, coverage and plane, bit for bit.
    for a, b in zip(_box_depth(o, d, bg, pos, rot, HALF, FX, silhouette_px, False), got):
        assert np.array_equal(a, b)
    # The cases the test is meant to cover do occur: table, sky, off-box and soft silhouette pixels,
    # box pixels, and (in the sunk pose) box pixels hidden under the table.
    soft = (w_ref > 1e-3) & (w_ref < 1 - 1e-3)
    assert soft.sum() > 100 and (w_ref > 0.99).sum() > 500
    assert np.isinf(plane_ref).sum() > 1000  # no visible face's plane in front (the reversed rays)
    assert (np.isfinite(plane_ref) & (w_ref < 1e-9) & np.isfinite(bg)).sum() > 1000  # the table around the box
    if sky_every:
        assert (np.isinf(bg) & (w_ref < 1e-9)).sum() > 100
    if k == 2:
        assert (np.isfinite(plane_ref) & (plane_ref >= bg) & (w_ref == 0)).sum() > 100


def test_predict_box_depth_keeps_its_signature():
    pos, rot = POSES[1]
    idx = ALL[::5]
    out3 = predict_box_depth(RAYS, idx, pos, rot, HALF, FX)
    out4 = predict_box_depth(RAYS, idx, pos, rot, HALF, FX, 0.5, jacobian=True)
    assert len(out3) == 3 and len(out4) == 4
    assert all(x.shape == (idx.size,) for x in out3) and out4[3].shape == (idx.size, 6)
    for a, b in zip(out3, out4):
        assert np.array_equal(a, b)
    ref = _reference_box_depth(RAYS.origin, RAYS.ray[idx], RAYS.table_depth[idx], pos, rot, HALF, FX, 0.5, True)
    np.testing.assert_allclose(out4[0], ref[0], rtol=1e-10)
    _assert_rows_close(out4[3], ref[3], 1e-10)


@pytest.mark.parametrize("k", range(len(POSES)))
def test_jacobian_matches_central_differences_away_from_edges(k):
    pos, rot = POSES[k]
    silhouette_px = 2.0  # a wider soft silhouette: more pixels where the coverage's terms matter
    # The table everywhere: where no table is seen, the model's background follows the box (_FAR_M
    # behind it) and its Jacobian, by design, treats the background as fixed.
    o, d, bg = RAYS.origin, _rays(ALL), _table(ALL)
    _, w, _, J = _box_depth(o, d, bg, pos, rot, HALF, FX, silhouette_px, True)
    sig = _reference_box_depth(o, d, bg, pos, rot, HALF, FX, silhouette_px, False, details=True)[3]
    h = 1e-6
    Jn = np.zeros_like(J)
    steady = np.ones(w.shape, bool)  # the same face, edge and coverage branch under every perturbation
    for j in range(6):
        dv = np.zeros(6)
        dv[j] = h
        zp = _box_depth(o, d, bg, pos + dv[:3], exp_so3(dv[3:]) @ rot, HALF, FX, silhouette_px, False)[0]
        zm = _box_depth(o, d, bg, pos - dv[:3], exp_so3(-dv[3:]) @ rot, HALF, FX, silhouette_px, False)[0]
        Jn[:, j] = (zp - zm) / (2 * h)
        for s in (10.0, -10.0):
            moved = _reference_box_depth(o, d, bg, pos + s * dv[:3], exp_so3(s * dv[3:]) @ rot, HALF, FX,
                                         silhouette_px, False, details=True)[3]
            steady &= np.all(moved == sig, 1)
    on = steady & (w > 0)
    soft = on & (w > 1e-3) & (w < 1 - 1e-3)
    assert on.sum() > 2000 and soft.sum() > 200
    assert (~steady & (w > 0)).sum() < 0.05 * (w > 0).sum()  # few pixels sit on an edge
    # Central differences of depths ~0.5 m with h = 1e-6 carry ~1e-10 of rounding: rows below 1e-3
    # (pixels hardly covered) are compared to 1e-8 absolute.
    _assert_rows_close(J[on], Jn[on], 1e-5, floor=1e-3)


@pytest.mark.parametrize("flying_k", [0.0, 3.0])
@pytest.mark.parametrize("k", range(len(POSES)))
def test_fused_normal_equations_equal_gram_and_tmv(k, flying_k):
    pos, rot = POSES[k]
    rng = np.random.default_rng(k)
    sigma, robust_k, occluder_k, silhouette_px = 0.01, 1.5, 3.0, 0.5
    idx = ALL[::3]
    o, d, bg = _box_rays(RAYS.origin, RAYS.ray[idx], _table(idx, 11))
    # Observations: the prediction at a slightly different pose plus noise, with invalid pixels
    # (0) and occluders in front.
    z_true = _box_depth(o, d, bg, pos + [0.004, -0.003, 0.002], exp_so3([0.02, -0.01, 0.03]) @ rot, HALF, FX,
                        silhouette_px, False)[0]
    z_obs = z_true + rng.normal(0.0, sigma, idx.size)
    z_obs[rng.random(idx.size) < 0.05] = 0.0
    front = rng.random(idx.size) < 0.05
    z_obs[front] -= 0.1
    z_obs[np.isinf(z_obs)] = 0.0
    # flying pixels: halfway between the box's edge and the table behind it
    _, _, plane_true = _box_depth(o, d, bg, pos, rot, HALF, FX, silhouette_px, False)
    fly = (rng.random(idx.size) < 0.05) & np.isfinite(plane_true) & np.isfinite(bg) & (bg - plane_true > 0.1)
    z_obs[fly] = 0.5 * (plane_true[fly] + bg[fly])
    A_ref, g_ref, J, w, r = _reference_normal_equations(o, d, bg, z_obs, pos, rot, HALF, FX, silhouette_px, sigma,
                                                        robust_k, occluder_k, flying_k)
    if flying_k and fly.any():
        assert (w[fly] == 0).all()
    assert (w[(J != 0).any(1)] == 0).sum() > 50 and (w > 0.5).sum() > 500  # occluded/invalid and inliers
    A, g = _box_normal_equations(o, d, bg, np.ascontiguousarray(z_obs), pos, rot, HALF, FX, silhouette_px, sigma,
                                 robust_k, occluder_k, flying_k)
    assert np.array_equal(A, A.T)
    np.testing.assert_allclose(A, A_ref, rtol=0, atol=1e-10 * np.abs(A_ref).max())
    np.testing.assert_allclose(g, g_ref, rtol=0, atol=1e-10 * np.abs(g_ref).max())
    # ... and the same sums of the kernel's own J and weights, which differ from the model's by rounding.
    _, _, plane, Jk = _box_depth(o, d, bg, pos, rot, HALF, FX, silhouette_px, True)
    zk = _box_depth(o, d, bg, pos, rot, HALF, FX, silhouette_px, False)[0]
    rk = z_obs - zk
    m = flying_k * sigma
    back = np.where(np.isfinite(bg), bg, plane + 1.0)
    flying_k_mask = (m > 0) & np.isfinite(plane) & (plane + m < z_obs) & (z_obs < back - m)
    wk = np.where((z_obs > 0) & ~(z_obs - np.minimum(zk, plane) < -occluder_k * sigma) & ~flying_k_mask,
                  1.0 / (1.0 + (rk / (robust_k * sigma)) ** 2), 0.0)
    np.testing.assert_allclose(A, gram(Jk, wk), rtol=0, atol=1e-12 * np.abs(A_ref).max())
    np.testing.assert_allclose(g, tmv(Jk, wk * rk), rtol=0, atol=1e-12 * np.abs(g_ref).max())


@pytest.mark.parametrize("with_prior", [False, True])
def test_fit_follows_the_numpy_gauss_newton(with_prior, monkeypatch):
    """``BoxTracker.fit`` with the compiled normal equations, and with the NumPy model's (gram and
    tmv) swapped in: the same Gauss-Newton path to 1e-9."""
    import fsv.track.object as box_module
    size = SIZE
    model = ObjectModel(size_m=size, mass_kg=0.4, inertia=ObjectModel.solid_box_inertia(size, 0.4), friction=0.8)
    pos, rot = np.array([0.01, 0.0, 0.05]), exp_so3([0.1, -0.1, 0.6])
    start = (pos + [0.006, -0.004, 0.003], exp_so3([0.02, 0.03, -0.04]) @ rot)
    tracker = BoxTracker(CALIB, model, *start)
    index = tracker.roi(*start, 20)
    rng = np.random.default_rng(2)
    z_obs = _box_depth(RAYS.origin, RAYS.ray[index], RAYS.table_depth[index], pos, rot, HALF, FX, 0.5, False)[0]
    z_obs = z_obs + rng.normal(0.0, 0.005, index.size)
    prior = start if with_prior else None
    p_new, R_new, frac, _ = tracker.fit(z_obs, index, *start, 0.005, prior)
    monkeypatch.setattr(box_module, "_box_normal_equations", lambda *args: _reference_normal_equations(*args)[:2])
    p_ref, R_ref, _, _ = tracker.fit(z_obs, index, *start, 0.005, prior)
    np.testing.assert_allclose(p_new, p_ref, rtol=0, atol=1e-9)
    np.testing.assert_allclose(R_new, R_ref, rtol=0, atol=1e-9)
    assert np.linalg.norm(p_new - pos) < 0.002 and frac > 0.8


def test_flying_pixels_lie_between_the_face_plane_and_the_background():
    from fsv.track.box_kernels import _flying_pixels

    inf = np.inf
    z = np.array([1.20, 1.01, 1.49, 1.50, 1.50, 1.20])
    plane = np.array([1.0, 1.0, 1.0, 1.0, inf, 1.0])
    bg = np.array([1.5, 1.5, 1.5, inf, 1.6, 1.5])  # inf: the ray misses the table (background 1 m behind)
    assert _flying_pixels(z, plane, bg, 0.03).tolist() == [True, False, False, True, False, True]
    assert not _flying_pixels(z, plane, bg, 0.0).any()  # flying_k = 0: kept
