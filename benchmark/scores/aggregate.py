"""Aggregates of per-episode metrics over a suite: medians and means with 95 % bootstrap intervals."""

from __future__ import annotations

import numpy as np
from scipy import stats

CONFIDENCE = 0.95
RESAMPLES = 2000
BOOTSTRAP_SEED = 0  # the intervals are a deterministic function of the scores


def aggregate(values, statistic: str) -> dict:
    """A statistic of per-episode values with its percentile-bootstrap confidence interval.

    Args:
        values: One value per episode; NaN entries (a stage with nothing to score) are left out.
        statistic: ``"median"`` or ``"mean"``.

    Returns:
        ``{"value", "ci_low", "ci_high", "n"}``; with fewer than two finite values the interval is
        the value itself (nothing to resample), and with none every entry is None.
    """
    fn = {"median": np.median, "mean": np.mean}[statistic]
    x = np.asarray([v for v in values if v is not None and np.isfinite(v)], dtype=float)
    if x.size == 0:
        return {"value": None, "ci_low": None, "ci_high": None, "n": 0}
    value = float(fn(x))
    if x.size < 2 or np.all(x == x[0]):
        return {"value": value, "ci_low": value, "ci_high": value, "n": int(x.size)}
    res = stats.bootstrap((x,), fn, confidence_level=CONFIDENCE, n_resamples=RESAMPLES, method="percentile",
                          rng=np.random.default_rng(BOOTSTRAP_SEED))
    ci = res.confidence_interval
    return {"value": value, "ci_low": float(ci.low), "ci_high": float(ci.high), "n": int(x.size)}


def aggregate_all(rows: list[dict], metrics, by: str | None = None) -> dict:
    """Median and mean of every metric over ``rows`` (per-episode dicts), optionally per ``by`` value.

    Returns:
        ``{metric: {"median": aggregate, "mean": aggregate}}``, or ``{group: that}`` with ``by``.
    """
    if by is not None:
        groups = sorted({r[by] for r in rows})
        return {g: aggregate_all([r for r in rows if r[by] == g], metrics) for g in groups}
    return {m: {s: aggregate([r[m] for r in rows], s) for s in ("median", "mean")} for m in metrics}
