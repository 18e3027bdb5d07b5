"""Aggregates of per-episode metrics over a suite: medians and means with 95 % bootstrap intervals."""

from __future__ import annotations

import numpy as np
from scipy import stats

CONFIDENCE = 0.95
RESAMPLES = 2000
BOOTSTRAP_SEED = 0  # the intervals are a deterministic function of the scores


def span(values, missing: str = "-") -> str:
    """``median (min-max)`` of the finite values, to three significant digits (``missing`` if none)."""
    v = np.asarray([x for x in values if x is not None and np.isfinite(x)], dtype=float)
    if not len(v):
        return missing
    return f"{np.median(v):.3g} ({v.min():.3g}-{v.max():.3g})"


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


MIN_PAIRED_EPISODES = 6
"""Fewest paired episodes (non-zero differences) with which a two-sided Wilcoxon signed-rank test can
reach p < 0.05: its smallest p with n pairs is 2 / 2^n (0.0625 with 5, 0.031 with 6)."""

FEW_EPISODES = 10
"""Below this many episodes a bootstrap interval is little more than the values' range: reports
label such intervals "few episodes"."""


def paired_test(differences) -> dict:
    """Wilcoxon's signed-rank test of paired per-episode differences (exact for up to 50 pairs).

    Returns:
        ``{"n", "p", "median_diff"}``: ``n`` the non-zero finite differences (ties at zero are
        dropped, Wilcoxon's rule); ``p`` the two-sided p-value, or None when ``n`` is below
        :data:`MIN_PAIRED_EPISODES` (too few episodes for any verdict at 95 %); the median difference.
    """
    d = np.asarray([v for v in differences if v is not None and np.isfinite(v)], dtype=float)
    nonzero = d[d != 0]
    median = float(np.median(d)) if d.size else None
    if nonzero.size < MIN_PAIRED_EPISODES:
        return {"n": int(nonzero.size), "p": None, "median_diff": median}
    method = "exact" if nonzero.size <= 50 else "approx"
    p = float(stats.wilcoxon(nonzero, alternative="two-sided", method=method).pvalue)
    return {"n": int(nonzero.size), "p": p, "median_diff": median}
