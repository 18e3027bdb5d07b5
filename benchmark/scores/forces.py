"""Scores of the force stage against the truth: the paper's §4.2 and Fig. 5.

Metric definitions (docs/design.md):

* Net force / torque error: the resultant of the estimated contact forces (fingers and, where the
  method models it, the table) minus the true resultant contact wrench (fingers and the table)
  averaged over the frame's interval (``Truth.net_wrench_mean``), world frame, torque about the
  centre of mass; ``net_force_err_n_rms`` and ``net_torque_err_nm_rms`` are the root mean square of
  its Euclidean norm over the scored frames (those with an estimate: every status but
  NO_KINEMATICS and FAILED). ``net_force_err_n_rms_instant`` is the same against the instantaneous
  resultant at the frame's time, which also holds contact transients of a few milliseconds (a
  grasp's onset, the table's impact) that no method sampling at the frame rate can resolve.
* Nominal normal force error: per finger and frame where both the truth and the estimate have the
  contact, the nominal normal force minus the true normal force n_k . F_k; ``nominal_normal_err_n_mean``
  is its mean (negative: people grip harder than the L2-minimal grasp, as in the paper's Fig. 5).
* Sum of squares (eq. 6): Σ_k ||F_k||² over the fingers, true and nominal. Since the nominal grasp
  is L2-minimal among those the program allows, the true sum is not below it wherever the true forces
  are feasible for the program (frames where neither the truth nor the estimate has the table).
* ``solver_failures``: frames whose forces are a fallback (:data:`fsv.forces.FALLBACKS`: least
  violation, failed, or above the physical bound); ``fallback_frac`` their fraction of the frames
  with kinematics. Frames solved with static friction for sliding contacts count as solved.
* Sensitivity (§4.2): the nominal forces computed with vision contact points minus those computed
  with the true contact points, same kinematics; per finger normal force, pooled over fingers and
  frames where both have the contact; mean and standard deviation (the paper: 0.216 N, 1.548 N).
"""

from __future__ import annotations

import numpy as np

from benchmark.world.truth import Truth
from fsv import Contacts, Kinematics, ObjectModel
from fsv.forces import (
    FALLBACKS,
    ForceSettings,
    ForceSolution,
    FrameStatus,
    nominal_forces,
    to_world_frame,
)

PAPER_SENSITIVITY_N = {"mean": 0.216, "std": 1.548}

_ESTIMATED = (FrameStatus.OPTIMAL, FrameStatus.STATIC_FRICTION, FrameStatus.LEAST_VIOLATION, FrameStatus.NO_CONTACTS)


def true_net_wrench(truth: Truth) -> np.ndarray:
    """The true resultant contact wrench (fingers and table) averaged over each frame's interval,
    world frame, about the COM, (T, 6): what the net force scores compare with."""
    return np.asarray(truth.net_wrench_mean, float)


def true_net_wrench_instant(truth: Truth) -> np.ndarray:
    """Resultant of the true contact forces (fingers and table) at the frame times, world frame, about the COM, (T, 6)."""
    F = np.asarray(truth.contact_force, float)
    fingers = np.concatenate([F.sum(axis=1), np.cross(truth.contact_point, F).sum(axis=1)], axis=1)
    return to_world_frame(truth.box_rot, fingers) + np.concatenate([truth.env_force, truth.env_torque], axis=1)


def true_normal_forces(truth: Truth) -> np.ndarray:
    """Each finger's true normal force n_k . F_k, shape (T, K), [N]; 0 off contact (the scoring reference)."""
    f = np.sum(np.asarray(truth.contact_force, float) * np.asarray(truth.contact_normal, float), axis=-1)
    return np.where(truth.contact_active, f, 0.0)


def scored_frames(solution: ForceSolution) -> np.ndarray:
    """Frames with an estimate (every status but NO_KINEMATICS and FAILED), (T,) bool."""
    return np.isin(solution.status, [int(s) for s in _ESTIMATED])


def score_forces(solution: ForceSolution, truth: Truth, rot: np.ndarray) -> dict:
    """The ``forces`` block of ``summary.json`` (see the module docstring).

    Args:
        solution: Nominal forces of the method.
        truth: The episode's truth.
        rot: The orientation the method used to express its forces in the world, (T, 3, 3).

    Returns:
        ``net_force_err_n_rms``, ``net_torque_err_nm_rms``, ``net_force_err_n_rms_instant``,
        ``nominal_normal_err_n_mean``,
        ``nominal_normal_err_n_std``, ``true_normal_n_mean``, ``nominal_normal_n_mean``,
        ``sos_true_not_below_nominal_frac``, ``sos_frames``, ``solver_failures``, ``status``
        (frames per status name) and ``frames_scored``; NaN where undefined.
    """
    ok = scored_frames(solution)
    est = to_world_frame(rot, solution.net_wrench)
    err = est - true_net_wrench(truth)
    err_instant = est - true_net_wrench_instant(truth)
    both = solution.active & np.asarray(truth.contact_active, bool) & ok[:, None]
    d = (solution.nominal_normal - true_normal_forces(truth))[both]
    sos_true = np.einsum("tki,tki->t", truth.contact_force, truth.contact_force)
    free = ok & (solution.env_active == 0) & (np.linalg.norm(truth.env_force, axis=1) == 0)
    free &= solution.active.any(axis=1)
    tol = 1e-6 * (1.0 + sos_true)
    nan = float("nan")
    fallbacks = sum(solution.count(s) for s in FALLBACKS)

    def rms(x):
        return float(np.sqrt(np.mean(np.sum(x**2, axis=1)))) if x.size else nan

    return {
        "net_force_err_n_rms": rms(err[ok, :3]),
        "net_torque_err_nm_rms": rms(err[ok, 3:]),
        "net_force_err_n_rms_instant": rms(err_instant[ok, :3]),
        "nominal_normal_err_n_mean": float(d.mean()) if d.size else nan,
        "nominal_normal_err_n_std": float(d.std()) if d.size else nan,
        "true_normal_n_mean": float(true_normal_forces(truth)[both].mean()) if d.size else nan,
        "nominal_normal_n_mean": float(solution.nominal_normal[both].mean()) if d.size else nan,
        "sos_true_not_below_nominal_frac": float(np.mean(sos_true[free] >= solution.sum_of_squares[free] - tol[free]))
        if free.any() else nan,
        "sos_frames": int(free.sum()),
        "solver_failures": fallbacks,
        "fallback_frac": fallbacks / max(len(solution) - solution.count(FrameStatus.NO_KINEMATICS), 1),
        "status": {s.name.lower(): solution.count(s) for s in FrameStatus},
        "frames_scored": int(ok.sum()),
    }


def sensitivity(
    kinematics: Kinematics,
    true_contacts: Contacts,
    vision_contacts: Contacts,
    model: ObjectModel,
    *,
    gravity=(0.0, 0.0, -9.81),
    settings: ForceSettings | None = None,
) -> dict:
    """Nominal forces with vision contact points minus with true ones (§4.2), same kinematics.

    Returns:
        ``normal_diff_n_mean`` and ``normal_diff_n_std`` (per finger normal force, pooled),
        ``force_diff_n_rms`` (Euclidean norm of the per-finger force difference, RMS) and ``pairs``.
    """
    a = nominal_forces(kinematics, vision_contacts, model, gravity=gravity, settings=settings)
    b = nominal_forces(kinematics, true_contacts, model, gravity=gravity, settings=settings)
    both = a.active & b.active & scored_frames(a)[:, None] & scored_frames(b)[:, None]
    d = (a.normal_force - b.normal_force)[both]
    v = np.linalg.norm(a.force - b.force, axis=-1)[both]
    nan = float("nan")
    return {
        "normal_diff_n_mean": float(d.mean()) if d.size else nan,
        "normal_diff_n_std": float(d.std()) if d.size else nan,
        "force_diff_n_rms": float(np.sqrt(np.mean(v**2))) if v.size else nan,
        "pairs": int(d.size),
    }
