"""Aggregates of per-episode metrics over a suite: medians, means and 90th percentiles (the tail) with
95 % bootstrap intervals, over every episode (a metric that could not be computed counts at its worst
value)."""

from __future__ import annotations

import numpy as np

from benchmark.scores.metrics import WORST

CONFIDENCE = 0.95
RESAMPLES = 2000
BOOTSTRAP_SEED = 0  # the intervals are a deterministic function of the scores


def p90(x, axis=None):
    """The 90th percentile by nearest rank (the smallest value with at least 90 % of the values at or
    below it: no interpolation, so an episode at an infinite worst value gives +inf, never NaN).

    Args:
        x: Values, any shape.
        axis: Reduced axis (None: all).
    """
    return np.percentile(x, 90, axis=axis, method="inverted_cdf")


STATISTICS = {"median": np.median, "mean": np.mean, "p90": p90}
"""The statistics a gate or a report takes over a suite's episodes, by name: the median (a typical
episode), the mean, and the 90th percentile (the tail: one episode in ten is worse)."""


def _stats():
    """``scipy.stats``, imported where an interval or a test is computed."""
    from scipy import stats  # lazy: scipy.stats (0.4 s of CPU) off `fsv-bench`'s start-up: one episode has no interval

    return stats


def span(values, missing: str = "-") -> str:
    """``median (min-max)`` of the finite values, to three significant digits (``missing`` if none)."""
    v = np.asarray([x for x in values if x is not None and np.isfinite(x)], dtype=float)
    if not len(v):
        return missing
    return f"{np.median(v):.3g} ({v.min():.3g}-{v.max():.3g})"


def aggregate(values, statistic: str, worst: float | None = None) -> dict:
    """A statistic of per-episode values with its percentile-bootstrap confidence interval; every
    episode counts.

    Args:
        values: One value per episode. None or NaN (a metric that could not be computed) counts as
            ``worst``, never left out; so does an infinite value where ``worst`` is finite (a rate).
        statistic: A name of :data:`STATISTICS` (``"median"``, ``"mean"``, ``"p90"``).
        worst: The metric's worst value (:data:`benchmark.scores.episode.WORST`); None: the
            statistic is undefined when any value is missing.

    Returns:
        ``{"value", "ci_low", "ci_high", "n", "at_worst"}``: ``n`` is every value's count,
        ``at_worst`` how many were missing or not finite; with fewer than two values, or all equal,
        the interval is the value itself; the value is None when nothing can be said (no values, or
        a missing one without a worst value). An infinite ``worst`` keeps the statistic and interval
        deterministic: +inf where the worst values reach them.
    """
    if statistic not in STATISTICS:
        raise ValueError(f"statistic {statistic!r} is not one of {', '.join(STATISTICS)}")
    fn = STATISTICS[statistic]
    raw = np.asarray([np.nan if v is None else v for v in values], dtype=float)
    missing = np.isnan(raw) if worst is None or np.isinf(worst) else ~np.isfinite(raw)
    n, at_worst = int(raw.size), int((~np.isfinite(raw)).sum())
    none = {"value": None, "ci_low": None, "ci_high": None, "n": n, "at_worst": at_worst}
    if n == 0 or (missing.any() and worst is None):
        return none
    x = np.where(missing, worst, raw) if missing.any() else raw
    with np.errstate(invalid="ignore"):
        value = float(fn(x))
    if np.isnan(value):  # +inf and -inf together (a signed metric's overflows): no statistic
        return none
    if x.size < 2 or np.all(x == x[0]):
        return {"value": value, "ci_low": value, "ci_high": value, "n": n, "at_worst": at_worst}
    if np.isfinite(x).all():
        res = _stats().bootstrap((x,), fn, confidence_level=CONFIDENCE, n_resamples=RESAMPLES, method="percentile",
                              rng=np.random.default_rng(BOOTSTRAP_SEED))
        low, high = res.confidence_interval
    else:
        low, high = _bootstrap_with_infinities(x, fn)
    return {"value": value, "ci_low": float(low), "ci_high": float(high), "n": n, "at_worst": at_worst}


def _bootstrap_with_infinities(x: np.ndarray, fn) -> tuple:
    """The percentile-bootstrap interval of ``fn`` over values some of which are +inf (NumPy's
    percentile interpolates inf - inf to NaN: here two equal neighbours give themselves)."""
    rng = np.random.default_rng(BOOTSTRAP_SEED)
    with np.errstate(invalid="ignore"):
        theta = np.sort(fn(x[rng.integers(0, x.size, size=(RESAMPLES, x.size))], axis=1))
    alpha = (1.0 - CONFIDENCE) / 2.0
    out = []
    for q in (alpha, 1.0 - alpha):
        pos = q * (RESAMPLES - 1)
        frac = pos - np.floor(pos)
        lo, hi = theta[int(np.floor(pos))], theta[int(np.ceil(pos))]
        out.append(lo if frac == 0 or lo == hi else (hi if np.isinf(hi) else lo if np.isinf(lo)
                                                     else lo + (hi - lo) * frac))
    return tuple(out)


def aggregate_all(rows: list[dict], metrics, by: str | None = None) -> dict:
    """Every statistic of :data:`STATISTICS` of every metric over ``rows`` (per-episode dicts),
    optionally per ``by`` value; every row counts, a missing metric at its
    :data:`~benchmark.scores.episode.WORST` value.

    Returns:
        ``{metric: {"median": aggregate, "mean": aggregate, "p90": aggregate}}``, or ``{group: that}``
        with ``by``.
    """
    if by is not None:
        groups = sorted({r[by] for r in rows})
        return {g: aggregate_all([r for r in rows if r[by] == g], metrics) for g in groups}
    return {m: {s: aggregate([r.get(m) for r in rows], s, WORST.get(m)) for s in STATISTICS} for m in metrics}


MIN_PAIRED_EPISODES = 6
"""Fewest paired episodes (non-zero differences) with which a two-sided Wilcoxon signed-rank test can
reach p < 0.05: its smallest p with n pairs is 2 / 2^n (0.0625 with 5, 0.031 with 6)."""

FEW_EPISODES = 10
"""Below this many episodes a bootstrap interval is little more than the values' range: reports
label such intervals "few episodes"."""


def paired_test(differences) -> dict:
    """Wilcoxon's signed-rank test of paired per-episode differences (exact for up to 50 pairs).

    Args:
        differences: One per episode; None or NaN (no difference defined) is left out, an infinite
            one (one side at its worst value) ranks beyond every finite one.

    Returns:
        ``{"n", "p", "median_diff"}``: ``n`` the non-zero differences (ties at zero are dropped,
        Wilcoxon's rule); ``p`` the two-sided p-value, or None when ``n`` is below
        :data:`MIN_PAIRED_EPISODES` (too few episodes for any verdict at 95 %); the median difference.
    """
    d = np.asarray([v for v in differences if v is not None and not np.isnan(v)], dtype=float)
    nonzero = d[d != 0]
    median = float(np.median(d)) if d.size else None
    if nonzero.size < MIN_PAIRED_EPISODES:
        return {"n": int(nonzero.size), "p": None, "median_diff": median}
    finite = nonzero[np.isfinite(nonzero)]
    beyond = 2.0 * (np.abs(finite).max() if finite.size else 1.0) + 1.0  # the test sees ranks and signs only
    ranked = np.where(np.isinf(nonzero), np.sign(nonzero) * beyond, nonzero)
    method = "exact" if nonzero.size <= 50 else "approx"
    p = float(_stats().wilcoxon(ranked, alternative="two-sided", method=method).pvalue)
    return {"n": int(nonzero.size), "p": p, "median_diff": median}
