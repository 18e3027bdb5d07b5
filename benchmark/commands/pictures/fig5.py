"""A figure like the paper's Fig. 5: per-finger normal forces, the net force and the sums of squares over time."""

from __future__ import annotations

import pathlib

import numpy as np

from benchmark.atomic import save_figure
from benchmark.commands.pictures.layout import Margins
from benchmark.scores.forces import scored_frames, true_net_wrench, true_normal_forces
from benchmark.world.truth import Truth
from fsv.forces import FALLBACKS, SOLVED, ForceSolution, to_world_frame


def robust_limits(*series, margin: float = 0.1) -> tuple:
    """y-limits that show the bulk of the data: from min(0, 1st percentile) to the 99th percentile
    of every finite value, widened to the truth's range (the first series) and by ``margin``.

    An outlier beyond them is drawn at the edge (see :func:`plot_fig5`) instead of setting the scale.
    """
    values = np.concatenate([np.asarray(x, float).ravel() for x in series])
    values = values[np.isfinite(values)]
    if not values.size:
        return 0.0, 1.0
    truth = np.asarray(series[0], float)
    truth = truth[np.isfinite(truth)]
    lo = min(0.0, float(np.percentile(values, 1)), float(truth.min()) if truth.size else 0.0)
    hi = max(float(np.percentile(values, 99)), float(truth.max()) if truth.size else 0.0)
    span = max(hi - lo, 1e-9)
    return lo - margin * span, hi + margin * span


def _clip_outliers(ax, t, y, lim, color) -> int:
    """Marks values of ``y`` beyond ``lim`` with triangles at the axis edge; returns how many."""
    lo, hi = lim
    above, below = np.isfinite(y) & (y > hi), np.isfinite(y) & (y < lo)
    if above.any():
        ax.scatter(np.broadcast_to(t[:, None], y.shape)[above], np.full(above.sum(), hi), marker="^", s=18,
                   color=color, clip_on=False, zorder=4)
    if below.any():
        ax.scatter(np.broadcast_to(t[:, None], y.shape)[below], np.full(below.sum(), lo), marker="v", s=18,
                   color=color, clip_on=False, zorder=4)
    return int(above.sum() + below.sum())


def _mark_frames(ax, t, mask, color, label) -> bool:
    """Shades the runs of frames where ``mask`` holds; returns whether any was shaded."""
    idx = np.flatnonzero(mask)
    if not idx.size:
        return False
    dt = float(np.median(np.diff(t))) if len(t) > 1 else 1.0
    starts = idx[np.r_[True, np.diff(idx) > 1]]
    ends = idx[np.r_[np.diff(idx) > 1, True]]
    for i, (a, b) in enumerate(zip(starts, ends)):
        ax.axvspan(t[a] - dt / 2, t[b] + dt / 2, color=color, alpha=0.18, lw=0, label=label if i == 0 else None)
    return True


def plot_fig5(solution: ForceSolution, truth: Truth, rot: np.ndarray, path, title: str = "",
              learned: ForceSolution | None = None) -> pathlib.Path:
    """A figure like the paper's Fig. 5: per-finger normal forces, net force and sum of squares.

    Per finger: the truth (solid), the nominal forces (dashed) and, when given, the method's final
    forces with learned internal forces (dotted). The net contact force's components (world frame),
    true against estimated. The sums of squares. Frames whose nominal program was infeasible or failed
    are shaded red (and the learned program's, orange). The y-limits follow the bulk of the data
    (:func:`robust_limits`); a value beyond them is drawn as a triangle at the edge, and the number of
    such values is noted in the panel. Written atomically as a PNG.
    """
    import matplotlib  # lazy: matplotlib (0.4 s) off `fsv-bench`'s start-up

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # lazy: matplotlib (0.4 s) off `fsv-bench`'s start-up

    t = truth.t
    fig, axes = plt.subplots(3, 1, figsize=(13, 10), sharex=True)
    ok = scored_frames(solution)
    bad = np.isin(solution.status, [int(s) for s in FALLBACKS])
    fn_true = np.where(truth.contact_active, true_normal_forces(truth), np.nan)
    fn_nom = np.where(solution.active & ok[:, None], solution.nominal_normal, np.nan)
    fn_learn = None
    if learned is not None:
        ok_l = np.isin(learned.status, [int(s) for s in SOLVED])
        fn_learn = np.where(learned.active & ok_l[:, None], learned.normal_force, np.nan)
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for ax in axes:
        _mark_frames(ax, t, bad, "red", "nominal forces: least violation, failed or implausible")
        if learned is not None:
            _mark_frames(ax, t, np.isin(learned.status, [int(s) for s in FALLBACKS]),
                         "orange", "learned forces: least violation or failed")
    _finger_panel(axes[0], t, solution.finger_names, fn_true, fn_nom, fn_learn, colors)
    _net_force_panel(axes[1], t, np.where(ok[:, None], to_world_frame(rot, solution.net_wrench)[:, :3], np.nan),
                     true_net_wrench(truth)[:, :3], colors)
    sos = {"true": np.einsum("tki,tki->t", truth.contact_force, truth.contact_force),
           "nominal (L2-minimal)": np.where(ok, solution.sum_of_squares, np.nan)}
    if learned is not None:
        sos["learned"] = np.where(np.isin(learned.status, [int(s) for s in SOLVED]), learned.sum_of_squares, np.nan)
    _sum_of_squares_panel(axes[2], t, sos)
    if title:
        fig.suptitle(title, fontsize=9)
    MARGINS.apply(fig, titled=bool(title))
    try:
        return save_figure(fig, path)
    finally:
        plt.close(fig)


def _beyond(clipped: int) -> str:
    return f"; {clipped} values beyond the axis drawn as triangles" if clipped else ""


def _finger_panel(ax, t, names, fn_true, fn_nom, fn_learn, colors) -> None:
    """Per finger: the true normal force (solid), the nominal (dashed) and the learned (dotted)."""
    lim = robust_limits(fn_true, fn_nom, *(() if fn_learn is None else (fn_learn,)))
    clipped = 0
    from matplotlib.lines import Line2D  # lazy: matplotlib (0.4 s) off `fsv-bench`'s start-up

    for k, name in enumerate(names):
        c = colors[k % len(colors)]
        ax.plot(t, fn_true[:, k], color=c, lw=1.6)
        ax.plot(t, fn_nom[:, k], color=c, ls="--", lw=1.0)
        clipped += _clip_outliers(ax, t, fn_nom[:, k:k + 1], lim, c)
        if fn_learn is not None:
            ax.plot(t, fn_learn[:, k], color=c, ls=":", lw=1.6)
            clipped += _clip_outliers(ax, t, fn_learn[:, k:k + 1], lim, c)
    ax.set_ylim(*lim)
    ax.set_ylabel("normal force per finger [N]")
    ax.set_title("normal forces: true (solid), nominal (dashed)" + (", learned (dotted)" if fn_learn is not None else "")
                 + _beyond(clipped), fontsize=9)
    # two small legends instead of one entry per digit and estimate: the digits by colour, the estimates by line
    digits = ax.legend(handles=[Line2D([], [], color=colors[k % len(colors)], lw=1.6, label=name)
                                for k, name in enumerate(names)],
                       title="digit", fontsize=7, title_fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    ax.add_artist(digits)
    styles = [("true", "-", 1.6), ("nominal", "--", 1.0)] + ([("learned", ":", 1.6)] if fn_learn is not None else [])
    ax.legend(handles=[Line2D([], [], color="k", ls=ls, lw=lw, label=label) for label, ls, lw in styles],
              fontsize=7, loc="lower left", bbox_to_anchor=(1.01, 0.0))


def _net_force_panel(ax, t, net_est, net_true, colors) -> None:
    """The net contact force's components (world frame), true against estimated."""
    lim = robust_limits(net_true, net_est)
    clipped = 0
    for i, ax_name in enumerate("xyz"):
        c = colors[i]
        ax.plot(t, net_true[:, i], color=c, lw=1.6, label=f"F{ax_name} true (frame mean)")
        ax.plot(t, net_est[:, i], color=c, ls="--", label=f"F{ax_name} estimated (nominal)")
        clipped += _clip_outliers(ax, t, net_est[:, i:i + 1], lim, c)
    ax.set_ylim(*lim)
    ax.set_ylabel("net contact force, world frame [N]")
    ax.set_title("net force of every contact (fingers and table)" + _beyond(clipped), fontsize=9)
    ax.legend(ncol=1, fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))


def _sum_of_squares_panel(ax, t, sos: dict) -> None:
    """The sums of squares of the finger forces (eq. 6): true, nominal, learned."""
    lim = robust_limits(*sos.values())
    clipped = 0
    for (label, y), ls in zip(sos.items(), ("-", "--", ":")):
        ax.plot(t, y, ls=ls, lw=1.6 if ls != "--" else 1.0, color="k" if ls == "-" else None, label=label)
        clipped += _clip_outliers(ax, t, y[:, None], lim, "k")
    ax.set_ylim(*lim)
    ax.set_ylabel("sum over fingers of |F|² [N²]")
    ax.set_title("sum of squares (eq. 6)" + _beyond(clipped), fontsize=9)
    ax.set_xlabel("time [s]")
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))


MARGINS = Margins(left_in=0.7, right_in=1.85, bottom_in=0.6, top_in=0.35, title_in=0.33, wspace=0.2, hspace=0.16)
"""Fig. 5's margins (:mod:`benchmark.commands.pictures.layout`): the legends sit right of the panels;
``tight_layout`` gave 0.63, 1.81, 0.59 in (top 0.63 under a title) and 0.15 on the default lift;
room here for tick labels a digit wider."""
