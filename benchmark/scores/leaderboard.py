"""A leaderboard: several methods' aggregates on one suite, one row per method, as Markdown."""

from __future__ import annotations

import numpy as np

from benchmark.scores.aggregate import span

COLUMNS = (
    ("box_pos_err_mm", "median", "box [mm]"),
    ("contact_err_mm_std", "median", "contact std [mm]"),
    ("contact_recall", "median", "recall"),
    ("acc_err_rms", "median", "acc RMS [m/s²]"),
    ("net_force_err_n_rms", "median", "net force [N]"),
    ("net_force_err_n_rms_instant", "median", "net force, instant [N]"),
    ("least_violation_frac", "mean", "least-violation frames"),
    ("learned_rel_err_pct", "median", "learned [%]"),
    ("learned_mae_n", "median", "MAE [N]"),
    ("learned_rel_err_pct_paper", "median", "learned, paper's rule [%]"),
    ("force_mae_n", "mean", "per-contact MAE [N]"),
    ("force_rmse_n", "mean", "per-contact RMSE [N]"),
    ("force_normal_mae_n", "mean", "normal MAE [N]"),
    ("force_tangential_mae_n", "mean", "tangential MAE [N]"),
    ("peak_force_err_n", "mean", "peak-force MAE [N]"),
)
"""The leaderboard's columns: metric, statistic, header. The final forces' errors in newtons
(:mod:`benchmark.scores.contact_forces`) are means over the episodes, as the peers report theirs
(the peak force's mean absolute error over clips is the Hoi! challenge's number)."""


def _cell(agg: dict) -> str:
    if agg["value"] is None:
        return "—"
    v, lo, hi = agg["value"], agg["ci_low"], agg["ci_high"]
    return f"{v:.3g} [{lo:.3g}, {hi:.3g}]"


def leaderboard_markdown(suite, entries: list, baseline_stage: dict | None = None) -> str:
    """A Markdown table of ``entries`` (``(name, scores.json content)``) on ``suite``.

    Each cell is the statistic over the suite's episodes with its 95 % bootstrap interval; the last
    column counts the suite's gates that hold. With ``baseline_stage`` (baseline name -> the stage
    it stands in for) a second table gives every method's skill against its stage's best baseline.
    """
    head = "| method | " + " | ".join(f"{h} ({s})" for _, s, h in COLUMNS) + " | gates |"
    lines = [f"# Leaderboard: {suite.name} (version {suite.version}, {len(suite.scenarios)} episodes)", "",
             suite.description, "",
             "Each cell: the statistic over the episodes [95 % bootstrap interval]. 'oracle' marks inputs "
             "taken from the truth (ablations, not methods).", "", head,
             "|" + "---|" * (len(COLUMNS) + 2)]
    for name, scores in entries:
        agg = scores["aggregate"]
        held = sum(g["passed"] for g in scores["gates"])
        cells = " | ".join(_cell(agg[m][s]) for m, s, _ in COLUMNS)
        lines.append(f"| {name} | {cells} | {held}/{len(scores['gates'])} |")
    lines += skill_table(entries, baseline_stage or {})
    lines += spread_table(entries)
    lines += ["", "Methods:", ""]
    lines += [f"- **{name}**: {scores['method']}" for name, scores in entries]
    return "\n".join(lines) + "\n"


HIGHER_IS_BETTER = ("contact_recall", "contact_precision")


def skill(value: float | None, best_baseline: float | None, metric: str) -> float | None:
    """A method's skill against the best baseline: 1 - error / the baseline's error (1 perfect, 0 no
    better than the trivial method, below 0 worse); for recall and precision (higher is better)
    (value - baseline) / (1 - baseline). None where either is missing or the baseline is perfect."""
    if value is None or best_baseline is None:
        return None
    if metric in HIGHER_IS_BETTER:
        return None if best_baseline >= 1.0 else (value - best_baseline) / (1.0 - best_baseline)
    return None if best_baseline <= 0.0 else 1.0 - value / best_baseline


METRIC_STAGE = {"box_pos_err_mm": "tracker", "contact_err_mm_std": "tracker", "contact_recall": "tracker",
                "acc_err_rms": "differentiator", "net_force_err_n_rms": "forces", "net_force_err_n_rms_instant": "forces",
                "least_violation_frac": "forces", "learned_rel_err_pct": "internal", "learned_mae_n": "internal",
                "learned_rel_err_pct_paper": "internal",
                **{m: "internal" for m in ("force_mae_n", "force_rmse_n", "force_normal_mae_n", "force_tangential_mae_n",
                                           "peak_force_err_n")}}
"""The stage whose output each column scores: its baselines are the ones a method's skill is measured against."""


def skill_table(entries: list, baseline_stage: dict) -> list:
    """Lines of a Markdown table: per metric the best of the baselines standing in for the metric's
    stage (rows ``baseline-<name>``, ``baseline_stage``: name -> stage), then every other method's
    skill against it."""
    baselines = [(n, s) for n, s in entries if n.startswith("baseline-")]
    if not baselines:
        return []
    best = {}
    for m, st, _ in COLUMNS:
        values = [(s["aggregate"][m][st]["value"], n) for n, s in baselines
                  if s["aggregate"][m][st]["value"] is not None and baseline_stage.get(n[9:]) == METRIC_STAGE[m]]
        pick = max if m in HIGHER_IS_BETTER else min
        best[m] = pick(values) if values else (None, None)
    lines = ["", "Skill against the best baseline of the metric's stage (the static box for the tracker's "
             "metrics, zero kinematics for the acceleration, gravity-only forces for the net force and "
             "least-violation frames, no internal forces or the grip line alone for the learned forces): "
             "1 - statistic / the baseline's (recall: (statistic - baseline) / (1 - baseline)); 1 is "
             "perfect, 0 no better than the trivial method, below 0 worse.", "",
             "| | " + " | ".join(h for _, _, h in COLUMNS) + " |", "|" + "---|" * (len(COLUMNS) + 1),
             "| best baseline | " + " | ".join("—" if best[m][0] is None else f"{best[m][0]:.3g} ({best[m][1][9:]})"
                                               for m, _, _ in COLUMNS) + " |"]
    for name, scores in entries:
        if name.startswith("baseline-"):
            continue
        cells = []
        for m, st, _ in COLUMNS:
            k = skill(scores["aggregate"][m][st]["value"], best[m][0], m)
            cells.append("—" if k is None else f"{k:.2f}")
        lines.append(f"| {name} | " + " | ".join(cells) + " |")
    return lines



SPREAD = (("learned_rel_err_pct", "learned [%]"), ("contact_err_mm_std", "contact std [mm]"),
          ("net_force_err_n_rms", "net force [N]"))
"""The metrics whose spread over people and grasp families the leaderboard shows."""


def spread_table(entries: list) -> list:
    """Lines of a Markdown table: the first method's per-episode values per grasp family (each
    episode's ``grasp_family``), median (min-max), and over people (every episode a person of its
    own in the split suites: the quartiles of the episodes)."""

    if not entries or not all("grasp_family" in r for r in entries[0][1]["episodes"]):
        return []
    name, scores = entries[0]
    rows = scores["episodes"]
    people = len({r["scenario"]["user"] for r in rows})
    lines = ["", f"Spread of **{name}** over grasp families and people ({people} people in {len(rows)} episodes): "
             "median (min-max) of the episodes' values.", "",
             "| grasp family | episodes | " + " | ".join(h for _, h in SPREAD) + " |", "|---|---|" + "---|" * len(SPREAD)]
    for family in sorted({r["grasp_family"] for r in rows}):
        sub = [r for r in rows if r["grasp_family"] == family]
        lines.append(f"| {family} | {len(sub)} | " + " | ".join(span((r.get(m) for r in sub), "—") for m, _ in SPREAD) + " |")
    lines.append(f"| every family | {len(rows)} | " + " | ".join(span((r.get(m) for r in rows), "—") for m, _ in SPREAD) + " |")
    per_person = {}
    for r in rows:
        if r.get("learned_rel_err_pct") is not None and np.isfinite(r["learned_rel_err_pct"]):
            per_person.setdefault(r["scenario"]["user"], []).append(r["learned_rel_err_pct"])
    if per_person:
        means = {u: float(np.mean(v)) for u, v in per_person.items()}
        q1, q2, q3 = np.percentile(list(means.values()), [25, 50, 75])
        worst = max(means, key=means.get)
        lines += ["", f"Learned forces per person: quartiles {q1:.3g} / {q2:.3g} / {q3:.3g} %; the worst person "
                      f"{worst} at {means[worst]:.3g} %."]
    return lines
