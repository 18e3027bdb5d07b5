"""The track stage: the method on the episode's camera inputs; the ``tracking`` block and the overlay.

It is the command's one entry into the method (:func:`benchmark.method.run_method`): the estimate
(tracking, kinematics, forces) it returns is what the later stages score.
"""

from __future__ import annotations

import numpy as np

from benchmark.commands.pictures.overlay import plot_overlay
from benchmark.commands.stage import Picture, Run, Stage, StageResult
from benchmark.errors import ScenarioError
from benchmark.limits import MAX_INIT_SCALE, number
from benchmark.method import run_method
from benchmark.method.init import INIT_PERTURBATION
from benchmark.method.run import camera_input_and_knowledge
from benchmark.scores.frames import tracking_in_true_world
from benchmark.scores.tracking import score_tracking
from benchmark.world.contact_error import PAPER_CONTACT_ERROR_MM


def add_arguments(parser) -> None:
    """Options of the track stage of ``fsv-bench``."""
    parser.add_argument("--init-perturbation", type=number(0, MAX_INIT_SCALE), default=1.0, metavar="SCALE",
                        help=f"scale of the tracker's seeded first-frame perturbation, 0 (the exact start) to "
                             f"{MAX_INIT_SCALE:g} (default 1; see benchmark.method.init.INIT_PERTURBATION)")


def check_options(options) -> None:
    """Raises ScenarioError for an init-perturbation scale outside [0, ``MAX_INIT_SCALE``]."""
    scale = options["init_perturbation"]
    if not (np.isfinite(scale) and 0 <= scale <= MAX_INIT_SCALE):
        raise ScenarioError(f"--init-perturbation must be a scale from 0 to {MAX_INIT_SCALE:g}, got {scale!r}")


def run(record: Run, options) -> StageResult:
    """Runs the method on the rendered episode; scores its tracking against the truth."""
    check_options(options)
    ep, scale = record.episode, float(options["init_perturbation"])
    spec = record.method_spec
    inputs, known = camera_input_and_knowledge(ep, scale, spec.knowledge, spec.protocol)
    estimate = run_method(record.method_spec, ep, inputs=inputs, progress=not record.quiet)
    tracking = estimate.tracking
    elapsed = estimate.timing_s["track"]
    stages = dict(getattr(tracking, "timing_s", None) or {})
    first = float(getattr(tracking, "first_frame_s", 0.0))
    compiling = float(getattr(tracking, "compile_s", 0.0))  # the first run after installing compiles the kernels
    scores = score_tracking(tracking_in_true_world(tracking, known.world_from_method), ep.truth)
    overlay = None if options["no_pictures"] else record.out / "tracking_overlay.png"
    T = len(ep.truth.t)
    block = {
        **scores,
        "paper_contact_err_mm": PAPER_CONTACT_ERROR_MM,
        "frames_per_s": T / elapsed,
        "frames_per_s_after_first": frames_per_s_after_first(T, _fits_s(stages, elapsed), first, compiling),
        "first_frame_s": first,
        "compile_s": compiling,
        "stage_ms_per_frame": {k: 1e3 * v / T for k, v in stages.items()},
        "tracker": estimate.labels.get("tracker"),
        "init_perturbation": {k: float(v) * scale for k, v in INIT_PERTURBATION.items()},
        "overlay": None if overlay is None else overlay.name,
    }
    paper = PAPER_CONTACT_ERROR_MM
    line = (
        f"tracking [{estimate.labels.get('tracker')}] ({block['frames_per_s_after_first']:.1f} frames/s after the "
        f"first frame, which took {first:.1f} s"
        + (f"; {compiling:.1f} s compiling numba's kernels set aside, once after installing" if compiling >= 0.05 else "")
        + f"): box {scores['box_pos_err_mm']:.2f} mm / "
        f"{scores['box_rot_err_deg']:.2f} deg (median), fingertips {scores['fingertip_err_mm']:.1f} mm, "
        f"contact point {scores['contact_err_mm_mean']:+.2f} ± {scores['contact_err_mm_std']:.2f} mm per axis "
        f"(paper {paper['mean']:g} ± {paper['std']:g}), median {scores['contact_err_mm_median_euclid']:.1f} mm, recall "
        f"{scores['contact_recall']:.2f}, precision {scores['contact_precision']:.2f}"
        + ("" if overlay is None else f"; overlay {overlay.name}")
    )
    # drawn as the method sees it: its calibration, hand and box (the truth in gold, through its calibration)
    pictures = () if overlay is None else (Picture(
        "tracking overlay", plot_overlay,
        (_whole(ep.depth), inputs.calib, tracking, inputs.object_model, inputs.hand_model, overlay), {"truth": ep.truth}),)
    grip = inputs.grip
    person = {"protocol": spec.protocol,
              "grip": None if grip is None else {"baseline_n": grip.baseline_n, "gain": grip.gain, "samples": grip.samples}}
    told = known.line() + ("; person [blind]: nothing known" if grip is None else
                           f"; person [calibrated]: grip {grip.baseline_n:.2f} N + {grip.gain:.3f} N per N of load "
                           f"({grip.samples} samples of a calibration recording)")
    return StageResult(blocks=(("knowledge", known.record()), ("person", person), ("tracking", block)), lines=(told, line),
                       pictures=pictures, estimate=estimate, knowledge=known, inputs=inputs)


def frames_per_s_after_first(T: int, fits_s: float, first_s: float, compile_s: float) -> float:
    """The tracker's speed from the second frame on, numba's compilation set aside (the speed of
    every run after the first after installing): ``(T - 1) / (fits_s - first_s - compile_s)``, NaN
    where that time is not positive or there is one frame.

    Args:
        T: Frames tracked.
        fits_s: Seconds of the frames' fits, [s]: the reference tracker's box and hand fits
            (``Tracking.timing_s``), not the frames' wait for a depth still being rendered beside
            it, nor the table's fit or the contacts' detection once; another tracker's whole time.
        first_s: The first frame's, without compiling, [s].
        compile_s: Of ``fits_s``, compiling numba's kernels, [s].
    """
    rest = fits_s - first_s - compile_s
    return (T - 1) / rest if T > 1 and rest > 0 else float("nan")


def _fits_s(stages: dict, elapsed_s: float) -> float:
    """The frames' fits' seconds of a tracker's ``timing_s`` (``box`` and ``hand``), else ``elapsed_s``."""
    return stages["box"] + stages["hand"] if {"box", "hand"} <= set(stages) else elapsed_s


def _whole(depth):
    """``depth`` (an ``fsv.DepthVideo``) once every frame is there: a depth still being recorded
    beside the tracker (``fsv.types.DepthRecording``, which a method need not have read to its
    end) is waited for here, in the process that started it, before a picture's child is forked."""
    depth.depth_m  # noqa: B018 (read for its wait)
    return depth


STAGE = Stage(name="track", run=run, options=("init_perturbation", "no_pictures"), add_arguments=add_arguments)
