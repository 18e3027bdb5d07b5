"""What the end-to-end force network sees of a frame: :func:`direct_inputs`, all in the object frame.

Everything comes from what the method has after tracking: the box's differentiated kinematics (in
the frame the force stage receives, the tracked table at z = 0 with gravity along -z), the contacts
the tracker found, and the lab's knowledge of the box (its mass, size and inertia). Nothing of the
person and nothing of the truth.

Per frame, in this order (``input_names`` names them):

* ``wrench_{Fx..Tz}``: the wrench the motion requires of the contacts (eq. 1) in the object frame,
  m R^T (a - g) [N] and I alpha_o + omega_o x I omega_o [N m], about the centre of mass;
* ``spec_{x,y,z}``: the specific force R^T (a - g) [m/s^2] (what an accelerometer in the box reads);
* ``vel_{x,y,z}``, ``omega_{x,y,z}``, ``alpha_{x,y,z}``: R^T v [m/s], R^T omega [rad/s], R^T alpha
  [rad/s^2];
* ``up_{x,y,z}``: the table's normal (world +z) in the object frame, R^T e_z (the box's tilt);
* ``mass``: [kg]; ``half_{x,y,z}``: the box's half extents [m];
* ``height``: the height of the box's lowest corner above the table, [m] (z = 0 of the frame);
* with a window of W frames, ``spec_*``, ``omega_*`` and ``alpha_*`` again at each offset
  -W..-1, 1..W (``spec_x@-1``, ...): a neighbour outside the episode or without kinematics is
  replaced by the frame itself;
* per finger k: ``active_k`` (0 or 1), ``point_{x,y,z}_k`` [m] and ``normal_{x,y,z}_k``, the contact
  point and the unit normal into the box in the object frame, zero where the finger is not in contact.

A frame without valid kinematics (``Kinematics.valid`` False, or a pose that is not finite), or
with any other input not finite, has NaN inputs and is not valid. Element-wise arithmetic in a fixed order only (no BLAS, no einsum, whose sums follow the
operands' memory layout): the same bits on every machine, from a dataset's table or a tracker.
"""

from __future__ import annotations

import numpy as np

from fsv.errors import InputError
from fsv.models import ObjectModel
from fsv.types import Contacts, Kinematics

_AX = "xyz"
MAX_WINDOW = 15
"""Largest accepted window, in frames on either side (0.5 s at 30 Hz)."""


def input_names(finger_names, window: int = 0) -> tuple:
    """The names of :func:`direct_inputs`' columns, in order."""
    names = [f"wrench_{c}" for c in ("Fx", "Fy", "Fz", "Tx", "Ty", "Tz")]
    for block in ("spec", "vel", "omega", "alpha", "up"):
        names += [f"{block}_{a}" for a in _AX]
    names += ["mass", *(f"half_{a}" for a in _AX), "height"]
    for o in _offsets(window):
        names += [f"{block}_{a}@{o:+d}" for block in ("spec", "omega", "alpha") for a in _AX]
    for n in finger_names:
        names += [f"active_{n}", *(f"point_{a}_{n}" for a in _AX), *(f"normal_{a}_{n}" for a in _AX)]
    return tuple(names)


def _offsets(window: int) -> list:
    return [o for o in range(-window, window + 1) if o != 0]


def check_window(window) -> int:
    """``window`` as an int in 0..:data:`MAX_WINDOW`; InputError otherwise."""
    if isinstance(window, bool) or not isinstance(window, (int, np.integer)) or not 0 <= window <= MAX_WINDOW:
        raise InputError(f"window must be an integer number of frames from 0 to {MAX_WINDOW}, got {window!r}")
    return int(window)


def _in_object(rot: np.ndarray, v: np.ndarray) -> np.ndarray:
    """R^T v per frame: (T, 3, 3), (T, 3) -> (T, 3), summed in a fixed order (einsum's sums follow
    the operands' memory layout: a table's column-major copy and a tracker's rows would differ in
    the last bit)."""
    return rot[:, 0, :] * v[:, 0:1] + rot[:, 1, :] * v[:, 1:2] + rot[:, 2, :] * v[:, 2:3]


def _times(matrix: np.ndarray, v: np.ndarray) -> np.ndarray:
    """M v per frame for one (3, 3) matrix: (3, 3), (T, 3) -> (T, 3), in a fixed order."""
    return v[:, 0:1] * matrix[:, 0] + v[:, 1:2] * matrix[:, 1] + v[:, 2:3] * matrix[:, 2]


def lowest_height(kinematics: Kinematics, object_model: ObjectModel) -> np.ndarray:
    """Height of the box's lowest corner above the plane z = 0, shape (T,), [m]:
    z - sum_j |R_zj| h_j with h the half extents (NaN where the pose is not finite)."""
    up, h = np.abs(kinematics.rot[:, 2, :]), object_model.half_extents
    return kinematics.pos[:, 2] - (up[:, 0] * h[0] + up[:, 1] * h[1] + up[:, 2] * h[2])


def direct_inputs(kinematics: Kinematics, contacts: Contacts, object_model: ObjectModel, gravity, *,
                  window: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """The network's inputs of every frame (see the module docstring).

    Args:
        kinematics: The box's kinematics in the table's frame (z = 0 the table), T frames.
        contacts: The contacts the method uses (object frame), T frames, K fingers.
        object_model: The box as the method knows it (mass, size, inertia).
        gravity: Gravity in the kinematics' frame, shape (3,), [m/s^2].
        window: Frames of kinematics on either side (0: the frame alone).

    Returns:
        ``(x, valid)``: inputs, shape (T, len(input_names(K, window))), NaN on frames without
        kinematics; and those frames' mask, shape (T,).
    """
    if not isinstance(kinematics, Kinematics) or not isinstance(contacts, Contacts) or len(kinematics) != len(contacts):
        raise InputError(f"direct_inputs needs an fsv.Kinematics and fsv.Contacts of the same frames, got "
                         f"{type(kinematics).__name__} and {type(contacts).__name__}")
    if not isinstance(object_model, ObjectModel):
        raise InputError(f"object_model must be an fsv.ObjectModel, got {type(object_model).__name__}")
    window = check_window(window)
    g = np.asarray(gravity, dtype=float)
    if g.shape != (3,) or not np.all(np.isfinite(g)):
        raise InputError(f"gravity must be a finite vector of shape (3,), got {gravity!r}")
    T, R = len(kinematics), kinematics.rot
    valid = (np.asarray(kinematics.valid, bool) & np.all(np.isfinite(kinematics.pos), axis=1)
             & np.all(np.isfinite(R), axis=(1, 2)))
    for name in ("vel", "acc", "omega", "alpha"):
        valid &= np.all(np.isfinite(getattr(kinematics, name)), axis=1)
    with np.errstate(invalid="ignore"):
        spec = _in_object(R, kinematics.acc - g)
        omega, alpha = _in_object(R, kinematics.omega), _in_object(R, kinematics.alpha)
        inertia = object_model.inertia
        torque = _times(inertia, alpha) + np.cross(omega, _times(inertia, omega))
        blocks = [object_model.mass_kg * spec, torque, spec, _in_object(R, kinematics.vel), omega, alpha,
                  R[:, 2, :], np.full((T, 1), object_model.mass_kg), np.tile(object_model.half_extents, (T, 1)),
                  lowest_height(kinematics, object_model)[:, None]]
        kin = np.concatenate([spec, omega, alpha], axis=1)
        for o in _offsets(window):
            j = np.arange(T) + o
            inside = (j >= 0) & (j < T)
            j = np.where(inside, j, np.arange(T))
            use = inside & valid[j]
            blocks.append(np.where(use[:, None], kin[np.where(use, j, np.arange(T))], kin))
    active = np.asarray(contacts.active, bool)
    on = active[..., None]
    for k in range(len(contacts.finger_names)):
        blocks += [active[:, k, None].astype(float), np.where(on[:, k], contacts.point[:, k], 0.0),
                   np.where(on[:, k], contacts.normal[:, k], 0.0)]
    x = np.concatenate(blocks, axis=1)
    valid &= np.all(np.isfinite(x), axis=1)  # e.g. a contact without a point
    x[~valid] = np.nan
    return x, valid
