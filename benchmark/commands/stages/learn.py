"""The learn stage: the method's final forces (learned internal forces) against the truth."""

from __future__ import annotations

from benchmark.commands.stage import Run, Stage, StageResult
from benchmark.commands.stages.forces import estimate_inputs, oracle_tag
from benchmark.scores.learned import model_block, score_episode
from fsv.learn.model import SHIPPED_MODELS


def add_arguments(parser) -> None:
    """Adds ``--internal-model FILE`` to ``fsv-bench``."""
    parser.add_argument("--internal-model", default=None,
                        help="internal-force model from `fsv-bench train` (default: the protocol's model shipped in fsv/data: "
                             "user-blind under --protocol blind, with grip inputs under --protocol calibrated)")


def run(record: Run, options) -> StageResult:
    """The ``learning`` block and one printed line: the estimate's final forces scored against the truth."""
    est = record.estimate
    kin, contacts, labels = estimate_inputs(est)
    if est.forces is None:
        return StageResult(blocks=(("learning", {**labels, "program": None}),),
                           lines=(f"learning: the method has no internal-force stage ({est.labels['internal']})",))
    scores = score_episode(record.episode, est.forces, kin, contacts)
    path = options["internal_model"]
    model_info = {}
    if est.learned_model is not None:  # the reference's learned stage: the model it used
        grip = record.inputs.grip  # what the track stage handed the method of the person (None: blind)
        blind = grip is None
        model_info = {"internal_model": path or f"fsv/data/{SHIPPED_MODELS[blind]}",
                      "model": model_block(est.learned_model)}
        if model_info["model"]["grip_inputs"]:
            model_info["grip_calibration"] = None if blind else {"baseline_n": grip.baseline_n, "gain": grip.gain}
    program = est.labels["internal"]
    if est.forces is est.nominal:  # a force stage whose forces are the final ones (--method direct)
        program = est.labels["forces"]
        model_info = {"direct_model": record.method_spec.direct_model or "fsv/data/direct_forces.npz"}
    block = {**labels, "program": program, **model_info, **scores}
    paper = block["paper_rule"]
    line = (
        f"learning [{oracle_tag(labels)}] (kinematics {labels['kinematics']}, contacts {labels['contacts']}): learned forces' "
        f"relative error {block['rel_err_pct_mean']:.1f} ± {block['rel_err_pct_std']:.1f} % over every contact frame "
        f"({block['scored']} finger-frames, {100 * block['unsolved_frac']:.1f} % unsolved, scored as 0 N), MAE "
        f"{block['mae_n']:.2f} N; under the paper's sample rule {paper['rel_err_pct_mean']:.1f} ± "
        f"{paper['rel_err_pct_std']:.1f} % over {paper['scored']} (paper, Table 2: 9.7-10.9 %)"
        + (f"; the user's grip calibration: {g['baseline_n']:.2f} N + {g['gain']:.2f} N per N of load"
           if (g := block.get("grip_calibration")) else "")
    )
    return StageResult(blocks=(("learning", block),), lines=(line,), learned=scores)


STAGE = Stage(name="learn", run=run, options=("internal_model",), add_arguments=add_arguments)
