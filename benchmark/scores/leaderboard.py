"""A leaderboard: several methods' aggregates on one suite, one row per method, as Markdown."""

from __future__ import annotations

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
)
"""The leaderboard's columns: metric, statistic, header."""


def _cell(agg: dict) -> str:
    if agg["value"] is None:
        return "—"
    v, lo, hi = agg["value"], agg["ci_low"], agg["ci_high"]
    return f"{v:.3g} [{lo:.3g}, {hi:.3g}]"


def leaderboard_markdown(suite, entries: list) -> str:
    """A Markdown table of ``entries`` (``(name, scores.json content)``) on ``suite``.

    Each cell is the statistic over the suite's episodes with its 95 % bootstrap interval; the last
    column counts the suite's gates that hold.
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
    lines += ["", "Methods:", ""]
    lines += [f"- **{name}**: {scores['method']}" for name, scores in entries]
    return "\n".join(lines) + "\n"
