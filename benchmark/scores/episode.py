"""Per-episode metrics of every stage of the method, pure functions of (estimate, truth).

Metrics (all floats; NaN where a stage has nothing to score: aggregates count such an episode at
the metric's :data:`benchmark.scores.metrics.WORST` value):

* tracking (:func:`benchmark.scores.tracking.score_tracking`): ``box_pos_err_mm`` and ``box_rot_err_deg``
  (medians over frames), ``contact_err_mm_mean`` / ``contact_err_mm_std`` (per axis, pooled),
  ``contact_recall``, ``contact_precision``;
* kinematics: ``acc_err_rms`` [m/s^2] and ``gyro_err_rms`` [rad/s], the AHRS-frame errors of the
  estimated kinematics against the truth's simulated AHRS over the valid frames (Table 1's signals);
* nominal forces (:func:`benchmark.scores.forces.score_forces`): ``net_force_err_n_rms`` [N] against
  the truth's mean over each frame's interval, ``net_force_err_n_rms_instant`` [N] against the
  instantaneous truth, ``net_torque_err_nm_rms`` [N m], ``least_violation_frac`` (fraction of the frames with kinematics
  whose forces are a fallback: least violation, failed, or above the physical bound);
* learned forces (:func:`benchmark.scores.learned.score_episode`): over every finger-frame where
  the estimate and the truth both have the contact (unsolved frames scored as 0 N, failures not
  gaps), ``learned_rel_err_pct`` (Table 2's relative error, true forces >= 1 N) and
  ``learned_mae_n``, the mean absolute error of the final normal force [N]; and, for comparison
  with the paper, ``learned_rel_err_pct_paper``: the relative error on the frames the paper's
  sample rules keep (they choose by the truth: a secondary column, Table 2's protocol);
* forces in newtons in the peers' forms (:mod:`benchmark.scores.contact_forces`), of the final
  forces (:data:`benchmark.scores.metrics.FORCE_METRICS`) and of the nominal ones (the same names
  prefixed ``nominal_``): ``force_mae_n`` and ``force_rmse_n``, the MAE and RMSE of the 3D finger
  force's error norm over the truth's contacts (a finger the method leaves without force there
  counts as 0 N), ``force_normal_mae_n`` and ``force_tangential_mae_n`` its parts along the true
  normal and across it, and ``peak_force_err_n``, the absolute error of the episode's peak hand
  force ||Σ_k F_k|| [N].
"""

from __future__ import annotations

from dataclasses import asdict

import numpy as np

from benchmark.scores.contact_forces import KEYS, contact_force_errors
from benchmark.scores.forces import score_forces
from benchmark.scores.frames import rot_in_true_world, tracking_in_true_world
from benchmark.scores.learned import score_episode as score_learned
from benchmark.scores.metrics import FORCE_METRICS, METRICS, NOMINAL_FORCE_METRICS
from benchmark.scores.tracking import score_tracking
from benchmark.world.grasp_plan import grasp_spec
from benchmark.world.scenario import episode_name


def score_episode(episode, estimate, world_from_method=None, *, learned: dict | None = None) -> dict:
    """Every metric of one episode.

    Args:
        episode: A rendered ``benchmark.world.episode.Episode`` (its truth is the reference).
        estimate: The method's ``fsv.method.Estimate`` on the episode's camera inputs (learned
            metrics are NaN when it has no final forces).
        world_from_method: Carries the method's world frame into the true one, (4, 4), when the
            method was told the camera with an error (:mod:`benchmark.scores.frames`); None: the same.
        learned: :func:`benchmark.scores.learned.score_episode` of this estimate's final forces,
            if already computed (the main command's learn stage): taken as it is, not computed again.

    Returns:
        ``{metric: float}`` for every name in :data:`METRICS`.
    """

    tr = episode.truth
    t = score_tracking(tracking_in_true_world(estimate.tracking, world_from_method), tr, estimate.contacts)
    out = {
        "box_pos_err_mm": t["box_pos_err_mm"], "box_rot_err_deg": t["box_rot_err_deg"],
        "contact_err_mm_mean": t["contact_err_mm_mean"], "contact_err_mm_std": t["contact_err_mm_std"],
        "contact_recall": t["contact_recall"], "contact_precision": t["contact_precision"],
    }
    out.update(kinematics_errors(estimate.kinematics, tr))
    if estimate.nominal is not None:
        f = score_forces(estimate.nominal, tr, rot_in_true_world(estimate.kinematics.rot, world_from_method))
        out.update(net_force_err_n_rms=f["net_force_err_n_rms"], net_force_err_n_rms_instant=f["net_force_err_n_rms_instant"],
                   net_torque_err_nm_rms=f["net_torque_err_nm_rms"], least_violation_frac=f["fallback_frac"])
    else:
        out.update(net_force_err_n_rms=np.nan, net_force_err_n_rms_instant=np.nan, net_torque_err_nm_rms=np.nan,
                   least_violation_frac=np.nan)
    out.update(learned_errors(episode, estimate, learned))
    out.update(newton_errors(estimate, tr))
    return {k: float(out[k]) for k in METRICS}


def kinematics_errors(kinematics, truth) -> dict:
    """RMS of the AHRS-frame acceleration and angular-velocity errors over the valid frames."""
    acc, gyro = kinematics.imu(truth.gravity)
    v = kinematics.valid
    if not v.any():
        return {"acc_err_rms": np.nan, "gyro_err_rms": np.nan}
    da, dg = acc[v] - truth.imu_acc[v], gyro[v] - truth.imu_gyro[v]
    return {"acc_err_rms": float(np.sqrt(np.mean(da * da))), "gyro_err_rms": float(np.sqrt(np.mean(dg * dg)))}


def learned_errors(episode, estimate, block: dict | None = None) -> dict:
    """The final (learned) forces over every contact frame, and Table 2's error under the paper's rule
    (from ``block``, :func:`benchmark.scores.learned.score_episode` of the estimate, if given)."""
    if estimate.forces is None:
        return {"learned_rel_err_pct": np.nan, "learned_mae_n": np.nan, "learned_rel_err_pct_paper": np.nan}

    if block is None:
        block = score_learned(episode, estimate.forces, estimate.kinematics, estimate.contacts)
    return {"learned_rel_err_pct": block["rel_err_pct_mean"], "learned_mae_n": block["mae_n"],
            "learned_rel_err_pct_paper": block["paper_rule"]["rel_err_pct_mean"]}


def newton_errors(estimate, truth) -> dict:
    """The final and nominal forces' errors in the peers' forms (:mod:`benchmark.scores.contact_forces`),
    NaN for a stage the estimate does not have: ``{metric: float}`` for
    :data:`~benchmark.scores.metrics.FORCE_METRICS` and :data:`~benchmark.scores.metrics.NOMINAL_FORCE_METRICS`."""
    final, nominal = contact_force_errors(estimate.forces, truth), contact_force_errors(estimate.nominal, truth)
    return {**{m: final[k] for m, k in zip(FORCE_METRICS, KEYS, strict=True)},
            **{m: nominal[k] for m, k in zip(NOMINAL_FORCE_METRICS, KEYS, strict=True)}}


def episode_row(episode, estimate, known, protocol: str, *, seconds: float, rendered: bool) -> dict:
    """One episode's row of a suite's scores (``scores.json``'s ``episodes``): which episode, its
    metrics (:func:`score_episode`), what the method was told and how long it took.

    Args:
        episode: A rendered ``benchmark.world.episode.Episode``.
        estimate: The method's ``fsv.Estimate`` on it (run in process, or read from a file).
        known: The ``benchmark.method.knowledge.Knowledge`` the method was given (its calibration
            carries the estimate into the true world).
        protocol: What the method was told of the person ("blind" or "calibrated").
        seconds: Time the episode took, [s].
        rendered: Whether the episode was made for this run (not read from the cache).
    """
    sc = episode.scenario
    return {"episode": episode_name(sc), "task": sc.task, "scenario": asdict(sc),
            "grasp_family": grasp_spec(sc)["family"],
            **score_episode(episode, estimate, known.world_from_method),
            "knowledge": known.record(), "protocol": protocol, "seconds": seconds, "rendered": rendered}
