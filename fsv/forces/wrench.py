"""Newton–Euler (the paper's eq. 1) and the contact geometry shared by the cone programs.

The net wrench of the contact forces about the centre of mass C that explains the motion is

    F_c = m a - m g,        tau_c = J_q alpha + omega x (J_q omega),        J_q = R I R^T,

with gravity g the only non-contact force (it acts at C, so it adds no torque), I the inertia in
the object frame and R = world_R_object. The cone programs are assembled in the object frame,
where the contact points and normals live, so the wrench is rotated there: R^T F_c, R^T tau_c.
"""

from __future__ import annotations

import numpy as np

from fsv._check import as_array, finite
from fsv.linalg import mm
from fsv.models import ObjectModel
from fsv.types import Kinematics

GRAVITY = np.array([0.0, 0.0, -9.81])


def required_wrench(kinematics: Kinematics, model: ObjectModel, gravity=GRAVITY) -> np.ndarray:
    """The net contact wrench that explains the observed motion (eq. 1), world frame.

    Args:
        kinematics: Object kinematics in the world frame, T frames.
        model: Known mass [kg] and inertia about the centre of mass (object frame) [kg m^2].
        gravity: Gravity in the world frame, shape (3,), [m/s^2].

    Returns:
        ``[F_c, tau_c]`` per frame, shape (T, 6): net contact force in [N] and net contact torque
        about the centre of mass in [N m], both in the world frame.
    """
    g = as_array("gravity", gravity, (3,))
    finite("gravity", g)
    R = kinematics.rot
    J = mm(mm(R, model.inertia), np.swapaxes(R, 1, 2))
    force = model.mass_kg * (kinematics.acc - g)
    Jw = np.einsum("tij,tj->ti", J, kinematics.omega)
    torque = np.einsum("tij,tj->ti", J, kinematics.alpha) + np.cross(kinematics.omega, Jw)
    return np.concatenate([force, torque], axis=1)


def to_object_frame(rot: np.ndarray, wrench_world: np.ndarray) -> np.ndarray:
    """Rotates wrenches (T, 6) from the world frame to the object frame given rot (T, 3, 3)."""
    f = np.einsum("tji,tj->ti", rot, wrench_world[:, :3])
    m = np.einsum("tji,tj->ti", rot, wrench_world[:, 3:])
    return np.concatenate([f, m], axis=1)


def to_world_frame(rot: np.ndarray, wrench_object: np.ndarray) -> np.ndarray:
    """Rotates wrenches (T, 6) from the object frame to the world frame given rot (T, 3, 3)."""
    f = np.einsum("tij,tj->ti", rot, wrench_object[:, :3])
    m = np.einsum("tij,tj->ti", rot, wrench_object[:, 3:])
    return np.concatenate([f, m], axis=1)


def tangent_basis(normal: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit tangents t_x, t_y with (n, t_x, t_y) right-handed and orthonormal (eq. 2).

    Args:
        normal: Unit normals, shape (..., 3).

    Returns:
        ``(t_x, t_y)``, each shape (..., 3). t_x is n crossed with the coordinate axis least
        aligned with n, so the basis is a deterministic function of n.
    """
    n = np.asarray(normal, dtype=float)
    axis = np.eye(3)[np.argmin(np.abs(n), axis=-1)]
    tx = np.cross(n, axis)
    tx /= np.maximum(np.linalg.norm(tx, axis=-1, keepdims=True), 1e-300)
    ty = np.cross(n, tx)
    return tx, ty
