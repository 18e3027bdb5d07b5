"""Motion and grasp features of the internal-force networks (the paper's eq. 10-13).

Per frame i and finger k, with the net contact force and torque of eq. (1),

    F_c = m (a - g),                      tau_c = J_q alpha + omega x (J_q omega),

(the contact wrench about the centre of mass; gravity acts at the centre of mass, so it adds no
torque), the features are

    p1      = ||F_c||                                              (10)
    p2_k    = n_k . F_c / ||F_c||                                  (11)
    p3      = ||tau_c||                                            (12)
    p4_k    = (CP_k x n_k) . tau_c / ||tau_c||                     (13)

with n_k the unit contact normal pointing into the object and CP_k the vector from the centre of
mass C to finger k's contact point. Everything is evaluated in the object frame (its origin is the
centre of mass, so CP_k is the contact point itself); the dot products do not depend on the frame.

Where a magnitude is below ``min_norm`` its direction is undefined: the unit vector is taken as
zero, so p2 (or p4) is 0 for every finger. Fingers not in contact get p2_k = p4_k = 0 and a
False entry in :attr:`Features.active`; the networks see that mask as an input (see `fsv.learn`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fsv._check import as_array, finite, positive, same_length
from fsv.errors import InputError
from fsv.linalg import rows_mt
from fsv.models import ObjectModel
from fsv.types import Contacts, Kinematics

GRAVITY = np.array([0.0, 0.0, -9.81])


@dataclass(frozen=True)
class Features:
    """The features of eq. (10)-(13) per frame, K finger slots (thumb first).

    Attributes:
        p1: ||F_c||, shape (T,), [N].
        p2: n_k . u_Fc per finger, shape (T, K), dimensionless in [-1, 1]; 0 where not active.
        p3: ||tau_c||, shape (T,), [N m].
        p4: (CP_k x n_k) . u_tau per finger, shape (T, K), [m]; 0 where not active.
        active: Finger k touches the object at frame i, shape (T, K).
        net_force: F_c in the object frame, shape (T, 3), [N].
        net_torque: tau_c about the centre of mass in the object frame, shape (T, 3), [N m].
    """

    p1: np.ndarray
    p2: np.ndarray
    p3: np.ndarray
    p4: np.ndarray
    active: np.ndarray
    net_force: np.ndarray
    net_torque: np.ndarray

    def __post_init__(self):
        K = np.shape(self.p2)[-1] if np.ndim(self.p2) == 2 else None
        fields = dict(
            p1=as_array("Features.p1", self.p1, (None,)),
            p2=as_array("Features.p2", self.p2, (None, K)),
            p3=as_array("Features.p3", self.p3, (None,)),
            p4=as_array("Features.p4", self.p4, (None, K)),
            active=as_array("Features.active", self.active, (None, K), bool),
            net_force=as_array("Features.net_force", self.net_force, (None, 3)),
            net_torque=as_array("Features.net_torque", self.net_torque, (None, 3)),
        )
        same_length("Features", **fields)
        for k, v in fields.items():
            object.__setattr__(self, k, v)

    def __len__(self) -> int:
        return self.p1.shape[0]

    @property
    def num_fingers(self) -> int:
        return self.p2.shape[1]

    def matrix(self) -> np.ndarray:
        """The network input: ``[p1, p3, p2_1..p2_K, p4_1..p4_K, active_1..active_K]``, shape (T, 2 + 3K)."""
        return np.concatenate(
            [self.p1[:, None], self.p3[:, None], self.p2, self.p4, self.active.astype(float)], axis=1
        )


def contact_wrench(kinematics: Kinematics, model: ObjectModel, gravity=GRAVITY) -> tuple[np.ndarray, np.ndarray]:
    """The net contact force and torque that explain the motion (eq. 1), in the object frame.

    Args:
        kinematics: Object kinematics in the world frame (T frames).
        model: Known mass and inertia (object frame, about the centre of mass).
        gravity: Gravity in the world frame, shape (3,), [m/s^2].

    Returns:
        ``(F_c, tau_c)``, each shape (T, 3), object frame: F_c = R^T m (a - g) in [N] and
        tau_c = I alpha_b + omega_b x (I omega_b) in [N m], with alpha_b = R^T alpha and
        omega_b = R^T omega (the body-frame form of J_q alpha + omega x J_q omega).
    """
    g = as_array("gravity", gravity, (3,))
    R = kinematics.rot
    F_world = model.mass_kg * (kinematics.acc - g)
    F_c = np.einsum("tji,tj->ti", R, F_world)
    w = np.einsum("tji,tj->ti", R, kinematics.omega)
    al = np.einsum("tji,tj->ti", R, kinematics.alpha)
    I = model.inertia
    tau_c = rows_mt(al, I) + np.cross(w, rows_mt(w, I))
    return F_c, tau_c


def _unit(v: np.ndarray, min_norm: float) -> tuple[np.ndarray, np.ndarray]:
    n = np.linalg.norm(v, axis=-1)
    safe = np.where(n >= min_norm, n, 1.0)
    return n, np.where((n >= min_norm)[:, None], v / safe[:, None], 0.0)


def grasp_features(
    kinematics: Kinematics,
    contacts: Contacts,
    model: ObjectModel,
    *,
    gravity=GRAVITY,
    min_force_n: float = 1e-6,
    min_torque_nm: float = 1e-6,
) -> Features:
    """Computes p1, p2_k, p3, p4_k (eq. 10-13) for every frame.

    Args:
        kinematics: Object kinematics, world frame, T frames.
        contacts: Contacts in the object frame, T frames, K fingers.
        model: The known object model (mass, inertia).
        gravity: Gravity in the world frame, shape (3,), [m/s^2].
        min_force_n: Below this ||F_c|| [N] the force direction is undefined and p2 is 0.
        min_torque_nm: Below this ||tau_c|| [N m] the torque direction is undefined and p4 is 0.

    Returns:
        The :class:`Features` (T frames, K fingers).

    Raises:
        InputError: If the two sequences differ in length or a threshold is not positive.
    """
    if len(kinematics) != len(contacts):
        raise InputError(f"kinematics has {len(kinematics)} frames but contacts has {len(contacts)}")
    for name, v in (("min_force_n", min_force_n), ("min_torque_nm", min_torque_nm)):
        positive(name, v, "a positive number")
    F_c, tau_c = contact_wrench(kinematics, model, gravity)
    finite("net contact force", F_c)
    finite("net contact torque", tau_c)
    p1, u_f = _unit(F_c, min_force_n)
    p3, u_t = _unit(tau_c, min_torque_nm)
    act = contacts.active
    n = np.where(act[..., None], contacts.normal, 0.0)
    P = np.where(act[..., None], contacts.point, 0.0)
    p2 = np.einsum("tkc,tc->tk", n, u_f)
    p4 = np.einsum("tkc,tc->tk", np.cross(P, n), u_t)
    return Features(p1=p1, p2=p2, p3=p3, p4=p4, active=act, net_force=F_c, net_torque=tau_c)
