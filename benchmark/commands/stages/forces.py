"""The forces stage: the method's nominal forces against the truth (the paper's §4.2) and Fig. 5."""

from __future__ import annotations

from benchmark.commands.pictures.fig5 import plot_fig5
from benchmark.commands.stage import Picture, Run, Stage, StageResult
from benchmark.scores.forces import PAPER_SENSITIVITY_N, score_forces, sensitivity
from benchmark.scores.frames import rot_in_true_world
from benchmark.world.contact_error import PAPER_CONTACT_ERROR_MM, contacts_from_truth, vision_like_contacts

CONTACT_CHOICES = ("vision", "oracle")


def add_arguments(parser) -> None:
    """Adds ``--contacts {vision,oracle}`` to the command line of ``fsv-bench``."""
    parser.add_argument(
        "--contacts", choices=CONTACT_CHOICES, default="vision",
        help="contacts for the force programs: 'vision' (the tracker's where it ran, else the truth's "
             "moved by the paper's contact error model) or 'oracle' (the truth's; an ablation)",
    )


def estimate_inputs(estimate) -> tuple:
    """The kinematics and contacts the method's force stages used, with labels.

    Both come from the method's estimate (made by the track stage through
    :func:`benchmark.method.run_method`): the differentiated tracked poses and the tracked contacts,
    or the truth's where ``--kinematics oracle`` / ``--contacts oracle`` asked for an ablation.

    Returns:
        ``(kinematics, contacts, labels)`` with labels ``kinematics``, ``contacts`` and ``oracle``
        (the list of inputs taken from the truth).
    """
    oracle = list(estimate.oracle)
    kin_label = "oracle (truth)" if "kinematics" in oracle else f"{estimate.labels['differentiator']} on tracked poses"
    source = "oracle (truth)" if "contacts" in oracle else f"vision ({estimate.labels['tracker']})"
    return estimate.kinematics, estimate.contacts, {"kinematics": kin_label, "contacts": source, "oracle": sorted(oracle)}


def oracle_tag(labels: dict) -> str:
    """``ORACLE ...`` naming the inputs taken from the truth, or ``no oracle input``."""
    return f"ORACLE {', '.join(labels['oracle'])}" if labels["oracle"] else "no oracle input"


def run(record: Run, options) -> StageResult:
    """Nominal forces of the run's estimate: the ``forces`` block, a printed line and Fig. 5."""
    ep, est = record.episode, record.estimate
    kin, contacts, labels = estimate_inputs(est)
    sol = est.nominal
    if sol is None:
        return StageResult(blocks=(("forces", {**labels, "program": None}),),
                           lines=(f"forces: the method has no force stage ({est.labels['forces']})",))
    rot = rot_in_true_world(kin.rot, record.knowledge.world_from_method if record.knowledge else None)
    block = {**labels, "program": est.labels["forces"], **score_forces(sol, ep.truth, rot)}
    truth_contacts = contacts_from_truth(ep.truth)
    vision = vision_like_contacts(truth_contacts, ep.object_model, ep.scenario.rng("contact-error"))
    block["sensitivity"] = {
        **sensitivity(kin, truth_contacts, vision, ep.object_model, gravity=ep.truth.gravity),
        "vision_contacts": f"truth contacts + paper's contact error (mean {PAPER_CONTACT_ERROR_MM['mean']:g} mm, "
                           f"std {PAPER_CONTACT_ERROR_MM['std']:g} mm per axis)",
        "paper": PAPER_SENSITIVITY_N,
    }
    if "contacts" not in est.oracle:
        block["sensitivity_tracker"] = {
            **sensitivity(kin, truth_contacts, est.tracking.contacts, ep.object_model, gravity=ep.truth.gravity),
            "vision_contacts": "the tracker's (fingers and frames where both it and the truth have the contact)",
            "paper": PAPER_SENSITIVITY_N,
        }
    tag = oracle_tag(labels)
    plot = None if options["no_pictures"] else record.out / "forces_fig5.png"
    block["plot"] = None if plot is None else plot.name
    s = block["sensitivity"]
    rescued = {"static_friction": "held by static friction", "contacts_added": "with contacts added"}
    rescued = "".join(f", {block['status'][k]} {what}" for k, what in rescued.items() if block["status"].get(k))
    line = (
        f"forces [{tag}] (kinematics {labels['kinematics']}, contacts {labels['contacts']}): "
        f"net force err {block['net_force_err_n_rms']:.3f} N rms against the frame-mean truth "
        f"({block['net_force_err_n_rms_instant']:.3f} against the instant), net torque err {block['net_torque_err_nm_rms']:.4f} N m rms, "
        f"nominal - true normal {block['nominal_normal_err_n_mean']:+.2f} N mean, {block['solver_failures']} solver failures{rescued}; "
        f"contact-error sensitivity {s['normal_diff_n_mean']:+.3f} ± {s['normal_diff_n_std']:.3f} N "
        f"(paper {PAPER_SENSITIVITY_N['mean']} ± {PAPER_SENSITIVITY_N['std']} N)"
        + (f", with the tracker's contacts {block['sensitivity_tracker']['normal_diff_n_mean']:+.3f} ± "
           f"{block['sensitivity_tracker']['normal_diff_n_std']:.3f} N" if "sensitivity_tracker" in block else "")
        + ("" if plot is None else f"; plot {plot.name}")
    )
    pictures = () if plot is None else (Picture("Fig. 5", plot_fig5, (sol, ep.truth, rot, plot), {
        "learned": est.forces,
        "title": f"forces — kinematics: {labels['kinematics']}; contacts: {labels['contacts']} [{tag}]"}),)
    return StageResult(blocks=(("forces", block),), lines=(line,), pictures=pictures)


STAGE = Stage(name="forces", run=run, options=("no_pictures",), add_arguments=add_arguments)
