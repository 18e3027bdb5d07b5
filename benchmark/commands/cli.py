"""``fsv-bench``: simulate a scenario, run the pipeline's stages on it, save and summarise.

    fsv-bench --task lift --noise 0.01 [--user N --grasp N --mass N --seed N --duration S --out DIR]

The command runs a list of :class:`Stage` objects in order (``STAGES``). Each stage adds its own
command-line options, reads and extends the shared :class:`Run` (the episode, the summary), and
contributes one block to ``DIR/summary.json`` and a few lines to the printed summary. A later stage
(render, tracking, kinematics, forces, learning) plugs in by defining a ``Stage`` in its own module
and appending it to ``STAGES`` below, without touching the others.

Bad input (unknown task, index out of range, negative noise or duration) prints one line naming the
bad value and the accepted ones, exits with status 2 and writes nothing.
"""

from __future__ import annotations

import argparse
import pathlib
import sys
import time
from dataclasses import dataclass, field
from typing import Callable

from benchmark.background import Background
from benchmark.camera.episode_file import save_episode
from benchmark.world.episode import Episode
from benchmark.errors import BenchmarkError, ScenarioError
from benchmark.commands.report import format_world, scenario_block, world_block, write_json
from benchmark.world.scenario import Scenario
from fsv.errors import InputError
from fsv.provenance import provenance


@dataclass
class Run:
    """State shared by the stages of one command.

    Attributes:
        args: Parsed command-line options (every stage's).
        scenario: The scenario being run.
        out: Output directory (created only once the input has been validated).
        episode: The episode, once simulated (stages may replace it, e.g. after rendering).
        summary: Blocks of ``summary.json``, in stage order.
        timing_s: Seconds spent per stage.
        lines: Human-readable lines printed at the end.
        tracking: The tracker's output (box poses, hand, contacts), once tracked.
        method_spec: The method the command runs (its options, checked before any work).
        estimate: The method's estimate on the episode (tracking, kinematics, forces).
        background: Pictures and files the stages start and the command waits for at its end.
    """

    args: argparse.Namespace
    scenario: Scenario
    out: pathlib.Path
    episode: Episode | None = None
    summary: dict = field(default_factory=dict)
    timing_s: dict = field(default_factory=dict)
    lines: list = field(default_factory=list)
    tracking: object = None  # fsv.track.tracker.Tracking, once the tracking stage ran
    method_spec: object = None  # benchmark.method.MethodSpec: which method the tracking stage runs
    estimate: object = None  # fsv.method.Estimate, once the tracking stage ran the method
    background: Background = field(default_factory=Background)


@dataclass(frozen=True)
class Stage:
    """One step of the command.

    Attributes:
        name: Key of its block in ``summary.json`` and of its entry in ``timing_s``.
        add_arguments: Adds the stage's options to the parser (may do nothing).
        run: Does the work on a :class:`Run`; raises a BenchmarkError/FsvError on failure.
    """

    name: str
    add_arguments: Callable[[argparse.ArgumentParser], None]
    run: Callable[[Run], None]


def _no_arguments(parser: argparse.ArgumentParser) -> None:
    return None


def _simulate(run: Run) -> None:
    from benchmark.world.simulate import run as simulate_run

    episode, stats = simulate_run(run.scenario, progress=not run.args.quiet)
    run.episode = episode
    run.summary["scenario"] = scenario_block(episode)
    block = world_block(episode, stats.steps_per_s)
    run.summary["world"] = block
    run.lines.append(format_world(block))


SIMULATE = Stage(name="simulate", add_arguments=_no_arguments, run=_simulate)

# The stages, in pipeline order. Later stages append themselves here, one line each.
STAGES: list = [SIMULATE]

# Render (issue 3): noisy depth video, calibration and labels; depth preview PNG/GIF in DIR.
from benchmark.camera.render import add_cli_arguments as _render_arguments, run_cli_stage as _render  # noqa: E402

RENDER = Stage(name="render", add_arguments=_render_arguments, run=_render)
STAGES.append(RENDER)

# tracking (issue 6): box and hand from depth alone, contacts; scores and overlay (benchmark/scores/tracking.py).
from benchmark.scores import tracking as _tracking  # noqa: E402

STAGES.append(Stage(name="track", add_arguments=_tracking.add_arguments, run=_tracking.run_stage))

# kinematics (issue 4): Table 1, Fig. 4, and --kinematics for the later stages (benchmark/paper/table1.py).
from benchmark.paper import table1 as _table1  # noqa: E402

STAGES.append(Stage(name="kinematics", add_arguments=_table1.add_arguments, run=_table1.run_stage))

# forces (issue 5): nominal contact forces, scored against the truth (benchmark/scores/forces.py).
from benchmark.scores import forces as _score_forces  # noqa: E402

STAGES.append(Stage(name="forces", add_arguments=_score_forces.add_arguments, run=_score_forces.run_stage))

# learning (issue 7): learned internal forces with the shipped model (benchmark/scores/learned.py), and the
# subcommands `fsv-bench generate | train | table2` (benchmark/paper/dataset.py, training.py, table2.py).
from benchmark.scores import learned as _learning  # noqa: E402

STAGES.append(Stage(name="learn", add_arguments=_learning.add_arguments, run=_learning.run_stage))

# the verdict: the episode's metrics against the smoke suite's gates (a suite of one).
from benchmark.commands import verdict as _verdict  # noqa: E402

STAGES.append(Stage(name="verdict", add_arguments=_verdict.add_arguments, run=_verdict.run_stage))
SUBCOMMANDS = {"generate": "benchmark.paper.dataset", "calibrate": "benchmark.paper.calibration",
               "train": "benchmark.paper.training", "table2": "benchmark.paper.table2",
               "reproduce": "benchmark.reproduce", "eval": "benchmark.suites.evaluate",
               "compare": "benchmark.suites.compare", "export": "benchmark.exchange.export",
               "score": "benchmark.exchange.score", "leaderboard": "benchmark.suites.leaderboard",
               "sweep": "benchmark.suites.sweep"}


def _subcommand(argv: list) -> int:
    """Runs ``fsv-bench <subcommand> ...``; bad input exits 2, Ctrl-C 130 (re-run to resume)."""
    import importlib

    module = importlib.import_module(SUBCOMMANDS[argv[0]])
    p = _Parser(prog=f"fsv-bench {argv[0]}", description=module.__doc__.strip().splitlines()[0])
    module.add_arguments(p)
    args = p.parse_args(argv[1:])
    try:
        module.run(args)
    except (ScenarioError, InputError, ValueError) as e:
        print(f"fsv-bench {argv[0]}: error: {e}", file=sys.stderr)
        return 2
    except BenchmarkError as e:
        print(f"fsv-bench {argv[0]}: failed: {e}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print(f"fsv-bench {argv[0]}: interrupted; complete files are kept, run the same command to resume",
              file=sys.stderr)
        return 130
    return 0


class _Parser(argparse.ArgumentParser):
    """An argument parser whose errors are one line and exit status 2."""

    def error(self, message: str):
        self.exit(2, f"fsv-bench: error: {message}\n")


def build_parser() -> argparse.ArgumentParser:
    """The command's parser, with every stage's options."""
    p = _Parser(
        prog="fsv-bench",
        description="Simulate a hand-box manipulation and score force sensing from vision.",
        epilog="sub-commands: " + ", ".join(f"'fsv-bench {name} --help'" for name in SUBCOMMANDS)
        + " (training data, internal-force networks, the paper's Table 2)",
    )
    p.add_argument("--task", default="lift", help="task name (see benchmark.TASKS)")
    p.add_argument("--noise", type=float, default=0.01, help="depth noise standard deviation in metres, 0 to 0.1")
    p.add_argument("--sensor", default="ds325", help="depth sensor preset: ds325 (the paper's camera), kinect-v1, ideal")
    p.add_argument("--user", type=int, default=0, help="index into sim_assets/users.yaml")
    p.add_argument("--grasp", type=int, default=0, help="index into sim_assets/grasps.yaml")
    p.add_argument("--mass", type=int, default=0, help="index into sim_assets/masses.yaml")
    p.add_argument("--seed", type=int, default=0, help="random seed")
    p.add_argument("--duration", type=float, default=None, help="episode length in seconds, up to 120 (default: the task's)")
    p.add_argument("--out", type=pathlib.Path, default=None,
                   help="output directory (default: runs/<task>-u<user>-g<grasp>-m<mass>-s<seed>)")
    p.add_argument("--quiet", action="store_true", help="no progress bars")
    for stage in STAGES:
        stage.add_arguments(p)
    from benchmark.suites.evaluate import add_method_arguments

    add_method_arguments(p, oracle=False, internal_model=False)
    return p


def scenario_from_args(args: argparse.Namespace) -> Scenario:
    """The scenario of the command line, fully validated (raises ScenarioError)."""
    from benchmark.world.assets import validate

    sc = Scenario(task=args.task, user=args.user, grasp=args.grasp, mass=args.mass, noise_m=args.noise,
                  seed=args.seed, duration_s=args.duration, sensor=args.sensor)
    validate(sc)
    return sc


def method_spec_from_args(args: argparse.Namespace):
    """The method of the command line (``--kinematics``/``--contacts`` ablations, replaced stages,
    ``--internal-model``), loaded and checked; raises ValueError naming a bad option."""
    from benchmark.method import MethodSpec

    if args.differentiator and args.kinematics != "algebraic":
        raise ValueError(f"--kinematics {args.kinematics} and --differentiator {args.differentiator}: give one of them")
    differentiator = args.differentiator or (args.kinematics if args.kinematics in ("central", "gaussian") else None)
    oracle = tuple(name for name, on in (("kinematics", args.kinematics == "oracle"),
                                         ("contacts", args.contacts == "oracle")) if on)
    spec = MethodSpec(method=args.method, tracker=args.tracker, differentiator=differentiator, forces=args.forces,
                      internal=args.internal, internal_model=args.internal_model, oracle=oracle)
    spec.check()
    return spec


def main(argv: list | None = None) -> int:
    """Entry point of ``fsv-bench``; returns the exit status."""
    argv = sys.argv[1:] if argv is None else list(argv)
    if argv and argv[0] in SUBCOMMANDS:
        return _subcommand(argv)
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        scenario = scenario_from_args(args)
        spec = method_spec_from_args(args)
        if args.gates:
            from benchmark.suites.evaluate import load_gates

            load_gates(args.gates)
        from benchmark.suites.evaluate import check_out, episode_name

        out = args.out or pathlib.Path("runs") / episode_name(scenario)
        check_out(out)
    except (ScenarioError, InputError, ValueError) as e:
        print(f"fsv-bench: error: {e}", file=sys.stderr)
        return 2
    import shutil
    import tempfile

    from benchmark.atomic import swap_folder

    # Every file goes into a temporary sibling folder, moved into place only when the run is complete:
    # an interrupted or failed run leaves the previous output folder as it was.
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = pathlib.Path(tempfile.mkdtemp(prefix=f".{out.name}.", dir=out.parent))
    run = Run(args=args, scenario=scenario, out=tmp, method_spec=spec)
    start = time.perf_counter()
    try:
        for stage in STAGES:
            t0 = time.perf_counter()
            stage.run(run)
            run.timing_s[stage.name] = time.perf_counter() - t0
            if stage is RENDER:  # the episode is complete: its archive is written beside the later stages
                run.background.thread("episode.npz", save_episode, run.episode, tmp / "episode.npz")
        t0 = time.perf_counter()
        run.background.wait()
        run.timing_s["wait_background"] = time.perf_counter() - t0
        run.timing_s["total"] = time.perf_counter() - start
        run.summary["timing_s"] = run.timing_s
        run.summary["provenance"] = provenance()
        write_json(tmp / "summary.json", run.summary)
        swap_folder(tmp, out)
    except (ScenarioError, InputError) as e:
        run.background.cancel()
        shutil.rmtree(tmp, ignore_errors=True)
        print(f"fsv-bench: error: {e}", file=sys.stderr)
        return 2
    except BenchmarkError as e:
        run.background.cancel()
        shutil.rmtree(tmp, ignore_errors=True)
        print(f"fsv-bench: failed: {e}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        run.background.cancel()
        shutil.rmtree(tmp, ignore_errors=True)
        print(f"fsv-bench: interrupted; {out} is as it was before the run", file=sys.stderr)
        return 130
    except BaseException:
        run.background.cancel()
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    path = out / "episode.npz"
    sc = scenario
    print(f"fsv-bench: task {sc.task}, user {sc.user}, grasp {sc.grasp}, mass {sc.mass}, seed {sc.seed}, "
          f"sensor {sc.sensor}, noise {sc.noise_m} m, {len(run.episode.truth.t)} frames")
    for line in run.lines:
        print(line.replace(str(tmp), str(out)))
    print(f"episode: {path}\nsummary: {out / 'summary.json'} ({run.timing_s['total']:.1f} s)")
    failed = [g["name"] for g in run.summary["verdict"]["gates"] if not g["passed"]]
    if failed:
        print(f"fsv-bench: {len(failed)} gate(s) failed: {'; '.join(failed)}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
