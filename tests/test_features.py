import numpy as np
import pytest

from fsv import Contacts, InputError, Kinematics, ObjectModel
from fsv.features import contact_wrench, grasp_features

RZ90 = np.array([[0.0, -1, 0], [1, 0, 0], [0, 0, 1]])  # object x along world y


def _kin(R, acc, omega, alpha, T=1):
    return Kinematics(
        t=np.arange(T) / 30, pos=np.zeros((T, 3)), rot=np.tile(R, (T, 1, 1)), vel=np.zeros((T, 3)),
        acc=np.tile(acc, (T, 1)), omega=np.tile(omega, (T, 1)), alpha=np.tile(alpha, (T, 1)),
        valid=np.ones(T, bool),
    )


def _model(mass=0.5):
    return ObjectModel(size_m=[0.171, 0.111, 0.06], mass_kg=mass, inertia=np.diag([1e-3, 2e-3, 3e-3]), friction=0.8)


def _contacts(T=1):
    point = np.array([[0.0, -0.0555, 0.0], [0.0855, 0.02, 0.01], [0.01, 0.0555, 0.0]])
    normal = np.array([[0.0, 1, 0], [-1.0, 0, 0], [0.0, -1, 0]])
    return Contacts(
        ("thumb", "index", "middle"), active=np.tile([True, True, False], (T, 1)),
        sliding=np.zeros((T, 3), bool), point=np.tile(point, (T, 1, 1)), normal=np.tile(normal, (T, 1, 1)),
        slide_dir=np.zeros((T, 3, 3)),
    )


def test_features_on_a_constructed_frame():
    # a = (1, 0, 0), g = (0, 0, -9.81), m = 0.5: F_world = (0.5, 0, 4.905); object frame (R^T) = (0, -0.5, 4.905).
    # omega_world = (0, 1, 2) -> omega_b = (1, 0, 2); I omega_b = (1e-3, 0, 6e-3); omega_b x I omega_b = (0, -4e-3, 0).
    # alpha_world = (1, 0, 0) -> alpha_b = (0, -1, 0); I alpha_b = (0, -2e-3, 0). tau_c = (0, -6e-3, 0).
    f = grasp_features(_kin(RZ90, [1.0, 0, 0], [0.0, 1, 2], [1.0, 0, 0]), _contacts(), _model())
    p1 = np.sqrt(0.5**2 + 4.905**2)
    np.testing.assert_allclose(f.net_force[0], [0, -0.5, 4.905], atol=1e-12)
    np.testing.assert_allclose(f.net_torque[0], [0, -6e-3, 0], atol=1e-15)
    assert f.p1[0] == pytest.approx(p1)
    assert f.p3[0] == pytest.approx(6e-3)
    # thumb: n = (0, 1, 0) -> n.F = -0.5; index: n = (-1, 0, 0) -> 0; middle inactive -> 0.
    np.testing.assert_allclose(f.p2[0], [-0.5 / p1, 0.0, 0.0], atol=1e-12)
    # thumb: P x n = (0, 0, 0) (P parallel to n); index: P x n = (0, -0.01, 0.02), u_tau = (0, -1, 0) -> 0.01.
    np.testing.assert_allclose(f.p4[0], [0.0, 0.01, 0.0], atol=1e-12)
    np.testing.assert_array_equal(f.active[0], [True, True, False])
    np.testing.assert_allclose(f.matrix()[0], [p1, 6e-3, -0.5 / p1, 0, 0, 0, 0.01, 0, 1, 1, 0], atol=1e-12)


def test_torque_matches_world_frame_euler_equation():
    rng = np.random.default_rng(3)
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    R = q * np.sign(np.linalg.det(q))
    A = rng.normal(size=(3, 3))
    model = ObjectModel(size_m=[0.1, 0.1, 0.1], mass_kg=0.3, inertia=A @ A.T + np.eye(3) * 1e-3, friction=0.5)
    w, al = rng.normal(size=3), rng.normal(size=3)
    _, tau_b = contact_wrench(_kin(R, np.zeros(3), w, al), model)
    J = R @ model.inertia @ R.T  # J_q: inertia with orientation q, world frame
    tau_w = J @ al + np.cross(w, J @ w)
    np.testing.assert_allclose(R @ tau_b[0], tau_w, rtol=1e-12, atol=1e-14)


def test_undefined_directions_give_zero_features():
    # free fall: a = g -> F_c = 0; no rotation -> tau_c = 0.
    f = grasp_features(_kin(np.eye(3), [0, 0, -9.81], np.zeros(3), np.zeros(3), T=2), _contacts(2), _model())
    np.testing.assert_allclose(f.p1, 0, atol=1e-12)
    np.testing.assert_array_equal(f.p2, 0)
    np.testing.assert_array_equal(f.p4, 0)


def test_length_mismatch_is_rejected():
    with pytest.raises(InputError, match="3 frames but contacts has 1"):
        grasp_features(_kin(np.eye(3), np.zeros(3), np.zeros(3), np.zeros(3), T=3), _contacts(1), _model())
    with pytest.raises(InputError, match="min_force_n"):
        grasp_features(_kin(np.eye(3), np.zeros(3), np.zeros(3), np.zeros(3)), _contacts(), _model(), min_force_n=0)
