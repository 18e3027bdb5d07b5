"""Newton–Euler (eq. 1) checked against finite differences of momentum; the tangent basis."""

import numpy as np
import pytest
from forces_oracle import box_model, random_rotation
from hypothesis import given, settings
from hypothesis import strategies as st

from fsv import InputError, Kinematics
from fsv.forces import GRAVITY, required_wrench, tangent_basis, to_object_frame, to_world_frame


def _expm(w):
    th = np.linalg.norm(w)
    K = np.array([[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]])
    if th < 1e-12:
        return np.eye(3) + K
    return np.eye(3) + np.sin(th) / th * K + (1 - np.cos(th)) / th**2 * K @ K


def test_torque_is_the_rate_of_angular_momentum_and_force_the_rate_of_momentum():
    """Integrate a tumbling box; tau_c = d/dt (J_q omega), F_c = d/dt (m v) - m g, by central differences."""
    model = box_model(mass_kg=0.7)
    dt = 1e-5
    t = np.arange(-2, 3) * dt + 0.3
    omega = np.stack([[np.sin(3 * s), np.cos(2 * s), s**2] for s in t])  # world frame, rad/s
    alpha = np.stack([[3 * np.cos(3 * s), -2 * np.sin(2 * s), 2 * s] for s in t])
    vel = np.stack([[np.cos(s), s**3, np.sin(5 * s)] for s in t])
    acc = np.stack([[-np.sin(s), 3 * s**2, 5 * np.cos(5 * s)] for s in t])
    R0 = random_rotation(np.random.default_rng(0))
    # Orientation along the trajectory: R(t+dt) = exp(omega dt) R(t) (midpoint rule, accurate to dt^3).
    rot = [R0]
    for i in range(1, len(t)):
        rot.append(_expm(0.5 * (omega[i] + omega[i - 1]) * dt) @ rot[-1])
    rot = np.stack(rot)
    kin = Kinematics(t=t, pos=np.zeros((5, 3)), rot=rot, vel=vel, acc=acc, omega=omega, alpha=alpha,
                     valid=np.ones(5, bool))
    w = required_wrench(kin, model)
    L = np.einsum("tij,tj->ti", rot @ model.inertia @ np.swapaxes(rot, 1, 2), omega)
    dL = (L[3] - L[1]) / (2 * dt)
    dp = model.mass_kg * (vel[3] - vel[1]) / (2 * dt)
    assert np.allclose(w[2, 3:], dL, rtol=1e-5, atol=1e-7)
    assert np.allclose(w[2, :3], dp - model.mass_kg * GRAVITY, rtol=1e-6, atol=1e-6)


def test_a_box_at_rest_needs_its_weight_and_no_torque():
    model = box_model(mass_kg=0.5)
    R = random_rotation(np.random.default_rng(3))[None]
    z = np.zeros((1, 3))
    kin = Kinematics(t=[0.0], pos=z, rot=R, vel=z, acc=z, omega=z, alpha=z, valid=[True])
    w = required_wrench(kin, model)
    assert np.allclose(w[0], [0, 0, 0.5 * 9.81, 0, 0, 0])
    w_obj = to_object_frame(R, w)
    assert np.allclose(w_obj[0, :3], R[0].T @ [0, 0, 0.5 * 9.81])
    assert np.allclose(to_world_frame(R, w_obj), w)
    with pytest.raises(InputError, match="gravity"):
        required_wrench(kin, model, gravity=[0, -9.81])


@settings(max_examples=50, derandomize=True, deadline=None)
@given(st.lists(st.floats(-1, 1), min_size=3, max_size=3).filter(lambda v: np.linalg.norm(v) > 1e-3))
def test_tangent_basis_is_right_handed_and_orthonormal(v):
    n = np.asarray(v) / np.linalg.norm(v)
    tx, ty = tangent_basis(n)
    B = np.stack([n, tx, ty], axis=1)
    assert np.allclose(B.T @ B, np.eye(3), atol=1e-12)
    assert np.linalg.det(B) == pytest.approx(1.0)
