"""Per-frame results of the force programs: forces per finger, table wrench, status, residuals."""

from __future__ import annotations

from dataclasses import dataclass
from enum import IntEnum

import numpy as np

from fsv._check import as_array, same_length
from fsv.errors import InputError
from fsv.types import Contacts


class FrameStatus(IntEnum):
    """What happened at one frame.

    OPTIMAL: the program was solved; the forces satisfy the cones and Newton–Euler.
    LEAST_VIOLATION: the contacts cannot explain the required wrench (the program is infeasible);
        the forces minimise ``slack_weight * ||violation||^2 + cost``, and ``residual`` holds
        the violation.
    NO_CONTACTS: nothing touches the object; all forces are zero and ``residual`` is the whole
        required wrench.
    NO_KINEMATICS: the kinematics are not valid at this frame (``Kinematics.valid`` is False);
        the forces are NaN.
    FAILED: the solver failed on both the exact and the least-violation program; forces are NaN.
    STATIC_FRICTION: the program with the kinetic friction of the sliding contacts was infeasible;
        solved with those contacts held by static friction (their Coulomb cones) instead.
    IMPLAUSIBLE: solved, but the finger forces exceed the physical bound of the frame
        (:func:`fsv.forces.force_bound`); they are not passed on: NaN.
    CONTACTS_ADDED: infeasible with the given contacts (kinetic and static friction); solved with
        the fingers near the surface added as static contacts (``ForceSettings.repair_gap_m``,
        ``Contacts.gap``); ``active`` includes them.
    """

    OPTIMAL = 0
    LEAST_VIOLATION = 1
    NO_CONTACTS = 2
    NO_KINEMATICS = 3
    FAILED = 4
    STATIC_FRICTION = 5
    IMPLAUSIBLE = 6
    CONTACTS_ADDED = 7


SOLVED = (FrameStatus.OPTIMAL, FrameStatus.STATIC_FRICTION, FrameStatus.CONTACTS_ADDED)
"""Statuses whose forces satisfy the cones and Newton–Euler exactly."""

FALLBACKS = (FrameStatus.LEAST_VIOLATION, FrameStatus.FAILED, FrameStatus.IMPLAUSIBLE)
"""Statuses of frames whose contacts could not explain the motion physically."""


KINDS = ("nominal", "decomposition", "reconstruction", "direct")


@dataclass(frozen=True)
class ForceSolution:
    """Contact forces per frame from one of the cone programs. Object frame throughout.

    The finger force is F_k = F_k^(n) + F_k^(i) (eq. 7): the nominal parts (fingers and table)
    explain the motion, the internal parts (fingers and table) have zero net force and torque
    (eq. 8). The nominal program has no internal part (``internal`` is zero). Inactive fingers have zero force; frames with
    status NO_KINEMATICS or FAILED have NaN forces.

    A "direct" solution is a network's prediction (:class:`fsv.method.direct.DirectForces`), not a
    program's: ``force`` and ``nominal`` are the predicted forces, ``internal`` is zero, status
    OPTIMAL means a prediction was made (valid kinematics) and ``residual`` holds the wrench the
    prediction leaves unexplained, which no constraint drives to zero.

    Attributes:
        kind: "nominal" (eq. 4-6), "decomposition" (eq. 7-9), "reconstruction" (eq. 14) or
            "direct" (predicted by a network).
        finger_names: The K fingers, thumb first.
        active: Finger contacts used, shape (T, K).
        sliding: Contacts modelled as kinetic, shape (T, K).
        point: Contact points, shape (T, K, 3), [m].
        normal: Unit contact normals into the object, shape (T, K, 3).
        force: Total finger force F_k, shape (T, K, 3), [N].
        nominal: Nominal part F_k^(n), shape (T, K, 3), [N].
        internal: Internal part F_k^(i), shape (T, K, 3), [N].
        env_active: Number of table corners in contact, shape (T,).
        env_wrench: Table force and torque about the centre of mass (nominal + internal part),
            shape (T, 6), [N, N m].
        env_internal_wrench: The table's internal part (it balances the fingers' internal parts,
            e.g. when a finger presses the box onto the table), shape (T, 6); zero for "nominal".
        required: The wrench eq. 1 requires of the contacts, shape (T, 6), [N, N m].
        residual: ``required`` minus the wrench of the nominal parts of the fingers and the table,
            shape (T, 6); zero up to solver tolerance where the status is OPTIMAL.
        status: :class:`FrameStatus` per frame, shape (T,), int8.
        objective: Value of the program's cost (with its constant term, so eq. 6, 9 or 14
            exactly; plus the table and regularisation terms), shape (T,).
        iterations: Interior-point iterations of the last solve, shape (T,).
        solve_time_s: Wall-clock time spent on the frame's program(s): assembly, solver update,
            solve and unpacking, shape (T,), [s]; 0 for frames without a program. The frames of
            one layout are assembled together (with their program's construction) and share that
            time equally.
    """

    kind: str
    finger_names: tuple
    active: np.ndarray
    sliding: np.ndarray
    point: np.ndarray
    normal: np.ndarray
    force: np.ndarray
    nominal: np.ndarray
    internal: np.ndarray
    env_active: np.ndarray
    env_wrench: np.ndarray
    env_internal_wrench: np.ndarray
    required: np.ndarray
    residual: np.ndarray
    status: np.ndarray
    objective: np.ndarray
    iterations: np.ndarray
    solve_time_s: np.ndarray

    def __post_init__(self):
        if self.kind not in KINDS:
            raise InputError(f"ForceSolution.kind must be one of {KINDS}, got {self.kind!r}")
        names = tuple(str(n) for n in self.finger_names)
        K = len(names)
        fields = dict(
            active=as_array("ForceSolution.active", self.active, (None, K), bool),
            sliding=as_array("ForceSolution.sliding", self.sliding, (None, K), bool),
            point=as_array("ForceSolution.point", self.point, (None, K, 3)),
            normal=as_array("ForceSolution.normal", self.normal, (None, K, 3)),
            force=as_array("ForceSolution.force", self.force, (None, K, 3)),
            nominal=as_array("ForceSolution.nominal", self.nominal, (None, K, 3)),
            internal=as_array("ForceSolution.internal", self.internal, (None, K, 3)),
            env_active=as_array("ForceSolution.env_active", self.env_active, (None,), np.int64),
            env_wrench=as_array("ForceSolution.env_wrench", self.env_wrench, (None, 6)),
            env_internal_wrench=as_array("ForceSolution.env_internal_wrench", self.env_internal_wrench, (None, 6)),
            required=as_array("ForceSolution.required", self.required, (None, 6)),
            residual=as_array("ForceSolution.residual", self.residual, (None, 6)),
            status=as_array("ForceSolution.status", self.status, (None,), np.int8),
            objective=as_array("ForceSolution.objective", self.objective, (None,)),
            iterations=as_array("ForceSolution.iterations", self.iterations, (None,), np.int64),
            solve_time_s=as_array("ForceSolution.solve_time_s", self.solve_time_s, (None,)),
        )
        same_length("ForceSolution", **fields)
        object.__setattr__(self, "finger_names", names)
        for k, v in fields.items():
            object.__setattr__(self, k, v)

    def __len__(self) -> int:
        return self.status.shape[0]

    def _along_normal(self, f: np.ndarray) -> np.ndarray:
        return np.einsum("tki,tki->tk", f, self.normal) * self.active

    @property
    def normal_force(self) -> np.ndarray:
        """Normal component f_k of the total finger force, shape (T, K), [N]; 0 where inactive."""
        return self._along_normal(self.force)

    @property
    def tangential_force(self) -> np.ndarray:
        """Tangential (friction) component F_k - f_k n_k of the total finger force, shape (T, K, 3), [N]."""
        return self.force - self.normal_force[..., None] * self.normal

    @property
    def nominal_normal(self) -> np.ndarray:
        """Normal component f_k^(n) of the nominal part, shape (T, K), [N]."""
        return self._along_normal(self.nominal)

    @property
    def internal_normal(self) -> np.ndarray:
        """Normal component f_k^(i) of the internal part, shape (T, K), [N]."""
        return self._along_normal(self.internal)

    @property
    def sum_of_squares(self) -> np.ndarray:
        """Sum over fingers of ||F_k||^2 (eq. 6 evaluated on the total forces), shape (T,), [N^2]."""
        return np.einsum("tki,tki->t", self.force, self.force)

    @property
    def finger_wrench(self) -> np.ndarray:
        """Net wrench of the total finger forces about the centre of mass, shape (T, 6)."""
        return np.concatenate(
            [self.force.sum(axis=1), np.cross(self.point * self.active[..., None], self.force).sum(axis=1)], axis=1
        )

    @property
    def net_wrench(self) -> np.ndarray:
        """Net wrench of every contact (fingers and table) about the centre of mass, shape (T, 6)."""
        return self.finger_wrench + self.env_wrench

    @property
    def internal_wrench(self) -> np.ndarray:
        """Net wrench of the internal parts (fingers and table), shape (T, 6); zero up to solver tolerance (eq. 8)."""
        fingers = np.concatenate(
            [self.internal.sum(axis=1), np.cross(self.point * self.active[..., None], self.internal).sum(axis=1)],
            axis=1,
        )
        return fingers + self.env_internal_wrench

    def contacts_used(self, given: Contacts) -> Contacts:
        """The contacts these forces were computed on: ``given`` (the contacts passed to the
        program) with the fingers the program added (:attr:`FrameStatus.CONTACTS_ADDED` frames) made
        active, static, at the points and normals it used. ``given`` itself when none was added.

        Args:
            given: The contacts the program was given, the same T frames and K fingers.

        Returns:
            The contacts the next stage should use.
        """
        if given.finger_names != self.finger_names or len(given) != len(self):
            raise InputError(f"contacts_used needs the program's {len(self)} frames and fingers {self.finger_names}, "
                             f"got {len(given)} frames and {given.finger_names}")
        added = self.active & ~given.active
        if not added.any():
            return given
        return Contacts(given.finger_names, given.active | added, given.sliding,
                        np.where(added[..., None], self.point, given.point),
                        np.where(added[..., None], self.normal, given.normal), given.slide_dir, given.gap)

    def count(self, status: FrameStatus) -> int:
        """Number of frames with the given status."""
        return int(np.sum(self.status == int(status)))
