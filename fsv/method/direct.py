"""The end-to-end network as the method's force stage: :class:`DirectForces`.

>>> method = make_method(forces=DirectForces(load_direct("model.npz")), internal=False)

Its output is already the method's final forces (``final = True``): the method passes it on as
both the nominal forces (the net wrench the force scores read) and the final forces (the learned
scores), with no internal-force stage after it (:meth:`fsv.method.Method.after_tracking`).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from fsv.errors import InputError
from fsv.forces import ForceSolution, FrameStatus, required_wrench, table_contacts, to_object_frame
from fsv.learn.direct import DirectForceModel
from fsv.types import Contacts, Kinematics


@dataclass(frozen=True)
class DirectForces:
    """Each finger's force and the table's wrench predicted by a :class:`fsv.learn.DirectForceModel`.

    The :class:`fsv.forces.ForceSolution` it returns has kind "direct": ``force = nominal`` the
    predicted finger forces, ``internal`` zero, ``env_wrench`` the predicted table wrench (its
    corners, ``env_active``, those of :func:`fsv.forces.table_contacts` on the frames where the
    table's wrench is predicted), ``required`` the wrench eq. 1 requires of the contacts and
    ``residual`` what the prediction leaves of it; status OPTIMAL on frames with kinematics, else
    NO_KINEMATICS (NaN forces).

    Attributes:
        model: The trained network.
        source: Where it came from, for the label (e.g. its file).
        final: Declares the output the method's final forces (read by :class:`fsv.method.Method`).
    """

    model: DirectForceModel
    source: str = ""
    final: bool = True

    def __post_init__(self):
        if not isinstance(self.model, DirectForceModel):
            raise InputError(f"DirectForces.model must be an fsv.learn.DirectForceModel, got {type(self.model).__name__}")
        if self.final is not True:
            raise InputError("DirectForces.final is True: its forces are the method's final ones")

    @property
    def name(self) -> str:
        return f"direct network from the tracker's outputs ({self.source or 'user model'}, " \
               f"{self.model.num_parameters:,} parameters)"

    def __call__(self, kinematics: Kinematics, contacts: Contacts, object_model, gravity) -> ForceSolution:
        t0 = time.perf_counter()
        pred = self.model.predict(kinematics, contacts, object_model, gravity)
        T, K = pred.force.shape[:2]
        valid = pred.valid
        active = np.asarray(contacts.active, bool) & valid[:, None]
        with np.errstate(invalid="ignore"):
            required = to_object_frame(kinematics.rot, required_wrench(kinematics, object_model, gravity))
            point = np.where(active[..., None], contacts.point, 0.0)
            fingers = np.concatenate([pred.force.sum(axis=1), np.cross(point, pred.force).sum(axis=1)], axis=1)
            residual = required - fingers - pred.table
        corners = table_contacts(kinematics, object_model).active.sum(axis=1)
        status = np.where(valid, int(FrameStatus.OPTIMAL), int(FrameStatus.NO_KINEMATICS)).astype(np.int8)
        zeros = np.zeros((T, K, 3))
        return ForceSolution(
            kind="direct", finger_names=contacts.finger_names, active=active,
            sliding=np.asarray(contacts.sliding, bool) & active, point=contacts.point, normal=contacts.normal,
            force=pred.force, nominal=pred.force, internal=np.where(valid[:, None, None], zeros, np.nan),
            env_active=np.where(pred.on_table, corners, 0), env_wrench=pred.table,
            env_internal_wrench=np.where(valid[:, None], np.zeros((T, 6)), np.nan), required=required,
            residual=residual, status=status, objective=np.full(T, np.nan), iterations=np.zeros(T, np.int64),
            solve_time_s=np.full(T, (time.perf_counter() - t0) / max(T, 1)),
        )
