"""Scores of the force stage against the truth: the paper's §4.2 and Fig. 5.

Metric definitions (docs/design.md):

* Net force / torque error: the resultant of the estimated contact forces (fingers and, where the
  method models it, the table) minus the true resultant contact wrench (fingers and the table)
  averaged over the frame's interval (``Truth.net_wrench_mean``), world frame, torque about the
  centre of mass; ``net_force_err_n_rms`` and ``net_torque_err_nm_rms`` are the root mean square of
  its Euclidean norm over the scored frames (those with an estimate: every status but
  NO_KINEMATICS and FAILED). ``net_force_err_n_rms_instant`` is the same against the instantaneous
  resultant at the frame's time, which also holds contact transients of a few milliseconds (a
  grasp's onset, the table's impact) that no method sampling at the frame rate can resolve.
* Nominal normal force error: per finger and frame where both the truth and the estimate have the
  contact, the nominal normal force minus the true normal force n_k . F_k; ``nominal_normal_err_n_mean``
  is its mean (negative: people grip harder than the L2-minimal grasp, as in the paper's Fig. 5).
* Sum of squares (eq. 6): Σ_k ||F_k||² over the fingers, true and nominal. Since the nominal grasp
  is L2-minimal among those the program allows, the true sum is not below it wherever the true forces
  are feasible for the program (frames where neither the truth nor the estimate has the table).
* ``solver_failures``: frames whose forces are a fallback (:data:`fsv.forces.FALLBACKS`: least
  violation, failed, or above the physical bound); ``fallback_frac`` their fraction of the frames
  with kinematics. Frames solved with static friction for sliding contacts count as solved.
* Sensitivity (§4.2): the nominal forces computed with vision contact points minus those computed
  with the true contact points, same kinematics; per finger normal force, pooled over fingers and
  frames where both have the contact; mean and standard deviation (the paper: 0.216 N, 1.548 N).
"""

from __future__ import annotations

import pathlib

import numpy as np

from benchmark.atomic import save_figure
from benchmark.world.truth import Truth
from fsv import Contacts, Kinematics, ObjectModel
from fsv.forces import FALLBACKS, SOLVED, ForceSettings, ForceSolution, FrameStatus, nominal_forces, to_world_frame
from benchmark.background import background_of

PAPER_SENSITIVITY_N = {"mean": 0.216, "std": 1.548}

_ESTIMATED = (FrameStatus.OPTIMAL, FrameStatus.STATIC_FRICTION, FrameStatus.LEAST_VIOLATION, FrameStatus.NO_CONTACTS)


def true_net_wrench(truth: Truth) -> np.ndarray:
    """The true resultant contact wrench (fingers and table) averaged over each frame's interval,
    world frame, about the COM, (T, 6): what the net force scores compare with."""
    return np.asarray(truth.net_wrench_mean, float)


def true_net_wrench_instant(truth: Truth) -> np.ndarray:
    """Resultant of the true contact forces (fingers and table) at the frame times, world frame, about the COM, (T, 6)."""
    F = np.asarray(truth.contact_force, float)
    fingers = np.concatenate([F.sum(axis=1), np.cross(truth.contact_point, F).sum(axis=1)], axis=1)
    return to_world_frame(truth.box_rot, fingers) + np.concatenate([truth.env_force, truth.env_torque], axis=1)


def true_normal_forces(truth: Truth) -> np.ndarray:
    """Each finger's true normal force n_k . F_k, shape (T, K), [N]; 0 off contact (the scoring reference)."""
    f = np.sum(np.asarray(truth.contact_force, float) * np.asarray(truth.contact_normal, float), axis=-1)
    return np.where(truth.contact_active, f, 0.0)


def scored_frames(solution: ForceSolution) -> np.ndarray:
    """Frames with an estimate (every status but NO_KINEMATICS and FAILED), (T,) bool."""
    return np.isin(solution.status, [int(s) for s in _ESTIMATED])


def score_forces(solution: ForceSolution, truth: Truth, rot: np.ndarray) -> dict:
    """The ``forces`` block of ``summary.json`` (see the module docstring).

    Args:
        solution: Nominal forces of the method.
        truth: The episode's truth.
        rot: The orientation the method used to express its forces in the world, (T, 3, 3).

    Returns:
        ``net_force_err_n_rms``, ``net_torque_err_nm_rms``, ``net_force_err_n_rms_instant``,
        ``nominal_normal_err_n_mean``,
        ``nominal_normal_err_n_std``, ``true_normal_n_mean``, ``nominal_normal_n_mean``,
        ``sos_true_not_below_nominal_frac``, ``sos_frames``, ``solver_failures``, ``status``
        (frames per status name) and ``frames_scored``; NaN where undefined.
    """
    ok = scored_frames(solution)
    est = to_world_frame(rot, solution.net_wrench)
    err = est - true_net_wrench(truth)
    err_instant = est - true_net_wrench_instant(truth)
    both = solution.active & np.asarray(truth.contact_active, bool) & ok[:, None]
    d = (solution.nominal_normal - true_normal_forces(truth))[both]
    sos_true = np.einsum("tki,tki->t", truth.contact_force, truth.contact_force)
    free = ok & (solution.env_active == 0) & (np.linalg.norm(truth.env_force, axis=1) == 0)
    free &= solution.active.any(axis=1)
    tol = 1e-6 * (1.0 + sos_true)
    nan = float("nan")
    fallbacks = sum(solution.count(s) for s in FALLBACKS)

    def rms(x):
        return float(np.sqrt(np.mean(np.sum(x**2, axis=1)))) if x.size else nan

    return {
        "net_force_err_n_rms": rms(err[ok, :3]),
        "net_torque_err_nm_rms": rms(err[ok, 3:]),
        "net_force_err_n_rms_instant": rms(err_instant[ok, :3]),
        "nominal_normal_err_n_mean": float(d.mean()) if d.size else nan,
        "nominal_normal_err_n_std": float(d.std()) if d.size else nan,
        "true_normal_n_mean": float(true_normal_forces(truth)[both].mean()) if d.size else nan,
        "nominal_normal_n_mean": float(solution.nominal_normal[both].mean()) if d.size else nan,
        "sos_true_not_below_nominal_frac": float(np.mean(sos_true[free] >= solution.sum_of_squares[free] - tol[free]))
        if free.any() else nan,
        "sos_frames": int(free.sum()),
        "solver_failures": fallbacks,
        "fallback_frac": fallbacks / max(len(solution) - solution.count(FrameStatus.NO_KINEMATICS), 1),
        "status": {s.name.lower(): solution.count(s) for s in FrameStatus},
        "frames_scored": int(ok.sum()),
    }


def sensitivity(
    kinematics: Kinematics,
    true_contacts: Contacts,
    vision_contacts: Contacts,
    model: ObjectModel,
    *,
    gravity=(0.0, 0.0, -9.81),
    settings: ForceSettings | None = None,
) -> dict:
    """Nominal forces with vision contact points minus with true ones (§4.2), same kinematics.

    Returns:
        ``normal_diff_n_mean`` and ``normal_diff_n_std`` (per finger normal force, pooled),
        ``force_diff_n_rms`` (Euclidean norm of the per-finger force difference, RMS) and ``pairs``.
    """
    a = nominal_forces(kinematics, vision_contacts, model, gravity=gravity, settings=settings)
    b = nominal_forces(kinematics, true_contacts, model, gravity=gravity, settings=settings)
    both = a.active & b.active & scored_frames(a)[:, None] & scored_frames(b)[:, None]
    d = (a.normal_force - b.normal_force)[both]
    v = np.linalg.norm(a.force - b.force, axis=-1)[both]
    nan = float("nan")
    return {
        "normal_diff_n_mean": float(d.mean()) if d.size else nan,
        "normal_diff_n_std": float(d.std()) if d.size else nan,
        "force_diff_n_rms": float(np.sqrt(np.mean(v**2))) if v.size else nan,
        "pairs": int(d.size),
    }


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
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = truth.t
    K = len(solution.finger_names)
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
    lim = robust_limits(fn_true, fn_nom, *(() if fn_learn is None else (fn_learn,)))
    clipped = 0
    for k in range(K):
        c = colors[k % len(colors)]
        name = solution.finger_names[k]
        axes[0].plot(t, fn_true[:, k], color=c, lw=1.6, label=f"{name}: true")
        axes[0].plot(t, fn_nom[:, k], color=c, ls="--", lw=1.0, label=f"{name}: nominal")
        clipped += _clip_outliers(axes[0], t, fn_nom[:, k:k + 1], lim, c)
        if fn_learn is not None:
            axes[0].plot(t, fn_learn[:, k], color=c, ls=":", lw=1.6, label=f"{name}: learned")
            clipped += _clip_outliers(axes[0], t, fn_learn[:, k:k + 1], lim, c)
    axes[0].set_ylim(*lim)
    axes[0].set_ylabel("normal force per finger [N]")
    axes[0].set_title("normal forces: true (solid), nominal (dashed)" + (", learned (dotted)" if learned is not None else "")
                      + (f"; {clipped} values beyond the axis drawn as triangles" if clipped else ""), fontsize=9)
    axes[0].legend(ncol=1, fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    net_est = np.where(ok[:, None], to_world_frame(rot, solution.net_wrench)[:, :3], np.nan)
    net_true = true_net_wrench(truth)[:, :3]
    lim = robust_limits(net_true, net_est)
    clipped = 0
    for i, ax_name in enumerate("xyz"):
        c = colors[i]
        axes[1].plot(t, net_true[:, i], color=c, lw=1.6, label=f"F{ax_name} true (frame mean)")
        axes[1].plot(t, net_est[:, i], color=c, ls="--", label=f"F{ax_name} estimated (nominal)")
        clipped += _clip_outliers(axes[1], t, net_est[:, i:i + 1], lim, c)
    axes[1].set_ylim(*lim)
    axes[1].set_ylabel("net contact force, world frame [N]")
    axes[1].set_title("net force of every contact (fingers and table)"
                      + (f"; {clipped} values beyond the axis drawn as triangles" if clipped else ""), fontsize=9)
    axes[1].legend(ncol=1, fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    sos = {"true": np.einsum("tki,tki->t", truth.contact_force, truth.contact_force),
           "nominal (L2-minimal)": np.where(ok, solution.sum_of_squares, np.nan)}
    if learned is not None:
        sos["learned"] = np.where(np.isin(learned.status, [int(s) for s in SOLVED]), learned.sum_of_squares, np.nan)
    lim = robust_limits(*sos.values())
    clipped = 0
    for (label, y), ls in zip(sos.items(), ("-", "--", ":")):
        axes[2].plot(t, y, ls=ls, lw=1.6 if ls != "--" else 1.0, color="k" if ls == "-" else None, label=label)
        clipped += _clip_outliers(axes[2], t, y[:, None], lim, "k")
    axes[2].set_ylim(*lim)
    axes[2].set_ylabel("sum over fingers of |F|² [N²]")
    axes[2].set_title("sum of squares (eq. 6)" + (f"; {clipped} values beyond the axis drawn as triangles" if clipped else ""),
                      fontsize=9)
    axes[2].set_xlabel("time [s]")
    axes[2].legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    if title:
        fig.suptitle(title, fontsize=9)
    fig.tight_layout()
    try:
        return save_figure(fig, path)
    finally:
        plt.close(fig)


# --- the ``forces`` stage of fsv-bench -----------------------------------------------------------

CONTACT_CHOICES = ("vision", "oracle")


def add_arguments(parser) -> None:
    """Adds ``--contacts {vision,oracle}`` to the command line of ``fsv-bench``."""
    parser.add_argument(
        "--contacts", choices=CONTACT_CHOICES, default="vision",
        help="contacts for the force programs: 'vision' (the tracker's where it ran, else the truth's "
             "moved by the paper's contact error model) or 'oracle' (the truth's; an ablation)",
    )


def stage_inputs(run) -> tuple:
    """The kinematics and contacts the method's force stages used in a ``benchmark.commands.cli.Run``, with labels.

    Both come from the method's estimate (``run.estimate``, made by the tracking stage through
    :func:`benchmark.method.run_method`): the differentiated tracked poses and the tracked contacts,
    or the truth's where ``--kinematics oracle`` / ``--contacts oracle`` asked for an ablation.

    Returns:
        ``(kinematics, contacts, labels)`` with labels ``kinematics``, ``contacts`` and ``oracle``
        (the list of inputs taken from the truth).
    """
    est = run.estimate
    oracle = list(est.oracle)
    kin_label = "oracle (truth)" if "kinematics" in oracle else f"{est.labels['differentiator']} on tracked poses"
    source = "oracle (truth)" if "contacts" in oracle else f"vision ({est.labels['tracker']})"
    return est.kinematics, est.contacts, {"kinematics": kin_label, "contacts": source, "oracle": sorted(oracle)}


def run_stage(run) -> None:
    """Nominal forces for the run's episode: the ``forces`` block, a printed line and the Fig. 5 plot."""
    from benchmark.world.contact_error import contacts_from_truth, vision_like_contacts

    ep = run.episode
    kin, contacts, labels = stage_inputs(run)
    sol = run.estimate.nominal
    if sol is None:
        run.summary["forces"] = {**labels, "program": None}
        run.lines.append(f"forces: the method has no force stage ({run.estimate.labels['forces']})")
        return
    block = {**labels, "program": run.estimate.labels["forces"], **score_forces(sol, ep.truth, kin.rot)}
    truth_contacts = contacts_from_truth(ep.truth)
    vision = vision_like_contacts(truth_contacts, ep.object_model, ep.scenario.rng("contact-error"))
    block["sensitivity"] = {
        **sensitivity(kin, truth_contacts, vision, ep.object_model, gravity=ep.truth.gravity),
        "vision_contacts": "truth contacts + paper's contact error (mean -1.55 mm, std 6.13 mm per axis)",
        "paper": PAPER_SENSITIVITY_N,
    }
    tracking = run.estimate.tracking
    if "contacts" not in run.estimate.oracle:
        block["sensitivity_tracker"] = {
            **sensitivity(kin, truth_contacts, tracking.contacts, ep.object_model, gravity=ep.truth.gravity),
            "vision_contacts": "the tracker's (fingers and frames where both it and the truth have the contact)",
            "paper": PAPER_SENSITIVITY_N,
        }
    tag = f"ORACLE {', '.join(labels['oracle'])}" if labels["oracle"] else "no oracle input"
    run.out.mkdir(parents=True, exist_ok=True)
    plot = run.out / "forces_fig5.png"
    background_of(run).process("Fig. 5", plot_fig5, sol, ep.truth, kin.rot, plot, learned=run.estimate.forces,
                           title=f"forces — kinematics: {labels['kinematics']}; contacts: {labels['contacts']} [{tag}]")
    block["plot"] = plot.name
    run.summary["forces"] = block
    s = block["sensitivity"]
    rescued = {"static_friction": "held by static friction", "contacts_added": "with contacts added"}
    rescued = "".join(f", {block['status'][k]} {what}" for k, what in rescued.items() if block["status"].get(k))
    run.lines.append(
        f"forces [{tag}] (kinematics {labels['kinematics']}, contacts {labels['contacts']}): "
        f"net force err {block['net_force_err_n_rms']:.3f} N rms against the frame-mean truth "
        f"({block['net_force_err_n_rms_instant']:.3f} against the instant), net torque err {block['net_torque_err_nm_rms']:.4f} N m rms, "
        f"nominal - true normal {block['nominal_normal_err_n_mean']:+.2f} N mean, {block['solver_failures']} solver failures{rescued}; "
        f"contact-error sensitivity {s['normal_diff_n_mean']:+.3f} ± {s['normal_diff_n_std']:.3f} N "
        f"(paper {PAPER_SENSITIVITY_N['mean']} ± {PAPER_SENSITIVITY_N['std']} N)"
        + (f", with the tracker's contacts {block['sensitivity_tracker']['normal_diff_n_mean']:+.3f} ± "
           f"{block['sensitivity_tracker']['normal_diff_n_std']:.3f} N" if "sensitivity_tracker" in block else "")
        + f"; plot {plot.name}"
    )
