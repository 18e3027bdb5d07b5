"""The kinematics stage: Table 1 of the episode (its differentiators against the AHRS) and Fig. 4.

Table 1 is scored on the tracked poses where the method tracked, else on tracker-like poses. The
kinematics the later stages score are the method's own (the ``--kinematics`` option chooses them
when the method is built; ``oracle`` is a labelled ablation).
"""

from __future__ import annotations

from benchmark.commands.pictures.fig4 import plot_fig4
from benchmark.commands.stage import Picture, Run, Stage, StageResult
from benchmark.errors import ScenarioError
from benchmark.paper.table1 import PAPER, score_table1
from benchmark.world.motion import CHOICES, DECLARED, observed_poses

FILES = {"markdown": "table1.md", "csv": "table1.csv", "plot": "fig4_kinematics.png"}
"""The files the stage writes into the output folder."""


def add_arguments(parser) -> None:
    """The kinematics stage's ``fsv-bench`` option."""
    parser.add_argument(
        "--kinematics",
        choices=CHOICES,
        default="algebraic",
        help="box kinematics the later stages use: a differentiator on the observed poses, or 'oracle' "
        "(the true kinematics: an ablation, labelled as such in every report)",
    )


def run(record: Run, options) -> StageResult:
    """Table 1 of the run's episode, its files and Fig. 4; which kinematics the later stages use."""
    ep, choice, drawn = record.episode, options["kinematics"], not options["no_pictures"]
    if choice not in CHOICES:
        raise ScenarioError(f"kinematics must be one of {', '.join(CHOICES)}; got {choice!r}")
    estimate = record.estimate
    if estimate is not None and estimate.tracking is not None:
        table, kins = score_table1(ep.truth, estimate.tracking.box, poses_label="tracked poses (fsv.track, from depth)")
    else:
        table, kins = score_table1(ep.truth, observed_poses(ep))
    oracle = choice == "oracle"
    # what the later stages use: the method's differentiator when the method ran (the reference's
    # differentiates tracked poses on its own window, not Table 1's), else the declared stencil
    if oracle:
        used = "true kinematics (oracle ablation)"
    elif estimate is not None:
        used = estimate.labels["differentiator"]
    else:
        used = f"{choice} ({DECLARED[choice].describe()})"
    info = {
        "selected": choice,
        "oracle": oracle,
        "selected_params": used,
        "poses": table.poses,
        "scored_frames": table.frames,
        "params": table.params,
        "tuning": table.tuning,
        "paper": PAPER,
        "files": {k: v for k, v in FILES.items() if k != "plot" or drawn},  # relative to --out, like the other stages
    }
    plot = record.out / FILES["plot"]
    figure = f"; Fig. 4: {plot}" if drawn else ""
    lines = ("Table 1: kinematics errors vs the AHRS (ours / paper's), pooled over axes and frames",
             *table.markdown().splitlines(),
             f"kinematics used by later stages: {'ORACLE (true kinematics, an ablation)' if oracle else used}{figure}")
    pictures = (Picture("Fig. 4", plot_fig4, (ep.truth, kins, plot), {"title": f"Vision kinematics vs AHRS ({table.poses})"}),
                ) if drawn else ()
    files = ((FILES["markdown"], (table.markdown() + "\n").encode()), (FILES["csv"], table.csv().encode()))
    return StageResult(blocks=(("kinematics", table.summary()), ("kinematics_info", info)), lines=lines,
                       files=files, pictures=pictures)


STAGE = Stage(name="kinematics", run=run, options=("kinematics", "no_pictures"), add_arguments=add_arguments)
