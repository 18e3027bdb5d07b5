"""How human the world is, over a suite's episodes: ``python -m benchmark.commands.humanness``.

Writes ``humanness.md`` and ``humanness.json`` (``results/world``) from
:func:`benchmark.world.humanness.suite_humanness`: the peaks of the box's motion while lifted, the
grip's fluctuation in holds and its coupling to the load, per task, beside the ranges the world
was planned with.
"""

from __future__ import annotations

import argparse
import json
import pathlib
import shutil
from dataclasses import asdict

import numpy as np

from benchmark.atomic import OutputFolderError, check_out, staging_folder, swap_folder, write_text
from benchmark.scores.aggregate import span
from benchmark.suites import get_suite
from benchmark.world import living
from benchmark.world.humanness import suite_humanness
from benchmark.world.tasks.human import (
    ROTATION_PEAK_ALPHA,
    SHAKE_PEAK_ACC,
    TRANSPORT_PEAK_ACC,
)
from fsv.provenance import provenance


def report_markdown(suite, rows: list) -> str:
    """The per-task table of :func:`suite_humanness`'s rows, with the literature ranges."""
    lines = [
        f"# How human the world is: suite {suite.name} v{suite.version} ({len(rows)} episodes, truth only)",
        "",
        f"The people's grip control: {', '.join(sorted({sc.grip_control for sc in suite.scenarios}))} "
        "(benchmark.world.grip). Peaks while the box is lifted (held, no table contact); median (min-max) over "
        "the task's episodes. The grip-load correlation is measured from 1 s after lift-off (the thumb's normal "
        "force against |m (a - g)|, benchmark.world.humanness); the effective margin is 1 - L / (mu sum N) "
        "over lifted frames (the digits' summed tangential and normal forces).",
        f"Planned ranges (benchmark/world/tasks/human.py): transports peak at {TRANSPORT_PEAK_ACC.lo:g}-"
        f"{TRANSPORT_PEAK_ACC.hi:g} m/s^2, turns at {ROTATION_PEAK_ALPHA.lo:g}-{ROTATION_PEAK_ALPHA.hi:g} rad/s^2, "
        f"shake at {SHAKE_PEAK_ACC.lo:g}-{SHAKE_PEAK_ACC.hi:g} m/s^2; grip fluctuations drawn for a total "
        f"coefficient of variation of about {100 * np.hypot(living.DRIFT_CV[0], living.TREMOR_CV[0]):.1f}-"
        f"{100 * np.hypot(living.DRIFT_CV[1], living.TREMOR_CV[1]):.1f} % (benchmark/world/living.py).",
        "",
        "| task | episodes | peak acc [m/s^2] | peak angular velocity [rad/s] | thumb grip CV in holds [%] "
        "| grip-load correlation | grip lead [ms] | effective margin | thumb / weight | Newton-Euler residual [N] |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for task in dict.fromkeys(sc.task for sc, _ in rows):  # in the suite's order
        hs = [h for sc, h in rows if sc.task == task]
        lines.append(
            f"| {task} | {len(hs)} | {span(h.peak_acc for h in hs)} | {span(h.peak_omega for h in hs)} "
            f"| {span(100 * h.grip_cv for h in hs)} | {span(h.grip_load_corr for h in hs)} "
            f"| {span(1000 * h.grip_lead_s for h in hs)} | {span(h.effective_margin for h in hs)} "
            f"| {span(h.thumb_per_weight for h in hs)} | {max(h.newton_euler_n for h in hs):.1e} |")
    every = [h for _, h in rows]
    lines += ["", f"Over every episode: effective margin {span(h.effective_margin for h in every)}, thumb / weight "
                  f"{span(h.thumb_per_weight for h in every)} (the people's drawn margins: sim_assets/users.yaml, "
                  "benchmark.world.people)."]
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    """``python -m benchmark.commands.humanness``: writes humanness.md and humanness.json."""
    p = argparse.ArgumentParser(prog="python -m benchmark.commands.humanness", description=__doc__.splitlines()[0])
    p.add_argument("--suite", default="standard", help="suite whose episodes are simulated (default standard)")
    p.add_argument("--out", type=pathlib.Path, default=pathlib.Path("results/world"),
                   help="output folder, replaced whole if fsv-bench wrote it")
    p.add_argument("--grip-control", default=None, help="the people's grip control, replacing the suite's: "
                                                          "whole-hand or per-digit (benchmark.world.grip)")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    args = p.parse_args(argv)
    try:
        suite = get_suite(args.suite, grip_control=args.grip_control)
        check_out(args.out)
    except (ValueError, OutputFolderError) as e:
        p.exit(2, f"{p.prog}: error: {e}\n")
    rows = suite_humanness(suite, progress=not args.quiet)
    md = report_markdown(suite, rows)
    def strict(h):  # nan (no hold, no lifted frame) as null
        return {k: (None if isinstance(v, float) and not np.isfinite(v) else v) for k, v in asdict(h).items()}

    doc = {"suite": {"name": suite.name, "version": suite.version},
           "episodes": [{"scenario": asdict(sc), **strict(h)} for sc, h in rows], "provenance": provenance()}
    tmp = staging_folder(args.out)
    try:
        write_text(str(tmp / "humanness.md"), md)
        write_text(str(tmp / "humanness.json"), json.dumps(doc, indent=1, allow_nan=False) + "\n")
        swap_folder(tmp, args.out)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    print(md)
    print(f"written to {args.out}/ (humanness.md, humanness.json)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
