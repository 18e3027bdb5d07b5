"""Table 1 from the command line: ``python -m benchmark.commands.table1``.

    python -m benchmark.commands.table1 --score --seeds 0,1,2 --out results/table1

``--calibrate`` tunes the differentiators on the calibration seeds, ``--sweep`` compares the best
filters per window budget, ``--score`` scores the six-axis table (:mod:`benchmark.paper.table1`)
and, with ``--out``, writes ``table1.md``, ``table1.csv`` and Fig. 4.

    python -m benchmark.commands.table1 --score --seeds 0,1,2 --imu mti-300 --out results/table1_ahrs

compares with a lab's AHRS instead of the truth (:mod:`benchmark.paper.ahrs`) and writes
``table1.md``, ``table1.csv`` and ``ahrs.json`` (the sensor's parameters, each episode's drawn
errors, and the table's standard deviations with each error source alone).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path

from benchmark.atomic import OutputFolderError, check_out, staged_folder, write_bytes
from benchmark.commands.pictures.fig4 import plot_fig4
from benchmark.errors import ScenarioError
from benchmark.paper.ahrs import IMU_CHOICES, MTI_300, SOURCES, lab_readings
from benchmark.paper.table1 import (
    MAX_SUPPORT_FRAMES,
    POSES_LABEL,
    SIX_AXIS_TASKS,
    Table1,
    episode_scenarios,
    episode_set,
    pose_error_stats,
    rms_errors,
    score_episodes,
    support_sweep,
    tune,
)
from benchmark.world.motion import CALIBRATION_SEEDS, DECLARED
from benchmark.world.scenario import episode_name
from benchmark.world.truth import Truth


def write_outputs(table: Table1, truth: Truth, kinematics: dict, out_dir: str | os.PathLike, panels: list | None = None,
                  background=None) -> dict:
    """Writes table1.md, table1.csv and fig4_kinematics.png into ``out_dir``; returns their paths.

    ``panels`` is passed to :func:`plot_fig4` (e.g. one excitation episode per axis). With a
    ``background`` (:class:`benchmark.background.Background`) the figure is drawn there.
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = {"markdown": out / "table1.md", "csv": out / "table1.csv", "plot": out / "fig4_kinematics.png"}
    write_bytes(paths["markdown"], (table.markdown() + "\n").encode())
    write_bytes(paths["csv"], table.csv().encode())
    title = f"Vision kinematics vs AHRS ({table.poses})"
    if background is None:
        plot_fig4(truth, kinematics, paths["plot"], title=title, panels=panels)
    else:
        background.process("Fig. 4", plot_fig4, truth, kinematics, paths["plot"], title=title, panels=panels)
    return paths


MTI_300_REFERENCE = (f"a lab's Xsens MTi-300 (benchmark.paper.ahrs: datasheet noise and biases, scale factors, "
                     f"alignment, {MTI_300.caption()})")


def lab_ahrs_report(episodes: list, scenarios: list, poses_label: str) -> tuple[Table1, list, dict]:
    """Table 1 against the MTi-300 of :mod:`benchmark.paper.ahrs`, and what each error source does.

    Args:
        episodes: (truth, poses) pairs.
        scenarios: Their scenarios (each reading draws from its ``"ahrs"`` stream).
        poses_label: Where the poses came from.

    Returns:
        ``(table, kinematics, report)``; ``report`` (``ahrs.json``): ``params``, ``episodes`` (name
        and drawn errors of each) and ``sources``: for each error source alone, and all together,
        each method's ``acc_std`` [m/s^2] and ``gyro_std`` [rad/s].
    """

    readings = [lab_readings(truth, sc) for (truth, _), sc in zip(episodes, scenarios)]
    table, kins = score_episodes(episodes, poses_label=poses_label, readings=readings, reference=MTI_300_REFERENCE)
    sources = {}
    for name in (*SOURCES, "all"):
        params = MTI_300 if name == "all" else MTI_300.only(name)
        alone = [lab_readings(truth, sc, params) for (truth, _), sc in zip(episodes, scenarios)]
        t, _ = score_episodes(episodes, poses_label=poses_label, readings=alone)
        sources[name] = {m: {k: t.stats[m][k] for k in ("acc_std", "gyro_std")} for m in t.stats}
    report = {
        "sensor": "Xsens MTi-300 (benchmark.paper.ahrs)",
        "params": MTI_300.describe(),
        "episodes": [{"episode": episode_name(sc), **r.draw.summary()} for sc, r in zip(scenarios, readings)],
        "sources": sources,
    }
    return table, kins, report


def _csv_list(text: str) -> list[str]:
    return [x for x in (t.strip() for t in text.split(",")) if x]


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(
        description="Table 1 tools: tune the differentiators on calibration episodes, or score the six-axis table."
    )
    parser.add_argument("--calibrate", action="store_true", help="tune on the calibration seeds and print the best parameters")
    parser.add_argument("--sweep", action="store_true", help="compare the best Gaussian and algebraic filters per window budget")
    parser.add_argument("--score", action="store_true", help="score Table 1 pooled over the tasks and --seeds")
    parser.add_argument("--tasks", default=",".join(SIX_AXIS_TASKS), help="comma-separated tasks (default: the six excitations)")
    parser.add_argument("--seeds", default="0", help="comma-separated seeds scored by --score (never the calibration seeds)")
    parser.add_argument("--noise", type=float, default=0.01)
    parser.add_argument("--out", type=Path, default=None,
                        help="with --score: write table1.md, table1.csv and Fig. 4 into this folder (replaced whole if "
                             "fsv-bench wrote it)")
    parser.add_argument(
        "--tracked", action="store_true", help="with --score: differentiate the tracker's poses (render + fsv.track; slow)"
    )
    parser.add_argument("--imu", choices=IMU_CHOICES, default="ideal",
                        help="with --score: compare with the simulator's truth (ideal) or a lab's Xsens MTi-300 "
                             "(benchmark.paper.ahrs); the latter writes table1.md, table1.csv and ahrs.json")
    args = parser.parse_args(argv)
    if not (args.calibrate or args.sweep or args.score):
        parser.print_help()
        return 0
    if args.score and args.out is not None:
        try:
            check_out(args.out)
        except OutputFolderError as e:
            print(f"{parser.prog}: error: {e}", file=sys.stderr)
            return 2
    tasks = _csv_list(args.tasks)
    if args.calibrate or args.sweep:
        calibration = episode_set(tasks, args.noise, CALIBRATION_SEEDS)
        seeds = ",".join(str(s) for s in CALIBRATION_SEEDS)
        print(f"calibration: tasks {','.join(tasks)}, noise {args.noise} m, seeds {seeds}, support <= {MAX_SUPPORT_FRAMES} frames")
    if args.calibrate:
        best, scores = tune(calibration)
        for method, scored in scores.items():
            print(f"{method}: best {best[method].describe()}")
            for cfg, j in sorted(scored, key=lambda s: s[1])[:5]:
                print(f"    objective {j:.4f}  {cfg.describe()}")
    if args.sweep:
        print("| support [frames] | method | parameters | acc RMS [m/s^2] | gyro RMS [rad/s] |")
        print("|---|---|---|---|---|")
        ref_acc, ref_gyro = rms_errors(calibration, DECLARED["central"])
        print(f"| 3 | central | {DECLARED['central'].describe()} | {ref_acc:.3f} | {ref_gyro:.3f} |")
        for r in support_sweep(calibration):
            print(f"| {r['support']} | {r['method']} | {r['params']} | {r['acc_rms']:.3f} | {r['gyro_rms']:.3f} |")
    if args.score:
        seeds = [int(s) for s in _csv_list(args.seeds)]
        if set(seeds) & set(CALIBRATION_SEEDS):
            raise ScenarioError(f"--seeds {seeds} overlap the calibration seeds {CALIBRATION_SEEDS}: they are never scored")
        episodes = episode_set(tasks, args.noise, seeds, tracked=args.tracked)
        label = "tracked poses (fsv.track, from depth)" if args.tracked else POSES_LABEL
        report = None
        if args.imu == "ideal":
            table, kins = score_episodes(episodes, poses_label=label)
        else:
            table, kins, report = lab_ahrs_report(episodes, episode_scenarios(tasks, args.noise, seeds), label)
        err = pose_error_stats(episodes)
        print(
            f"pose errors: {err['pos_std_mm']:.2f} mm and {err['rot_std_deg']:.2f} deg per axis (std), "
            f"lag-1 correlation {err['pos_lag1_corr']:.2f} (position), {err['rot_lag1_corr']:.2f} (rotation)"
        )
        print(f"Table 1 on tasks {','.join(tasks)}, seeds {','.join(map(str, seeds))}, noise {args.noise} m")
        print(table.markdown())
        if report is not None:
            print("Standard deviations with each AHRS error source alone (acc [m/s^2] / gyro [rad/s], algebraic):")
            for name, stats in report["sources"].items():
                print(f"    {name}: {stats['algebraic']['acc_std']:.3f} / {stats['algebraic']['gyro_std']:.3f}")
        if args.out is not None and report is not None:
            with staged_folder(args.out) as tmp:
                write_bytes(tmp / "table1.md", (table.markdown() + "\n").encode())
                write_bytes(tmp / "table1.csv", table.csv().encode())
                write_bytes(tmp / "ahrs.json", (json.dumps(report, indent=1) + "\n").encode())
            print(f"wrote {', '.join(str(args.out / n) for n in ('table1.md', 'table1.csv', 'ahrs.json'))}")
        elif args.out is not None:
            panels = None
            by_task = {task: i * len(seeds) for i, task in enumerate(tasks)}  # first seed of each task
            wanted = [f"excite-{kind}{axis}" for kind in "tr" for axis in "xyz"]
            if all(t in by_task for t in wanted):
                panels = [(episodes[by_task[t]][0], kins[by_task[t]], t) for t in wanted]
            with staged_folder(args.out) as tmp:
                paths = write_outputs(table, episodes[0][0], kins[0], tmp, panels=panels)
            print(f"wrote {', '.join(str(args.out / p.name) for p in map(Path, paths.values()))}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
