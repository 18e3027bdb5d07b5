"""The per-episode metrics by name (:data:`METRICS`) and the value each counts at when it cannot be
computed (:data:`WORST`); :func:`benchmark.scores.episode.score_episode` computes them."""

from __future__ import annotations

FORCE_METRICS = ("force_mae_n", "force_rmse_n", "force_normal_mae_n", "force_tangential_mae_n", "peak_force_err_n")
"""The final forces' errors in newtons in the peers' forms (:mod:`benchmark.scores.contact_forces`):
per-contact MAE and RMSE of the 3D force over the truth's contacts (EgoPHI's form), its normal and
tangential parts apart, and the absolute error of the episode's peak hand force (the Hoi! challenge's
form: the mean over episodes is its MAE)."""

NOMINAL_FORCE_METRICS = tuple(f"nominal_{m}" for m in FORCE_METRICS)
"""The same errors of the nominal forces (eq. 4-6: no internal forces)."""

METRICS = ("box_pos_err_mm", "box_rot_err_deg", "contact_err_mm_mean", "contact_err_mm_std", "contact_recall",
           "contact_precision", "acc_err_rms", "gyro_err_rms", "net_force_err_n_rms", "net_force_err_n_rms_instant",
           "net_torque_err_nm_rms", "least_violation_frac", "learned_rel_err_pct", "learned_mae_n",
           "learned_rel_err_pct_paper", *FORCE_METRICS, *NOMINAL_FORCE_METRICS)
"""Names of the per-episode metrics, in report order."""

WORST = {**{m: float("inf") for m in METRICS}, "contact_recall": 0.0, "contact_precision": 0.0,
         "least_violation_frac": 1.0, "contact_err_mm_mean": None}
"""The value at which an episode counts in an aggregate when its metric cannot be computed (NaN: a
stage with nothing to score, no valid frame, an overflow): +inf for an error, 0 for recall and
precision, 1 for the fallback fraction. The signed contact bias has no worst value: one such
episode leaves its aggregate undefined (null; a gate on it fails). docs/suites.md, "Every episode
counts"."""
