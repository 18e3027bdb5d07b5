"""Scores of the force stage against the truth: the paper's §4.2 and Fig. 5.

Metric definitions (docs/design.md):

* Net force / torque error: the resultant of the estimated contact forces (fingers and, where the
  method models it, the table) minus the resultant of the true contact forces (fingers and the
  table), world frame, torque about the centre of mass; ``net_force_err_n_rms`` and
  ``net_torque_err_nm_rms`` are the root mean square of its Euclidean norm over the scored frames
  (those with an estimate: every status but NO_KINEMATICS and FAILED).
* Nominal normal force error: per finger and frame where both the truth and the estimate have the
  contact, the nominal normal force minus the true normal force n_k . F_k; ``nominal_normal_err_n_mean``
  is its mean (negative: people grip harder than the L2-minimal grasp, as in the paper's Fig. 5).
* Sum of squares (eq. 6): Σ_k ||F_k||² over the fingers, true and nominal. Since the nominal grasp
  is L2-minimal among those the program allows, the true sum is not below it wherever the true forces
  are feasible for the program (frames where neither the truth nor the estimate has the table).
* ``solver_failures``: frames whose program was infeasible (least-violation answer) or failed.
* Sensitivity (§4.2): the nominal forces computed with vision contact points minus those computed
  with the true contact points, same kinematics; per finger normal force, pooled over fingers and
  frames where both have the contact; mean and standard deviation (the paper: 0.216 N, 1.548 N).
"""

from __future__ import annotations

import pathlib

import numpy as np

from benchmark.atomic import save_figure
from benchmark.truth import Truth
from fsv import Contacts, Kinematics, ObjectModel
from fsv.forces import ForceSettings, ForceSolution, FrameStatus, nominal_forces, to_world_frame

PAPER_SENSITIVITY_N = {"mean": 0.216, "std": 1.548}

_ESTIMATED = (FrameStatus.OPTIMAL, FrameStatus.LEAST_VIOLATION, FrameStatus.NO_CONTACTS)


def true_net_wrench(truth: Truth) -> np.ndarray:
    """Resultant of the true contact forces (fingers and table), world frame, about the COM, (T, 6)."""
    F = np.asarray(truth.contact_force, float)
    fingers = np.concatenate([F.sum(axis=1), np.cross(truth.contact_point, F).sum(axis=1)], axis=1)
    return to_world_frame(truth.box_rot, fingers) + np.concatenate([truth.env_force, truth.env_torque], axis=1)


def true_normal_forces(truth: Truth) -> np.ndarray:
    """The true normal force n_k . F_k per finger, (T, K), [N]; 0 off contact."""
    f = np.einsum("tki,tki->tk", np.asarray(truth.contact_force, float), np.asarray(truth.contact_normal, float))
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
        ``net_force_err_n_rms``, ``net_torque_err_nm_rms``, ``nominal_normal_err_n_mean``,
        ``nominal_normal_err_n_std``, ``true_normal_n_mean``, ``nominal_normal_n_mean``,
        ``sos_true_not_below_nominal_frac``, ``sos_frames``, ``solver_failures``, ``status``
        (frames per status name) and ``frames_scored``; NaN where undefined.
    """
    ok = scored_frames(solution)
    err = to_world_frame(rot, solution.net_wrench) - true_net_wrench(truth)
    both = solution.active & np.asarray(truth.contact_active, bool) & ok[:, None]
    d = (solution.nominal_normal - true_normal_forces(truth))[both]
    sos_true = np.einsum("tki,tki->t", truth.contact_force, truth.contact_force)
    free = ok & (solution.env_active == 0) & (np.linalg.norm(truth.env_force, axis=1) == 0)
    free &= solution.active.any(axis=1)
    tol = 1e-6 * (1.0 + sos_true)
    nan = float("nan")

    def rms(x):
        return float(np.sqrt(np.mean(np.sum(x**2, axis=1)))) if x.size else nan

    return {
        "net_force_err_n_rms": rms(err[ok, :3]),
        "net_torque_err_nm_rms": rms(err[ok, 3:]),
        "nominal_normal_err_n_mean": float(d.mean()) if d.size else nan,
        "nominal_normal_err_n_std": float(d.std()) if d.size else nan,
        "true_normal_n_mean": float(true_normal_forces(truth)[both].mean()) if d.size else nan,
        "nominal_normal_n_mean": float(solution.nominal_normal[both].mean()) if d.size else nan,
        "sos_true_not_below_nominal_frac": float(np.mean(sos_true[free] >= solution.sum_of_squares[free] - tol[free]))
        if free.any() else nan,
        "sos_frames": int(free.sum()),
        "solver_failures": solution.count(FrameStatus.LEAST_VIOLATION) + solution.count(FrameStatus.FAILED),
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


def plot_fig5(solution: ForceSolution, truth: Truth, rot: np.ndarray, path, title: str = "") -> pathlib.Path:
    """A figure like the paper's Fig. 5: per-finger normal forces, net force and sum of squares.

    True (solid) against nominal (dashed) per finger; the net contact force's components (world
    frame) true against estimated; the sums of squares. Written atomically as a PNG.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = truth.t
    K = len(solution.finger_names)
    fig, axes = plt.subplots(3, 1, figsize=(9, 9), sharex=True)
    ok = scored_frames(solution)
    fn_true = np.where(truth.contact_active, true_normal_forces(truth), np.nan)
    fn_nom = np.where(solution.active & ok[:, None], solution.nominal_normal, np.nan)
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for k in range(K):
        c = colors[k % len(colors)]
        axes[0].plot(t, fn_true[:, k], color=c, label=f"{solution.finger_names[k]} (true)")
        axes[0].plot(t, fn_nom[:, k], color=c, ls="--", label=f"{solution.finger_names[k]} (nominal)")
    axes[0].set_ylabel("normal force [N]")
    axes[0].legend(ncol=2, fontsize=7)
    net_est = np.where(ok[:, None], to_world_frame(rot, solution.net_wrench)[:, :3], np.nan)
    net_true = true_net_wrench(truth)[:, :3]
    for i, ax_name in enumerate("xyz"):
        c = colors[i]
        axes[1].plot(t, net_true[:, i], color=c, label=f"F{ax_name} (true)")
        axes[1].plot(t, net_est[:, i], color=c, ls="--", label=f"F{ax_name} (estimate)")
    axes[1].set_ylabel("net contact force [N]")
    axes[1].legend(ncol=3, fontsize=7)
    axes[2].plot(t, np.einsum("tki,tki->t", truth.contact_force, truth.contact_force), label="true")
    axes[2].plot(t, np.where(ok, solution.sum_of_squares, np.nan), ls="--", label="nominal (L2-minimal)")
    axes[2].set_ylabel("sum of squares [N²]")
    axes[2].set_xlabel("time [s]")
    axes[2].legend(fontsize=7)
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
    """The kinematics and contacts the method's force stages used in a ``benchmark.cli.Run``, with labels.

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
    from benchmark.contact_error import contacts_from_truth, vision_like_contacts

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
    plot = plot_fig5(sol, ep.truth, kin.rot, run.out / "forces_fig5.png",
                     title=f"nominal forces — kinematics: {labels['kinematics']}; contacts: {labels['contacts']} [{tag}]")
    block["plot"] = plot.name
    run.summary["forces"] = block
    s = block["sensitivity"]
    run.lines.append(
        f"forces [{tag}] (kinematics {labels['kinematics']}, contacts {labels['contacts']}): "
        f"net force err {block['net_force_err_n_rms']:.3f} N rms, net torque err {block['net_torque_err_nm_rms']:.4f} N m rms, "
        f"nominal - true normal {block['nominal_normal_err_n_mean']:+.2f} N mean, {block['solver_failures']} solver failures; "
        f"contact-error sensitivity {s['normal_diff_n_mean']:+.3f} ± {s['normal_diff_n_std']:.3f} N "
        f"(paper {PAPER_SENSITIVITY_N['mean']} ± {PAPER_SENSITIVITY_N['std']} N)"
        + (f", with the tracker's contacts {block['sensitivity_tracker']['normal_diff_n_mean']:+.3f} ± "
           f"{block['sensitivity_tracker']['normal_diff_n_std']:.3f} N" if "sensitivity_tracker" in block else "")
        + f"; plot {plot.name}"
    )
