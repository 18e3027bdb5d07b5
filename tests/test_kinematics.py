"""fsv.kinematics: stencils, SO(3) helpers and pose differentiation on analytic signals."""

import math
import warnings

import numpy as np
import pytest

from fsv import InputError, Poses
from fsv.kinematics import (
    AlgebraicConfig,
    CentralConfig,
    GaussianConfig,
    algebraic_weights,
    differentiate_poses,
    kinematics_in_frame,
    moments,
    sampling_period,
    so3,
)
from fsv.rotation import quat_to_rot

DT = 1 / 30
CONFIGS = [
    AlgebraicConfig(),
    AlgebraicConfig(window_frames=15, kappa=2, mu=2),
    AlgebraicConfig(window_frames=10, kappa=0, mu=2),
    AlgebraicConfig(window_frames=11, kappa=0.5, mu=1.5, causal=True),
    AlgebraicConfig(window_frames=9, kappa=1, mu=1, causal=True),
    CentralConfig(),
    CentralConfig(step_frames=2, causal=True),
    GaussianConfig(),
    GaussianConfig(sigma_frames=0.7, causal=True),
]


def _ids(cfg):
    return f"{cfg.name}-{cfg.describe()}-{'causal' if cfg.causal else 'offline'}"


def _rotating_poses(T=90, omega_body=(1.0, -2.0, 3.0), pos=None):
    t = np.arange(T) * DT
    q0 = so3.quat_exp(np.array([0.3, 0.2, -1.0]))
    q = so3.quat_mul(q0, so3.quat_exp(t[:, None] * np.asarray(omega_body)))
    if pos is None:
        pos = np.zeros((T, 3))
    return Poses(t=t, pos=pos, rot=quat_to_rot(q))


# --- stencils ---------------------------------------------------------------------------------


@pytest.mark.parametrize("cfg", CONFIGS, ids=_ids)
@pytest.mark.parametrize("order", [0, 1, 2])
def test_stencil_is_exact_on_polynomials_at_its_delay(cfg, order):
    st = cfg.stencil(order, DT)
    assert st.exact_degree == order + 1
    L = st.weights.size
    t_k = 2.0 + (L - 1) * DT  # newest sample of the window
    times = t_k - np.arange(L) * DT
    rng = np.random.default_rng(order)
    for degree in range(st.exact_degree + 1):
        c = rng.normal(size=degree + 1)
        x = np.polynomial.Polynomial(c)
        est = np.dot(st.weights, x(times))
        true = x.deriv(order)(t_k - st.delay_s)
        assert est == pytest.approx(true, abs=1e-9 * max(1.0, abs(true)))


@pytest.mark.parametrize("cfg", CONFIGS, ids=_ids)
def test_stencil_is_not_exact_one_degree_higher(cfg):
    st = cfg.stencil(1, DT)
    L = st.weights.size
    times = -np.arange(L) * DT
    x = np.polynomial.Polynomial.basis(st.exact_degree + 1)
    assert abs(np.dot(st.weights, x(times)) - x.deriv(1)(-st.delay_s)) > 1e-9


@pytest.mark.parametrize("kappa,mu,L", [(0, 0, 9), (1, 1, 9), (0, 2, 10), (1, 3, 12), (2.5, 0.5, 14)])
@pytest.mark.parametrize("order", [1, 2])
def test_algebraic_derivative_weights_sum_to_zero(kappa, mu, L, order):
    w = algebraic_weights(order, L, kappa, mu)
    m = moments(w, order)
    assert abs(m[0]) < 1e-12
    assert m[order] == pytest.approx(1.0, abs=1e-12)


def test_centred_algebraic_delay_is_half_a_window():
    for L in (5, 9, 16):
        st = AlgebraicConfig(window_frames=L, kappa=2, mu=2).stencil(2, DT)
        assert st.delay_s == pytest.approx((L - 1) / 2 * DT, abs=1e-12)


def test_asymmetric_delay_is_the_discrete_mboup_point():
    # Continuous minimal estimator: exact at (kappa+n+1)/(kappa+mu+2n+2) T; the discrete one is
    # within half a frame of that minus half a frame (hold over each sample interval).
    kappa, mu, L, n = 1.0, 3.0, 30, 1
    st = AlgebraicConfig(window_frames=L, kappa=kappa, mu=mu).stencil(n, DT)
    continuous = (kappa + n + 1) / (kappa + mu + 2 * n + 2) * L * DT
    assert st.delay_s == pytest.approx(continuous - DT / 2, abs=0.01 * DT)


def test_exact_moments_fixes_the_asymmetric_acceleration_ramp_leak():
    raw = algebraic_weights(2, 10, 0.0, 2.0, exact_moments=False)
    fixed = algebraic_weights(2, 10, 0.0, 2.0, exact_moments=True)
    assert abs(moments(raw, 2)[1]) / DT > 0.5  # at 30 fps a 1 m/s ramp reads as 0.52 m/s^2
    assert abs(moments(fixed, 2)[1]) < 1e-12
    cfg = AlgebraicConfig(window_frames=10, kappa=0, mu=2, exact_moments=False)
    assert cfg.stencil(2, DT).exact_degree == 0


def test_algebraic_matches_algdiff_analytic_weights():
    pytest.importorskip("AlgDiff")
    from AlgDiff import AlgebraicDifferentiator

    for kappa, mu, L in [(0, 0, 9), (1, 1, 9), (0, 2, 10), (1, 3, 12), (0.5, 1.5, 11), (-0.5, -0.5, 7)]:
        for n in (0, 1, 2) if min(kappa, mu) >= 0 else (1, 2):  # AlgDiff's order 0 gives NaN for kappa < 0
            T = L * DT
            while int(T / DT) != L:  # AlgDiff takes int(T / ts) samples
                T = np.nextafter(T, np.inf)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                ad = AlgebraicDifferentiator(ts=DT, alpha=kappa + n, beta=mu + n, N=0, T=T, display=False)
                theirs = ad.discretize(n, "analytic")[n]["analytic"]
            ours = AlgebraicConfig(window_frames=L, kappa=kappa, mu=mu, exact_moments=False).stencil(n, DT).weights
            np.testing.assert_allclose(ours * DT**n, theirs * DT**n, rtol=0, atol=1e-9)


def test_offline_taps_are_centred_and_causal_taps_look_back():
    st = AlgebraicConfig(window_frames=9).stencil(1, DT)
    off, c = st.taps(0.0)
    assert off.min() == -4 and off.max() == 4
    off, c = st.taps(st.delay_s)
    assert off.max() == 0 and off.min() == -8
    st = AlgebraicConfig(window_frames=10, kappa=0, mu=2).stencil(1, DT)
    off, c = st.taps(0.0)  # fractional delay: two blended copies, one more tap
    assert off.size == 11 and c.sum() == pytest.approx(0, abs=1e-12)


def test_gaussian_kernel_is_normalised_and_truncated():
    g = GaussianConfig(sigma_frames=1.5, truncate=3).kernel()
    assert g.size == 2 * math.ceil(4.5) + 1
    assert g.sum() == pytest.approx(1.0)
    assert g[len(g) // 2] == g.max()


@pytest.mark.parametrize(
    "make,match",
    [
        (lambda: AlgebraicConfig(window_frames=2), "window_frames"),
        (lambda: AlgebraicConfig(kappa=-1), "kappa"),
        (lambda: AlgebraicConfig(mu=float("nan")), "mu"),
        (lambda: AlgebraicConfig(causal="yes"), "causal"),
        (lambda: CentralConfig(step_frames=0), "step_frames"),
        (lambda: GaussianConfig(sigma_frames=0), "sigma_frames"),
        (lambda: AlgebraicConfig().stencil(3, DT), "order"),
        (lambda: AlgebraicConfig().stencil(1, -1.0), "dt"),
    ],
)
def test_bad_parameters_name_the_value(make, match):
    with pytest.raises(InputError, match=match):
        make()


# --- SO(3) -----------------------------------------------------------------------------------


def test_quaternion_round_trip_and_log_exp():
    rng = np.random.default_rng(0)
    q = rng.normal(size=(200, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    q[q[:, 0] < 0] *= -1
    q[0] = [0, 1, 0, 0]  # a half turn (Shepperd's x branch)
    q[1] = [1, 0, 0, 0]
    R = quat_to_rot(q)
    back = so3.quat_from_matrix(R)
    assert np.allclose(np.abs(np.sum(back * q, axis=1)), 1, atol=1e-12)
    phi = so3.quat_log(q)
    assert np.all(np.linalg.norm(phi, axis=1) <= np.pi + 1e-12)
    np.testing.assert_allclose(quat_to_rot(so3.quat_exp(phi)), R, atol=1e-12)
    tiny = np.array([1e-10, -2e-10, 3e-10])
    np.testing.assert_allclose(so3.quat_log(so3.quat_exp(tiny)), tiny, rtol=1e-12)


def test_quaternion_product_composes_rotations():
    rng = np.random.default_rng(1)
    p, q = so3.quat_exp(rng.normal(size=(5, 3))), so3.quat_exp(rng.normal(size=(5, 3)))
    np.testing.assert_allclose(
        quat_to_rot(so3.quat_mul(p, q)), quat_to_rot(p) @ quat_to_rot(q), atol=1e-12
    )


# --- differentiate_poses ---------------------------------------------------------------------


@pytest.mark.parametrize("cfg", CONFIGS, ids=_ids)
def test_constant_angular_velocity_is_returned_exactly(cfg):
    w_body = np.array([1.0, -2.0, 3.0])
    poses = _rotating_poses(omega_body=w_body)
    kin = differentiate_poses(poses, cfg)
    v = kin.valid
    w_world = np.einsum("tij,j->ti", kin.rot, w_body)  # constant too
    np.testing.assert_allclose(kin.omega[v], w_world[v], atol=1e-9)
    np.testing.assert_allclose(kin.alpha[v], 0, atol=1e-9)
    _, gyro = kin.imu(np.array([0, 0, -9.81]))
    np.testing.assert_allclose(gyro[v], np.broadcast_to(w_body, gyro[v].shape), atol=1e-9)


@pytest.mark.parametrize("cfg", CONFIGS, ids=_ids)
def test_constant_acceleration_translation(cfg):
    T = 60
    t = np.arange(T) * DT
    a, v0, p0 = np.array([0.3, -1.2, 2.0]), np.array([0.1, 0.2, -0.3]), np.array([0.5, 0.0, 0.1])
    pos = p0 + v0 * t[:, None] + 0.5 * a * t[:, None] ** 2
    kin = differentiate_poses(Poses(t=t, pos=pos, rot=np.tile(np.eye(3), (T, 1, 1))), cfg)
    v = kin.valid
    t_est = t - kin.delay_s
    np.testing.assert_allclose(kin.acc[v], np.broadcast_to(a, (v.sum(), 3)), atol=1e-9)
    np.testing.assert_allclose(kin.vel[v], v0 + a * t_est[v, None], atol=1e-9)
    np.testing.assert_allclose(kin.omega, 0, atol=1e-12)
    acc_imu, _ = kin.imu(np.array([0, 0, -9.81]))
    np.testing.assert_allclose(acc_imu[v], np.broadcast_to(a + [0, 0, 9.81], (v.sum(), 3)), atol=1e-9)


def test_varying_angular_velocity_matches_the_analytic_body_rates():
    # R(t) = Rz(a(t)) Rx(b(t)): body rate (b', a' sin b, a' cos b), differentiated by hand.
    # At 300 Hz the smoothing bias of a 5-frame window is ~1e-4; a frame or SO(3) mistake is O(1).
    t = np.arange(300) / 300
    a, da, dda = np.sin(2 * t) + t**2, 2 * np.cos(2 * t) + 2 * t, -4 * np.sin(2 * t) + 2
    b, db, ddb = 0.5 * np.cos(3 * t), -1.5 * np.sin(3 * t), -4.5 * np.cos(3 * t)
    rot = quat_to_rot(so3.quat_mul(so3.quat_exp(a[:, None] * [0, 0, 1]), so3.quat_exp(b[:, None] * [1, 0, 0])))
    w_body = np.stack([db, da * np.sin(b), da * np.cos(b)], 1)
    w_dot = np.stack([ddb, dda * np.sin(b) + da * np.cos(b) * db, dda * np.cos(b) - da * np.sin(b) * db], 1)
    kin = differentiate_poses(Poses(t=t, pos=np.zeros((300, 3)), rot=rot), AlgebraicConfig(window_frames=5))
    _, gyro = kin.imu(np.zeros(3))
    v = kin.valid
    assert np.max(np.abs(gyro[v] - w_body[v])) < 1e-3
    alpha_body = np.einsum("tji,tj->ti", kin.rot, kin.alpha)
    assert np.max(np.abs(alpha_body[v] - w_dot[v])) < 1e-2


def test_causal_mode_reports_its_delay_and_uses_only_the_past():
    cfg = AlgebraicConfig(window_frames=9, causal=True)
    T = 40
    t = np.arange(T) * DT
    pos = np.stack([np.sin(3 * t), t**3, np.cos(t)], 1)
    kin = differentiate_poses(Poses(t=t, pos=pos, rot=np.tile(np.eye(3), (T, 1, 1))), cfg)
    assert kin.delay_s == pytest.approx(4 * DT)
    assert not kin.valid[:8].any() and kin.valid[8:].all()
    changed = pos.copy()
    changed[25:] += 1.0  # the future of frame 24
    kin2 = differentiate_poses(Poses(t=t, pos=changed, rot=np.tile(np.eye(3), (T, 1, 1))), cfg)
    np.testing.assert_array_equal(kin.acc[:25], kin2.acc[:25])
    assert not np.allclose(kin.acc[25:33], kin2.acc[25:33])


def test_filtered_pose_is_what_the_method_smooths():
    rng = np.random.default_rng(4)
    truth = _rotating_poses(T=120, omega_body=(0.5, 0.2, -0.3))
    noisy_q = so3.quat_mul(so3.quat_from_matrix(truth.rot), so3.quat_exp(rng.normal(scale=0.05, size=(120, 3))))
    noisy = Poses(t=truth.t, pos=rng.normal(scale=0.002, size=(120, 3)), rot=quat_to_rot(noisy_q))

    def rot_err(kin):
        rel = np.einsum("tji,tjk->tik", truth.rot, kin.rot)[kin.valid]
        return np.sqrt(np.mean(np.sum(so3.quat_log(so3.quat_from_matrix(rel)) ** 2, axis=1)))

    raw = differentiate_poses(noisy, CentralConfig())
    np.testing.assert_allclose(raw.rot[raw.valid], noisy.rot[raw.valid], atol=1e-12)
    np.testing.assert_array_equal(raw.pos[raw.valid], noisy.pos[raw.valid])
    for cfg in (AlgebraicConfig(window_frames=15), GaussianConfig(sigma_frames=2)):
        kin = differentiate_poses(noisy, cfg)
        assert rot_err(kin) < 0.5 * rot_err(raw)
        assert np.std(kin.pos[kin.valid]) < 0.5 * np.std(noisy.pos)


def test_invalid_frames_hold_the_nearest_estimate():
    poses = _rotating_poses(T=30)
    kin = differentiate_poses(poses, AlgebraicConfig(window_frames=9))
    assert kin.valid.sum() == 30 - 8
    assert np.array_equal(kin.omega[0], kin.omega[4]) and np.array_equal(kin.omega[-1], kin.omega[-5])


def test_rejects_short_or_uneven_sequences():
    poses = _rotating_poses(T=6)
    with pytest.raises(InputError, match="needs at least 9 frames, got 6"):
        differentiate_poses(poses, AlgebraicConfig(window_frames=9))
    with pytest.raises(InputError, match="evenly spaced"):
        sampling_period(np.array([0, 0.1, 0.3]))
    with pytest.raises(InputError, match="config"):
        differentiate_poses(_rotating_poses(T=20), "algebraic")


def test_relative_log_matches_the_composed_operations():
    rng = np.random.default_rng(7)
    q = so3.quat_exp(rng.normal(scale=2.0, size=(50, 3)))
    q[::3] *= -1  # either sign of a quaternion
    ref = so3.quat_exp(rng.normal(size=(20, 3)))
    index = rng.integers(0, 50, size=(20, 6))
    index[0, 0] = 0
    ref[0] = q[0]  # identity relative rotation (the small-angle branch)
    slow = so3.quat_log(so3.quat_mul(so3.quat_conj(ref)[:, None, :], q[index]))
    np.testing.assert_allclose(np.moveaxis(so3.relative_log(ref, q, index), 0, -1), slow, atol=1e-12)


def test_kinematics_in_a_fixed_frame_are_those_of_the_moved_poses():
    t = np.arange(60) * DT
    poses = _rotating_poses(60, pos=np.stack([0.1 * t**2, np.sin(t), 0.02 * t], axis=1))
    M = np.eye(4)
    M[:3, :3] = quat_to_rot(so3.quat_exp(np.array([0.01, -0.008, 0.3])))
    M[:3, 3] = [0.01, -0.02, -0.004]
    moved = Poses(t=poses.t, pos=poses.pos @ M[:3, :3].T + M[:3, 3], rot=M[:3, :3] @ poses.rot)
    cfg = AlgebraicConfig(window_frames=7, kappa=0.5, mu=0.5)
    want = differentiate_poses(moved, cfg)
    got = kinematics_in_frame(differentiate_poses(poses, cfg), M)
    ok = want.valid & got.valid
    assert ok.sum() > 40
    for name in ("pos", "rot", "vel", "acc", "omega", "alpha"):
        assert np.allclose(getattr(got, name)[ok], getattr(want, name)[ok], atol=1e-9), name
    with pytest.raises(InputError, match="frame_from_world"):
        kinematics_in_frame(got, np.eye(3))
