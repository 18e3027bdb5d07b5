"""Each finger's 3D force against the truth in newtons, in the forms the learned force-from-vision
methods report (EgoPHI's per-contact MAE and RMSE, the Hoi! challenge's peak-force MAE per clip).

Definitions (docs/design.md, "Metric definitions"; docs/suites.md, "Metrics"). T frames, K fingers,
every vector in the box's own (object) frame, where both the estimate (:class:`fsv.forces.ForceSolution`)
and the truth (:class:`benchmark.world.truth.Truth`) hold their finger forces, so no world frame and
no calibration error enters:

* The estimate of finger k at frame t, F̂_k(t) [N], is the method's force where the finger is in
  the method's contact set (``solution.active``) on a solved frame (:data:`fsv.forces.SOLVED`), and
  **0 otherwise**: a finger the method leaves without force in a true contact (a missed contact,
  a frame without kinematics, least violation, failed, implausible) is scored as F̂ = 0, a
  failure, not a gap; the rule of the learned metrics (:mod:`benchmark.scores.learned`).
* Per-contact error e_k(t) = F̂_k(t) - F_k(t) on every **true** contact (finger-frames where the
  truth's ``contact_active`` holds), whatever the method found there; a force the method puts on a
  finger off the truth's contact is not in these (it is in the peak force and the net force):

  - ``mae_n`` = mean ||e||, the Euclidean norm of the 3D error (not per component);
  - ``rmse_n`` = sqrt(mean ||e||²);
  - ``normal_mae_n`` = mean |e . n|, with n the truth's unit contact normal (into the box);
  - ``tangential_mae_n`` = mean ||e - (e . n) n||, the rest (friction plane), so that
    ||e||² = (e . n)² + ||e_t||² on every pair.

  NaN when the truth has no contact in the episode (nothing to score).
* Peak force: the hand's force on the box is the resultant of its fingers' forces,
  H(t) = ||Σ_k F_k(t)|| (what a wrist or handle force sensor reads, the quantity of Hoi!'s
  end-effector forces), the estimate's with the same rule for unscored fingers;
  ``peak_err_n`` = |max_t Ĥ(t) - max_t H(t)| over the episode's frames, the absolute error of the
  episode's peak (the MAE over a suite's episodes is its mean). Always defined when the method
  gave forces (an estimate with no solved frame has the peak 0). Internal forces between the
  fingers cancel in H, those the table balances (a finger pressing the box onto it) do not: the peak
  scores the load the hand carries more than its grip, which the per-contact normal error holds.

The truth is instantaneous at the frame times (as the paper's tactile sensors read it; the learned
metrics' reference too), so transients of a few milliseconds (a grasp's onset, the table's impact)
are in its peak.
"""

from __future__ import annotations

import numpy as np

from benchmark.errors import BenchmarkError
from fsv.forces import SOLVED

KEYS = ("mae_n", "rmse_n", "normal_mae_n", "tangential_mae_n", "peak_err_n")
"""The keys of :func:`contact_force_errors`, in report order."""


def scored_estimate(solution) -> np.ndarray:
    """The estimate's finger forces as scored, (T, K, 3) [N]: the method's force where the finger
    is active on a solved frame, 0 elsewhere (NaN included)."""
    solved = np.isin(np.asarray(solution.status), [int(s) for s in SOLVED])
    use = np.asarray(solution.active, bool) & solved[:, None]
    return np.where(use[..., None], np.nan_to_num(np.asarray(solution.force, float), nan=0.0), 0.0)


def true_forces(truth) -> np.ndarray:
    """The truth's finger forces, (T, K, 3) [N], object frame; 0 off contact."""
    return np.where(np.asarray(truth.contact_active, bool)[..., None], np.asarray(truth.contact_force, float), 0.0)


def hand_force_n(forces: np.ndarray) -> np.ndarray:
    """||Σ_k F_k(t)||, the magnitude of the hand's resultant force on the box, (T,) [N], from (T, K, 3)."""
    s = forces.sum(axis=1)
    return np.sqrt(s[:, 0] * s[:, 0] + s[:, 1] * s[:, 1] + s[:, 2] * s[:, 2])


def contact_force_errors(solution, truth) -> dict:
    """The per-contact and peak-force errors of one method's forces on one episode.

    Args:
        solution: The method's forces (:class:`fsv.forces.ForceSolution`: ``force`` (T, K, 3) [N],
            ``active`` (T, K), ``status`` (T,)), final or nominal; None: every metric NaN.
        truth: The episode's truth (``contact_force`` (T, K, 3) [N], ``contact_normal`` (T, K, 3),
            ``contact_active`` (T, K)).

    Returns:
        ``{key: float}`` for every key of :data:`KEYS` (see the module docstring), and ``pairs``,
        the true finger-frames in contact scored.
    """
    nan = float("nan")
    if solution is None:
        return {**{k: nan for k in KEYS}, "pairs": 0}
    est, ref = scored_estimate(solution), true_forces(truth)
    if est.shape != ref.shape:
        raise BenchmarkError(f"the estimate's forces have shape {est.shape}, the truth's {ref.shape}: "
                         "need the same frames and fingers")
    peak = abs(float(hand_force_n(est).max(initial=0.0)) - float(hand_force_n(ref).max(initial=0.0)))
    on = np.asarray(truth.contact_active, bool)
    e, n = (est - ref)[on], np.asarray(truth.contact_normal, float)[on]
    if not e.size:
        return {**{k: nan for k in KEYS}, "peak_err_n": peak, "pairs": 0}
    sq = e[:, 0] * e[:, 0] + e[:, 1] * e[:, 1] + e[:, 2] * e[:, 2]
    en = e[:, 0] * n[:, 0] + e[:, 1] * n[:, 1] + e[:, 2] * n[:, 2]
    et = e - en[:, None] * n
    return {"mae_n": float(np.mean(np.sqrt(sq))), "rmse_n": float(np.sqrt(np.mean(sq))),
            "normal_mae_n": float(np.mean(np.abs(en))),
            "tangential_mae_n": float(np.mean(np.sqrt(et[:, 0] * et[:, 0] + et[:, 1] * et[:, 1] + et[:, 2] * et[:, 2]))),
            "peak_err_n": peak, "pairs": int(e.shape[0])}
