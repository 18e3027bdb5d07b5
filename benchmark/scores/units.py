"""The unit of every per-episode metric (:data:`benchmark.scores.episode.METRICS`), as reports print them."""

from __future__ import annotations

from benchmark.scores.metrics import FORCE_METRICS, NOMINAL_FORCE_METRICS

UNITS = {"box_pos_err_mm": "mm", "box_rot_err_deg": "deg", "contact_err_mm_mean": "mm", "contact_err_mm_std": "mm",
         "contact_recall": "", "contact_precision": "", "acc_err_rms": "m/s²", "gyro_err_rms": "rad/s",
         "net_force_err_n_rms": "N", "net_force_err_n_rms_instant": "N", "net_torque_err_nm_rms": "N m",
         "least_violation_frac": "", "learned_rel_err_pct": "%", "learned_mae_n": "N",
         "learned_rel_err_pct_paper": "%", **{m: "N" for m in (*FORCE_METRICS, *NOMINAL_FORCE_METRICS)}}
"""Each metric's unit ("" for a fraction of frames or contacts)."""


def labelled(metric: str) -> str:
    """A metric's name with its unit, as reports print it: ``acc_err_rms [m/s²]``."""
    unit = UNITS.get(metric, "")
    return f"{metric} [{unit}]" if unit else metric
