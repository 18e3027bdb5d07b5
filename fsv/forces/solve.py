"""Contact forces per frame: nominal (eq. 4-6), decomposition (eq. 7-9), reconstruction (eq. 14).

All three programs share the contacts (fingers from :class:`fsv.Contacts`, table corners from
:mod:`fsv.forces.environment`), the Coulomb cones, and the Newton–Euler equality of eq. 1 on the
nominal parts. They differ in the cost:

    nominal          Σ_k ||F_k||²                                               (eq. 6)
    decomposition    Σ_k ||F_k^(n)||² + (f_k^(n) + f_k^(i) - f̃_k)²             (eq. 9)
    reconstruction   Σ_k ||F_k^(n)||² + (f_k^(i) - f̃_k^(i))²                   (eq. 14)

plus ``table_weight`` Σ_j ||F_j||² over the table corners (their forces are part of the nominal
wrench; the paper sums over fingers only, and a small weight keeps the problem strictly convex
while letting the table carry what it can), and ``regularization`` times the squares of the
internal components that no target fixes (the tangential ones, and the normal one of a finger
without a target; a table corner's normal internal component gets ``regularization * table_weight``,
so that a finger pressing the box onto the table is balanced by a table reaction under it rather
than by friction), which makes the decomposition unique without measurably moving it.

In the decomposition and reconstruction, the nominal part of each contact lies in its friction
cone and so does the total F_k^(n) + F_k^(i) ("the distribution still obeys Coulomb's law"); the
internal parts alone need not (a finger may press less than its nominal share). The internal
parts have zero net force and torque (eq. 8). Table corners take part in both: a finger pressing
the box onto the table is a workless squeeze whose reaction is the table's internal part.

A frame whose program is infeasible is first solved again with its sliding contacts held by static
friction (their Coulomb cones instead of kinetic friction along the sliding direction; a contact
flagged sliding from noisy tracking often cannot pull the way kinetic friction forces it to),
flagged :attr:`FrameStatus.STATIC_FRICTION` when that succeeds (``settings.static_retry``). If it
is still infeasible, a contact is missing: the fingers the tracker saw near the surface but not on
it (``Contacts.gap`` at most ``settings.repair_gap_m``) are added as static contacts at their pads'
projections and the frame is solved again, flagged :attr:`FrameStatus.CONTACTS_ADDED` when that
succeeds (the solution's ``active`` then includes them, and :meth:`ForceSolution.contacts_used`
passes them on to the next stage). A frame on which nothing touches the object at all (the tracker
lost every contact, and the box is off the table) is solved with those fingers in the same way, or
by least violation with them: what the forces stage believes carries the box, rather than no force
(issue 45). If it is still infeasible (e.g. a single contact that would have
to pull), it is solved with the tracked contacts and a slack σ on the nominal wrench equality,
``slack_weight`` ||σ||² added to the cost: the least-violation answer, flagged
:attr:`FrameStatus.LEAST_VIOLATION`.

Nominal forces are checked against :func:`force_bound`, what the object's mass, its measured
motion and the grasp's size can need at most; a frame whose finger forces exceed it is flagged
:attr:`FrameStatus.IMPLAUSIBLE` and its forces are NaN, never passed on as estimates.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from fsv._check import as_array, positive, same_length
from fsv.errors import InputError
from fsv.forces.environment import TableContacts, table_contacts
from fsv.forces.program import OK, Layout, Program, Weights
from fsv.forces.solution import ForceSolution, FrameStatus
from fsv.forces.wrench import GRAVITY, required_wrench, tangent_basis, to_object_frame
from fsv.models import ObjectModel
from fsv.types import Contacts, Kinematics

BOUND_FACTOR = 5.0
"""Safety factor of the physical bound on the nominal forces: how far above the grasp-mechanics
estimate of :func:`force_bound` a minimal solution may go before it is called absurd. Chosen by hand
(not tuned on any suite): the L2-minimal forces of the truth's contacts stay below one bound."""


def force_bound(required: np.ndarray, friction: float, lever_m: float, factor: float = BOUND_FACTOR) -> np.ndarray:
    """The most the fingers' total force may need to be to produce the required wrench.

    Friction carries a force F with normal forces of about |F| / μ, and a torque τ needs forces of
    |τ| / lever about a lever arm; so the L2-minimal finger forces stay below
    ``factor * ((1 + 1/μ) |F| + (1 + 1/μ) |τ| / lever)``.

    Args:
        required: Required wrench per frame (force, torque about the centre of mass), shape (T, 6).
        friction: Finger friction coefficient μ.
        lever_m: The smallest lever arm of the grasp: half the object's smallest dimension, [m].
        factor: Safety factor.

    Returns:
        Bound on Σ_k ||F_k|| per frame, shape (T,), [N].
    """
    required = np.asarray(required, dtype=float)
    scale = 1.0 + 1.0 / float(friction)
    force = np.sqrt(np.sum(required[:, :3] ** 2, axis=1))
    torque = np.sqrt(np.sum(required[:, 3:] ** 2, axis=1))
    return factor * scale * (force + torque / float(lever_m))


FEASIBILITY_TOL = 1e-5
"""Relative violation below which a least-violation answer counts as solved (see ``ForceSettings``).
The least-violation program's slack weight (1e6) leaves a violation of about |F| / 1e6 even where
the frame is feasible up to rounding (a force exactly on its cone's surface); the tolerance is ten
times that for forces of the required wrench's size, and four orders below the errors of a method
from vision (net force errors of 0.1-0.3 N on a 3 N weight)."""


REPAIR_GAP_M = 0.035
"""How far from the surface [m] a tracked finger's pad may be for an infeasible frame to take it as a
contact. Chosen on the ``dev`` suite (seeds 500-547, never on ``standard``): with 0 (off), 0.02,
0.035 and 0.05 m the least-violation frames were 2.3, 1.0, 0.78 and 0.69 % of the frames, at the
same contact precision (0.968-0.969); 0.05 m gained little more. Pads within 35 mm are those the
contact detector's 6-12 mm hysteresis rejects under hand-tracking errors of 1-3 cm."""


@dataclass(frozen=True)
class ForceSettings:
    """Modelling and solver choices of the force programs.

    Attributes:
        table: Model the table as an environment contact (see :mod:`fsv.forces.environment`).
        table_height_tol_m: Corner height [m] below which a corner touches the table.
        table_max_tilt_deg: Tilt [deg] up to which the box's lowest face counts as flat (resting).
        table_weight: Weight of the table forces' squared norms in the cost (fingers have 1).
        slack_weight: Weight of the squared wrench violation in least-violation programs.
        regularization: Weight of the squared internal components without a target.
        max_iter: Interior-point iteration limit per solve.
        static_retry: Solve an infeasible frame with its sliding contacts static before least violation.
        feasibility_tol: A least-violation answer whose violation is at most this fraction of
            max(1, |required wrench|) explains the motion to the solver's precision (a contact force
            exactly on its cone's surface, as when the box slides on the table) and is reported
            OPTIMAL; 0 keeps every least-violation answer flagged.
        bound_factor: Safety factor of :func:`force_bound` on the nominal forces (``inf``: no bound).
        repair_gap_m: An infeasible frame is solved again with the inactive fingers whose
            ``Contacts.gap`` is at most this added as static contacts, [m]; 0 = off (see
            :data:`REPAIR_GAP_M`).
    """

    table: bool = True
    table_height_tol_m: float = 0.003
    table_max_tilt_deg: float = 10.0
    table_weight: float = 0.01
    slack_weight: float = 1e6
    regularization: float = 1e-3
    max_iter: int = 100
    static_retry: bool = True
    feasibility_tol: float = FEASIBILITY_TOL
    bound_factor: float = BOUND_FACTOR
    repair_gap_m: float = REPAIR_GAP_M

    def __post_init__(self):
        for name in ("table_height_tol_m", "regularization", "feasibility_tol", "repair_gap_m"):
            v = getattr(self, name)
            if not (np.isfinite(v) and v >= 0):
                raise InputError(f"ForceSettings.{name} must be a finite number >= 0, got {v!r}")
        for name in ("table_weight", "slack_weight"):
            v = getattr(self, name)
            positive(f"ForceSettings.{name}", v)
        if isinstance(self.max_iter, bool) or not isinstance(self.max_iter, (int, np.integer)) or self.max_iter < 1:
            raise InputError(f"ForceSettings.max_iter must be a positive integer, got {self.max_iter!r}")
        if not isinstance(self.static_retry, (bool, np.bool_)):
            raise InputError(f"ForceSettings.static_retry must be True or False, got {self.static_retry!r}")
        if not (self.bound_factor > 0):
            raise InputError(f"ForceSettings.bound_factor must be > 0 (inf: no bound), got {self.bound_factor!r}")


def nominal_forces(
    kinematics: Kinematics,
    contacts: Contacts,
    model: ObjectModel,
    *,
    gravity=GRAVITY,
    settings: ForceSettings | None = None,
) -> ForceSolution:
    """Minimal sum-of-squares contact forces that explain the motion (eq. 4-6).

    Args:
        kinematics: Object kinematics (world frame), T frames.
        contacts: Finger contacts (object frame), the same T frames.
        model: Known mass, inertia and friction coefficients.
        gravity: Gravity, world frame, shape (3,), [m/s^2].
        settings: Modelling and solver choices; defaults to ``ForceSettings()``.

    Returns:
        The forces per frame; ``internal`` is zero.
    """
    return _solve("nominal", kinematics, contacts, model, None, gravity, settings)


def decompose_forces(
    kinematics: Kinematics,
    contacts: Contacts,
    model: ObjectModel,
    measured_normal,
    *,
    gravity=GRAVITY,
    settings: ForceSettings | None = None,
) -> ForceSolution:
    """Nominal and internal parts that best match measured normal forces (eq. 7-9).

    Args:
        kinematics: Object kinematics (world frame), T frames.
        contacts: Finger contacts (object frame), the same T frames.
        model: Known mass, inertia and friction coefficients.
        measured_normal: Tactile measurements f̃_k of the normal force per finger, shape (T, K),
            [N]; NaN where a finger has no measurement (that finger's term drops from eq. 9).
        gravity: Gravity, world frame, shape (3,), [m/s^2].
        settings: Modelling and solver choices.

    Returns:
        ``nominal`` explains the motion with the table, ``internal`` has zero net wrench, and
        ``force`` is their sum.
    """
    return _solve("decomposition", kinematics, contacts, model, measured_normal, gravity, settings)


def reconstruct_forces(
    kinematics: Kinematics,
    contacts: Contacts,
    model: ObjectModel,
    internal_normal,
    *,
    gravity=GRAVITY,
    settings: ForceSettings | None = None,
) -> ForceSolution:
    """Full forces whose internal normal components follow given values (eq. 14).

    Args:
        kinematics: Object kinematics (world frame), T frames.
        contacts: Finger contacts (object frame), the same T frames.
        model: Known mass, inertia and friction coefficients.
        internal_normal: Predicted internal normal force f̃_k^(i) per finger, shape (T, K), [N]
            (e.g. from the networks of :mod:`fsv.learn`); NaN where there is no prediction.
        gravity: Gravity, world frame, shape (3,), [m/s^2].
        settings: Modelling and solver choices.

    Returns:
        ``nominal`` explains the motion with the table, ``internal`` has zero net wrench and
        normal components close to the predictions, and ``force`` is their sum.
    """
    return _solve("reconstruction", kinematics, contacts, model, internal_normal, gravity, settings)


def _unit_rows(v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    norm = np.linalg.norm(v, axis=-1, keepdims=True)
    return v / np.where(norm > 0, norm, 1.0), norm[..., 0]


def _column_bank(contacts: Contacts, table: TableContacts, mu: float, use: np.ndarray) -> tuple:
    """Unit-force wrenches per frame, contact and slot: (T, K + 8, 4, 6), plus the used normals."""
    T, K = contacts.active.shape
    n, norm = _unit_rows(np.where(use[..., None], contacts.normal, 0.0))
    bad = use & ~(norm > 1e-9)
    if bad.any():
        t, k = np.argwhere(bad)[0]
        raise InputError(f"Contacts.normal of active finger {k} at frame {t} is zero; a unit normal is required")
    s = contacts.slide_dir - np.einsum("tki,tki->tk", contacts.slide_dir, n)[..., None] * n
    s, snorm = _unit_rows(np.where((use & contacts.sliding)[..., None], s, 0.0))
    bad = use & contacts.sliding & ~(snorm > 1e-9)
    if bad.any():
        t, k = np.argwhere(bad)[0]
        raise InputError(
            f"Contacts.slide_dir of sliding finger {k} at frame {t} has no component in the contact's "
            "tangent plane; a sliding contact needs a tangential direction"
        )
    tx, ty = tangent_basis(np.where(use[..., None], n, (0.0, 0.0, 1.0)))
    fdirs = np.stack([n, tx, ty, n + mu * s], axis=2)  # (T, K, 4, 3)
    p = np.where(use[..., None], contacts.point, 0.0)
    ctx, cty = tangent_basis(table.normal)
    cdirs = np.stack([table.normal, ctx, cty, np.zeros_like(ctx)], axis=1)  # (T, 4, 3)
    cdirs = np.broadcast_to(cdirs[:, None], (T, 8, 4, 3))
    cp = np.broadcast_to(table.point[None, :, None, :], (T, 8, 4, 3))
    dirs = np.concatenate([fdirs, cdirs], axis=1)
    pts = np.concatenate([np.broadcast_to(p[:, :, None, :], fdirs.shape), cp], axis=1)
    return np.concatenate([dirs, np.cross(pts, dirs)], axis=-1), n


def _check_inputs(kind, kinematics, contacts, model, target, gravity, settings):
    if not isinstance(kinematics, Kinematics):
        raise InputError(f"kinematics must be fsv.Kinematics, got {type(kinematics).__name__}")
    if not isinstance(contacts, Contacts):
        raise InputError(f"contacts must be fsv.Contacts, got {type(contacts).__name__}")
    if not isinstance(model, ObjectModel):
        raise InputError(f"model must be fsv.ObjectModel, got {type(model).__name__}")
    settings = ForceSettings() if settings is None else settings
    if not isinstance(settings, ForceSettings):
        raise InputError(f"settings must be fsv.forces.ForceSettings, got {type(settings).__name__}")
    T = same_length("forces", kinematics=kinematics.t, contacts=contacts.active)
    K = len(contacts.finger_names)
    if target is None:
        target = np.full((T, K), np.nan)
    else:
        name = "measured_normal" if kind == "decomposition" else "internal_normal"
        target = as_array(name, target, (T, K))
        if np.isinf(target).any():
            raise InputError(f"{name} must be finite or NaN (no value), it holds inf")
    valid = kinematics.valid.copy()
    fields = (kinematics.pos, kinematics.acc, kinematics.omega, kinematics.alpha)
    finite_kin = np.all([np.isfinite(a).reshape(T, -1).all(axis=1) for a in fields], axis=0)
    finite_kin &= np.isfinite(kinematics.rot).reshape(T, -1).all(axis=1)
    if np.any(valid & ~finite_kin):
        t = int(np.argmax(valid & ~finite_kin))
        raise InputError(f"Kinematics frame {t} is marked valid but holds NaN/inf; mark it invalid instead")
    use = contacts.active & valid[:, None]
    if not np.isfinite(np.where(use[..., None], contacts.point, 0.0)).all():
        raise InputError("Contacts.point must be finite for active fingers")
    return settings, target, valid, use


def _solve(kind, kinematics, contacts, model, target, gravity, settings) -> ForceSolution:
    settings, target, valid, use = _check_inputs(kind, kinematics, contacts, model, target, gravity, settings)
    T, K = contacts.active.shape
    with np.errstate(invalid="ignore"):
        required = to_object_frame(kinematics.rot, required_wrench(kinematics, model, gravity))
    if settings.table:
        table = table_contacts(
            kinematics, model, height_tol_m=settings.table_height_tol_m, max_tilt_deg=settings.table_max_tilt_deg
        )
    else:
        table = TableContacts.none(T, model)
    corners_on = table.active & valid[:, None]
    candidates = _candidates(contacts, use, valid, settings.repair_gap_m)
    bank, normals = _column_bank(contacts, table, model.friction, use | candidates)
    weights = Weights(
        finger_friction=model.friction,
        table_friction=model.table_friction,
        table_weight=settings.table_weight,
        slack_weight=settings.slack_weight,
        regularization=settings.regularization,
        max_iter=settings.max_iter,
    )
    sliding = contacts.sliding & use
    fitted = use & np.isfinite(target) & (kind != "nominal")
    target = np.where(fitted, target, 0.0)
    frames = _Frames(kind=kind, K=K, weights=weights, bank=bank, required=required, target=target, use=use,
                     sliding=sliding, fitted=fitted, corners_on=corners_on, candidates=candidates, settings=settings)
    # Per frame the rows of Program.solve: nominal fingers (K), internal fingers (K), nominal table
    # corners (8), internal corners (8); one row block per frame keeps the loop to a single copy.
    out = np.zeros((T, 2 * K + 16, 3))
    status = np.full(T, int(FrameStatus.OPTIMAL), np.int8)
    objective = np.zeros(T)
    iterations = np.zeros(T, np.int64)
    seconds = np.zeros(T)
    keys = [row.tobytes() for row in np.concatenate([use, sliding, fitted, corners_on], axis=1)]
    touching = (use.any(axis=1) | corners_on.any(axis=1)).tolist()
    prepared = frames.assemble(keys, np.flatnonzero(valid & np.array(touching, bool)).tolist(), seconds)
    for t, is_valid in enumerate(valid.tolist()):
        if not is_valid:
            status[t] = FrameStatus.NO_KINEMATICS
            out[t] = objective[t] = np.nan
            continue
        if not touching[t]:
            if candidates[t].any():  # lost contacts: the pads near the surface, as for an infeasible frame
                t0 = time.perf_counter()
                out[t], status[t], objective[t], iterations[t] = frames.solve_untouched(t)
                seconds[t] += time.perf_counter() - t0
            else:
                status[t] = FrameStatus.NO_CONTACTS
            continue
        t0 = time.perf_counter()
        out[t], status[t], objective[t], iterations[t] = frames.solve(t, keys[t], prepared[t])
        seconds[t] += time.perf_counter() - t0
    if kind == "nominal" and np.isfinite(settings.bound_factor):
        bound = force_bound(required, model.friction, float(np.min(model.size_m)) / 2, settings.bound_factor)
        total = np.sqrt(np.sum(out[:, :K] ** 2, axis=2)).sum(axis=1)
        absurd = np.isin(status, [int(s) for s in (FrameStatus.OPTIMAL, FrameStatus.STATIC_FRICTION,
                                                   FrameStatus.CONTACTS_ADDED, FrameStatus.LEAST_VIOLATION)])
        absurd &= total > bound
        status[absurd] = FrameStatus.IMPLAUSIBLE
        out[absurd] = np.nan
        objective[absurd] = np.nan
    return _solution(kind, contacts, frames, table, normals, out, status, objective, iterations, seconds)


class _Frames:
    """One sequence's programs, one per layout, built on first use and re-used across frames; and
    the per-frame fallbacks. ``use`` and ``sliding`` are the caller's arrays: a fallback that adds
    contacts or holds sliding ones writes its frame's row of them."""

    def __init__(self, *, kind, K, weights, bank, required, target, use, sliding, fitted, corners_on, candidates,
                 settings):
        self.kind, self.K, self.weights, self.settings = kind, K, weights, settings
        self.bank, self.required, self.target = bank, required, target
        self.use, self.sliding, self.fitted, self.corners_on, self.candidates = use, sliding, fitted, corners_on, candidates
        self.programs: dict = {}

    def _program(self, slack: bool, key: bytes, use, sliding, fitted, corners_on):
        prog = self.programs.get((key, slack))
        if prog is None:
            prog = self.programs[(key, slack)] = _program(slack, self.kind, use, sliding, fitted, corners_on,
                                                          self.weights, self.K)
        return prog

    def assemble(self, keys: list, frames: list, seconds: np.ndarray) -> list:
        """Each layout's frames assembled in one NumPy pass (its time shared out over those frames)."""
        prepared = [None] * len(keys)
        groups: dict = {}
        for t in frames:
            groups.setdefault(keys[t], []).append(t)
        for key, ts in groups.items():
            t0 = time.perf_counter()
            t = ts[0]
            prog = self._program(False, key, self.use[t], self.sliding[t], self.fitted[t], self.corners_on[t])
            prepared_ts = prog.assemble(self.bank[ts], self.required[ts], self.target[ts])
            for t, frame in zip(ts, prepared_ts):
                prepared[t] = frame
            seconds[ts] = (time.perf_counter() - t0) / len(ts)
        return prepared

    def solve_untouched(self, t: int) -> tuple:
        """Frame ``t``, on which nothing touches the object, with its candidates as static contacts
        (flagged CONTACTS_ADDED), or their least-violation answer; ``(forces, status, objective,
        iterations)`` as :meth:`solve`."""
        K, fitted, corners_on = self.K, self.fitted, self.corners_on
        more, held = self.candidates[t].copy(), np.zeros(K, bool)
        key = np.concatenate([more, held, fitted[t], corners_on[t]]).tobytes()
        args = (self.bank[t], self.required[t], self.target[t])
        forces, code, objective, iterations = self._program(False, key, more, held, fitted[t], corners_on[t]).solve(*args)
        status = FrameStatus.CONTACTS_ADDED
        if code not in OK:
            forces, code, objective, iterations = self._program(True, key, more, held, fitted[t], corners_on[t]).solve(*args)
            status = FrameStatus.LEAST_VIOLATION
        if code not in OK:
            return np.full((2 * K + 16, 3), np.nan), FrameStatus.FAILED, np.nan, iterations
        self.use[t], self.sliding[t] = more, held
        return forces, status, objective, iterations

    def solve(self, t: int, key: bytes, prepared) -> tuple:
        """Frame ``t``: its layout's program, then the fallbacks (static friction, contacts added,
        least violation); ``(forces (2K + 16, 3), status, objective, iterations)``."""
        K, use, sliding, fitted, corners_on = self.K, self.use, self.sliding, self.fitted, self.corners_on
        args = (self.bank[t], self.required[t], self.target[t])
        status = FrameStatus.OPTIMAL
        forces, code, objective, iterations = self.programs[(key, False)].run(prepared)
        if code not in OK and self.settings.static_retry and sliding[t].any():
            held = np.zeros(K, bool)
            static = self._program(False, np.concatenate([use[t], held, fitted[t], corners_on[t]]).tobytes(),
                                   use[t], held, fitted[t], corners_on[t])
            forces, code, objective, iterations = static.solve(*args)
            if code in OK:
                status = FrameStatus.STATIC_FRICTION
                sliding[t] = held
        if code not in OK and self.candidates[t].any():
            more = use[t] | self.candidates[t]
            held = np.zeros(K, bool) if self.settings.static_retry else sliding[t]
            added = self._program(False, np.concatenate([more, held, fitted[t], corners_on[t]]).tobytes(),
                                  more, held, fitted[t], corners_on[t])
            got = added.solve(*args)
            if got[1] in OK:
                forces, code, objective, iterations = got
                status = FrameStatus.CONTACTS_ADDED
                use[t], sliding[t] = more, held
        if code not in OK:
            retry = self._program(True, key, use[t], sliding[t], fitted[t], corners_on[t])
            forces, code, objective, iterations = retry.solve(*args)
            status = FrameStatus.LEAST_VIOLATION if code in OK else FrameStatus.FAILED
            if code not in OK:
                forces, objective = np.full((2 * K + 16, 3), np.nan), np.nan
        return forces, status, objective, iterations


def _solution(kind, contacts, frames: _Frames, table, normals, out, status, objective, iterations,
              seconds) -> ForceSolution:
    """The :class:`ForceSolution` of the frames' forces (the wrenches they achieve, the residuals)."""
    K, use, required, settings = frames.K, frames.use, frames.required, frames.settings
    nominal, internal = out[:, :K], out[:, K : 2 * K]
    corner, corner_internal = out[:, 2 * K : 2 * K + 8], out[:, 2 * K + 8 :]
    env = np.concatenate([corner.sum(axis=1), np.cross(table.point, corner).sum(axis=1)], axis=1)
    env_internal = np.concatenate(
        [corner_internal.sum(axis=1), np.cross(table.point, corner_internal).sum(axis=1)], axis=1
    )
    point = np.where(use[..., None], contacts.point, 0.0)
    achieved = np.concatenate([nominal.sum(axis=1), np.cross(point, nominal).sum(axis=1)], axis=1) + env
    residual = np.where(status[:, None] == FrameStatus.NO_CONTACTS, required, required - achieved)
    if settings.feasibility_tol > 0:  # violations at the solver's precision: the frame was feasible
        scale = np.maximum(1.0, np.sqrt(np.sum(required**2, axis=1)))
        with np.errstate(invalid="ignore"):
            tiny = np.sqrt(np.sum(residual**2, axis=1)) <= settings.feasibility_tol * scale
        status[(status == FrameStatus.LEAST_VIOLATION) & tiny] = FrameStatus.OPTIMAL
    return ForceSolution(
        kind=kind,
        finger_names=contacts.finger_names,
        active=use,
        sliding=frames.sliding,
        point=point,
        normal=np.where(use[..., None], normals, 0.0),
        force=nominal + internal,
        nominal=nominal,
        internal=internal,
        env_active=frames.corners_on.sum(axis=1),
        env_wrench=env + env_internal,
        env_internal_wrench=env_internal,
        required=required,
        residual=residual,
        status=status,
        objective=objective,
        iterations=iterations,
        solve_time_s=seconds,
    )


def _candidates(contacts: Contacts, use: np.ndarray, valid: np.ndarray, gap_m: float) -> np.ndarray:
    """Inactive fingers an infeasible frame may add: the pad within ``gap_m`` of the surface, a
    finite point and a non-zero normal (the pad's projection), shape (T, K)."""
    if gap_m <= 0:
        return np.zeros_like(use)
    with np.errstate(invalid="ignore"):
        near = contacts.gap <= gap_m
    normal = np.nan_to_num(contacts.normal, nan=0.0, posinf=0.0, neginf=0.0)
    ok = np.isfinite(contacts.point).all(axis=2) & (np.einsum("tki,tki->tk", normal, normal) > 1e-18)
    return near & ok & ~use & valid[:, None]


def _program(slack, kind, use, sliding, fitted, corners, weights, K) -> Program:
    fingers = tuple(int(k) for k in np.flatnonzero(use))
    layout = Layout(
        kind=kind,
        fingers=fingers,
        sliding=tuple(bool(sliding[k]) for k in fingers),
        fitted=tuple(bool(fitted[k]) for k in fingers),
        corners=tuple(int(j) for j in np.flatnonzero(corners)),
        slack=slack,
    )
    return Program(layout, weights, K)
