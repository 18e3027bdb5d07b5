"""``fsv-bench``: simulate a scenario, run the method's stages on its depth, score and save them.

    fsv-bench --task lift --noise 0.01 [--user N --grasp N --mass N --seed N --duration S --out DIR]

The command runs the stages of :data:`benchmark.commands.stages.STAGES` in order. Each stage
reads the frozen :class:`~benchmark.commands.stage.Run` and the options it declares, and returns
a :class:`~benchmark.commands.stage.StageResult`: its blocks of ``DIR/summary.json``, its printed
lines, its files and pictures (drawn beside the later stages), and the episode or estimate it
made, from which the command builds the next ``Run``.

Bad input (unknown task, index out of range, negative noise or duration) prints one line naming the
bad value and the accepted ones, exits with status 2 and writes nothing.
"""

from __future__ import annotations

import argparse
import dataclasses
import hashlib
import json
import pathlib
import re
import shutil
import sys
import time

from benchmark import interrupt
from benchmark.atomic import check_out, staging_folder, swap_folder
from benchmark.background import Background
from benchmark.commands.digests import stage_digests
from benchmark.commands.parser import OneLineParser
from benchmark.commands.report import write_json
from benchmark.commands.stage import Run, StageResult, complete
from benchmark.commands.stages import STAGES
from benchmark.errors import BenchmarkError, ScenarioError
from benchmark.method.protocol import check_people
from benchmark.suites.evaluate import add_method_arguments, load_gates, spec_from_args
from benchmark.suites.splits import SPLITS
from benchmark.world.assets import validate
from benchmark.world.scenario import DEFAULT_GRIP_CONTROL, DEFAULT_HAND_SURFACE, Scenario, episode_name
from benchmark.world.tasks import TASKS
from fsv.errors import InputError
from fsv.provenance import provenance

SUBCOMMANDS = ("generate", "calibrate", "train", "train-direct", "table2", "eval", "compare", "export", "score",
               "leaderboard", "sweep", "check")
"""The sub-commands this module runs (:func:`subcommand_module`). ``fsv-bench reproduce``, which
regenerates results by running these commands, sits a floor above and is run by
:mod:`benchmark.commands.entry`."""

ALL_SUBCOMMANDS = SUBCOMMANDS + ("reproduce",)
"""Every sub-command of ``fsv-bench``, as its help lists them."""


def subcommand_module(name: str):
    """The module of ``fsv-bench <name>`` (one of :data:`SUBCOMMANDS`), imported when the sub-command
    runs: each pulls in libraries the main command does not need (torch, pandas, h5py, Ray)."""
    match name:
        case "generate":
            from benchmark.paper.dataset import cli as module  # lazy: a sub-command's libraries, when it runs
        case "calibrate":
            from benchmark.paper import calibration as module  # lazy: a sub-command's libraries, when it runs
        case "train":
            from benchmark.paper import training as module  # lazy: a sub-command's libraries, when it runs
        case "train-direct":
            from benchmark.paper import direct_training as module  # lazy: a sub-command's libraries, when it runs
        case "table2":
            from benchmark.paper import table2 as module  # lazy: a sub-command's libraries, when it runs
        case "eval":
            from benchmark.commands import eval as module  # lazy: a sub-command's libraries, when it runs
        case "compare":
            from benchmark.suites import compare as module  # lazy: a sub-command's libraries, when it runs
        case "export":
            from benchmark.exchange import export as module  # lazy: a sub-command's libraries, when it runs
        case "score":
            from benchmark.exchange import score as module  # lazy: a sub-command's libraries, when it runs
        case "leaderboard":
            from benchmark.suites import leaderboard as module  # lazy: a sub-command's libraries, when it runs
        case "sweep":
            from benchmark.suites import sweep as module  # lazy: a sub-command's libraries, when it runs
        case "check":
            from benchmark.exchange import check as module  # lazy: a sub-command's libraries, when it runs
        case _:
            raise KeyError(f"{name!r} is not a sub-command of this module; accepted: {', '.join(SUBCOMMANDS)}")
    return module


def _interrupted(e: BaseException) -> bool:
    """Whether an exception is Ctrl-C's: a KeyboardInterrupt, or what a library made of it (the
    SystemError of a compiled numba function, the ImportError of a C extension, an error that wraps it)."""
    return isinstance(e, KeyboardInterrupt) or interrupt.interrupted() or isinstance(e.__context__, KeyboardInterrupt)


def exit_status(e: BaseException, prog: str, when_interrupted: str, bad_input: tuple) -> int:
    """The exit status of a command that raised ``e``, with its one line on stderr: 130 interrupted,
    2 bad input (``bad_input``), 1 a failure of the benchmark (a failed stage); anything else (a bug,
    SystemExit) is raised again."""
    if not isinstance(e, SystemExit):
        if _interrupted(e):
            print(f"{prog}: interrupted; {when_interrupted}", file=sys.stderr)
            return 130
        if isinstance(e, bad_input):
            print(f"{prog}: error: {e}", file=sys.stderr)
            return 2
        if isinstance(e, BenchmarkError):
            print(f"{prog}: failed: {e}", file=sys.stderr)
            return 1
    raise e


def subcommand_parser(name: str, module=None) -> tuple:
    """``(module, parser)`` of ``fsv-bench <name>``: the sub-command's module (``module``, or
    :func:`subcommand_module`'s) and its parser."""
    module = subcommand_module(name) if module is None else module
    p = OneLineParser(prog=f"fsv-bench {name}", description=plain(module.__doc__.strip().splitlines()[0]))
    module.add_arguments(p)
    return module, p


def run_subcommand(argv: list, module=None) -> int:
    """Runs ``fsv-bench <subcommand> ...`` (with ``module``, the sub-command's module, or
    :func:`subcommand_module`'s); bad input exits 2, Ctrl-C 130 with the module's ``INTERRUPTED``
    line (what the interruption left)."""
    module, p = subcommand_parser(argv[0], module)
    args = p.parse_args(argv[1:])
    try:
        module.run(args)
    except BaseException as e:
        return exit_status(e, f"fsv-bench {argv[0]}", module.INTERRUPTED, (ScenarioError, InputError, ValueError))
    return 0


def plain(text: str) -> str:
    """A docstring's line as a terminal shows it: without reStructuredText's roles and literals
    (``:func:`x``` and ````x```` become ``x``)."""
    return re.sub(r"``([^`]+)``", r"\1", re.sub(r":[a-z]+:`~?([^`]+)`", r"\1", text))


def split_note(scenario: Scenario) -> str | None:
    """A note when the scenario's person, grasp or view lies in the test split: those are for scoring
    only (``benchmark.suites.splits``), and a result on them should not choose anything."""
    test = SPLITS["test"]
    parts = [f"{kind} {index}" for kind, index in (("user", scenario.user), ("grasp", scenario.grasp),
                                                   ("view", scenario.view)) if test.holds(index)]
    if not parts:
        return None
    return (f"fsv-bench: note: {', '.join(parts)} {'is' if len(parts) == 1 else 'are'} of the test split "
            f"({test.start}-{test.stop - 1}: {test.purpose}); choose on the dev split ({SPLITS['dev'].start}-"
            f"{SPLITS['dev'].stop - 1})")


def build_parser() -> argparse.ArgumentParser:
    """The command's parser, with every stage's options."""
    p = OneLineParser(
        prog="fsv-bench",
        description="Simulate a hand-box manipulation and score force sensing from vision.",
        epilog="sub-commands: " + ", ".join(f"'fsv-bench {name} --help'" for name in ALL_SUBCOMMANDS)
        + " (training data, internal-force networks, the paper's Table 2)",
    )
    p.add_argument("--task", default="lift", help=f"task name: {', '.join(TASKS)}")
    p.add_argument("--noise", type=float, default=0.01, help="depth noise standard deviation in metres, 0 to 0.1")
    p.add_argument("--sensor", default="ds325", help="depth sensor preset: ds325 (the paper's camera), kinect-v1, ideal")
    p.add_argument("--hand-surface", default=DEFAULT_HAND_SURFACE,
                   help="what the camera sees of the hand: skin (the default: the person's skin, with pulps that "
                        "compress and flatten on the box), skin-rigid (its pulps rigid) or capsules (the collision "
                        "primitives, an ablation)")
    p.add_argument("--grip-control", default=DEFAULT_GRIP_CONTROL,
                   help="how the simulated person controls the grip: per-digit (the default: each digit pressed for "
                        "its own load, the grasp at the person's safety margin, with tactile feedback) or whole-hand "
                        "(the grasp's squeeze scaled as one pattern, the world of earlier versions)")
    p.add_argument("--user", type=int, default=0, help="the person: 0-4 the named cohort (sim_assets/users.yaml), N >= 5 drawn with seed N (anatomy and grip style)")
    p.add_argument("--grasp", type=int, default=0, help="the grasp: 0-3 the named ones (sim_assets/grasps.yaml), N >= 4 drawn with seed N for the person's hand")
    p.add_argument("--mass", type=int, default=0, help="index into sim_assets/masses.yaml")
    p.add_argument("--seed", type=int, default=0, help="random seed")
    p.add_argument("--view", type=int, default=0,
                   help="the camera's pose: 0 the paper's set-up (sim_assets/camera.yaml), N >= 1 drawn around it with seed N")
    p.add_argument("--duration", type=float, default=None, help="episode length in seconds, up to 120 (default: the task's)")
    p.add_argument("--out", type=pathlib.Path, default=None,
                   help="output directory (default: runs/<task>-u<user>-g<grasp>-m<mass>-s<seed>, then -v<view>, "
                        "-<hand surface>, -<grip control> where not the default, and -o<digest> when any other "
                        "option that changes the result is not its default; the options go into options.json)")
    p.add_argument("--force", action="store_true",
                   help="replace an output folder of fsv-bench's that was made with other options (or holds no "
                        "options.json); without it that is refused")
    p.add_argument("--quiet", action="store_true", help="no progress bars")
    p.add_argument("--no-pictures", action="store_true",
                   help="draw no pictures (the depth and colour previews, the tracking overlay, Fig. 4, Fig. 5): "
                        "the episode, summary.json and the tables only, every number the same (for batch runs and CI)")
    for stage in STAGES:
        stage.add_arguments(p)
    add_method_arguments(p, oracle=False, internal_model=False)
    return p


def scenario_from_args(args: argparse.Namespace) -> Scenario:
    """The scenario of the command line, fully validated (raises ScenarioError)."""
    sc = _scenario(args)
    validate(sc)
    return sc


def _scenario(args: argparse.Namespace) -> Scenario:
    return Scenario(task=args.task, user=args.user, grasp=args.grasp, mass=args.mass, noise_m=args.noise,
                    seed=args.seed, duration_s=args.duration, sensor=args.sensor, view=args.view,
                    hand_surface=args.hand_surface, grip_control=args.grip_control)


PRESENTATION_OPTIONS = ("help", "out", "force", "quiet", "no_gif", "no_pictures")
"""The main command's options that change no number of a run (where it goes, what is printed,
which pictures are drawn); every other option changes the result and is recorded in ``options.json``."""
OPTIONS_FILE = "options.json"
"""The file of a run folder that records the options of the run that wrote it (:func:`run_options`)."""


def run_options(parser: argparse.ArgumentParser, args: argparse.Namespace) -> dict:
    """Every option of ``parser`` that changes the result (all but :data:`PRESENTATION_OPTIONS`),
    with its value in ``args``: what ``options.json`` records."""
    return {a.dest: _plain(getattr(args, a.dest)) for a in parser._actions if a.dest not in PRESENTATION_OPTIONS}


def default_out(parser: argparse.ArgumentParser, args: argparse.Namespace) -> pathlib.Path:
    """``runs/<episode name>`` (:func:`benchmark.world.scenario.episode_name`), and ``-o<digest>``
    when options the name does not show (:func:`run_options`: the sensor, the noise, the duration,
    the method's stages, knowledge and protocol, the gates, ...) are not their defaults, so that
    runs with other options never share a folder. The README's ``fsv-bench --task lift --noise
    0.01`` (every default) writes ``runs/lift-u0-g0-m0-s0``."""
    defaults = argparse.Namespace(**{a.dest: a.default for a in parser._actions})
    options, default_options = run_options(parser, args), run_options(parser, defaults)
    plain = episode_name(_scenario(defaults))
    hidden = {}
    for k, v in options.items():
        if v == default_options[k]:
            continue
        try:  # an option the episode name shows on its own (the person, the view, ...) needs no digest
            shown = episode_name(_scenario(argparse.Namespace(**{**vars(defaults), k: getattr(args, k)}))) != plain
        except ScenarioError:
            shown = False
        if not shown:
            hidden[k] = v
    name = episode_name(_scenario(args))
    if hidden:
        name += "-o" + hashlib.sha256(json.dumps(hidden, sort_keys=True).encode()).hexdigest()[:8]
    return pathlib.Path("runs") / name


def check_same_options(out: pathlib.Path, options: dict, force: bool, defaults: dict | None = None) -> None:
    """Refuses (ValueError, one line) to replace a run folder of fsv-bench's whose ``options.json``
    differs from ``options``, or that has none (a run of an earlier fsv-bench or another command),
    unless ``force``. A new or empty folder, or one of the same options, is replaced silently; an
    option the file does not record (one added since) counts at its value in ``defaults``."""
    if force or not out.is_dir() or out.is_symlink() or not any(out.iterdir()):
        return
    try:
        recorded = json.loads((out / OPTIONS_FILE).read_text()).get("options")
    except (OSError, ValueError, AttributeError):
        recorded = None
    if isinstance(recorded, dict) and defaults:
        recorded = {**{k: v for k, v in defaults.items() if k in options}, **recorded}
    if recorded == options:
        return
    if recorded is None:
        why = f"holds no readable {OPTIONS_FILE} (a run of an earlier fsv-bench, or another command's output)"
    else:
        changed = sorted(k for k in set(options) | set(recorded) if options.get(k) != recorded.get(k))
        why = "was made with other options (" + ", ".join(
            f"--{k.replace('_', '-')} {recorded.get(k)!r}, now {options.get(k)!r}" for k in changed) + ")"
    raise ValueError(f"--out {out}: {why}; give another --out, or --force to replace it")


def _plain(value):
    """An option's value as JSON has it (a path as its text, a tuple as a list)."""
    if isinstance(value, tuple):
        return [_plain(v) for v in value]
    return str(value) if isinstance(value, pathlib.PurePath) else value


def method_spec_from_args(args: argparse.Namespace):
    """The method of the command line (``--kinematics``/``--contacts`` ablations, replaced stages,
    ``--internal-model``), loaded and checked; raises ValueError naming a bad option."""
    if args.differentiator and args.kinematics != "algebraic":
        raise ValueError(f"--kinematics {args.kinematics} and --differentiator {args.differentiator}: give one of them")
    differentiator = args.differentiator or (args.kinematics if args.kinematics in ("central", "gaussian") else None)
    oracle = [name for name, on in (("kinematics", args.kinematics == "oracle"), ("contacts", args.contacts == "oracle"))
              if on]
    return spec_from_args(argparse.Namespace(**{**vars(args), "differentiator": differentiator, "oracle": ",".join(oracle)}))


def run_stages(record: Run, args: argparse.Namespace, background: Background) -> tuple:
    """Runs every stage on ``record``; returns ``(parts, timing_s, last record)``.

    Files go into ``record.out``; pictures (and the episode archive) are started on ``background``.
    ``parts`` holds, in order, each stage's :class:`~benchmark.commands.stage.StageResult` and the
    jobs it left running (``later``): :func:`finish_stages` joins them once ``background`` is done.
    """
    parts, timing = [], {}
    record = dataclasses.replace(record, background=background)
    if not args.no_pictures:
        # the pictures' library, imported while the first stages work, before any child is forked: the
        # render stage's depth preview (in a child beside the tracker) and every later figure inherit
        # it. Imported after the first stage, it was imported twice, in that child and here (0.1 s of CPU)
        background.preload("matplotlib.pyplot")
    for stage in STAGES:
        t0 = time.perf_counter()
        result = stage(record, args)
        record = dataclasses.replace(record, **result.updates())
        complete(result, record.out, background)
        parts += [result, *result.later]
        timing[stage.name] = time.perf_counter() - t0
    return parts, timing, dataclasses.replace(record, background=None)


def finish_stages(parts: list, record: Run) -> tuple:
    """``(summary, lines, digests, record)`` of the stages' ``parts`` (:func:`run_stages`), their
    later jobs' results in their place (call it after the background is done: a failed job raises
    BenchmarkError); the record holds the episode the last of them completed."""
    summary, lines, digests = {}, [], {}
    for part in parts:
        result = part if isinstance(part, StageResult) else part.result()
        if not isinstance(result, StageResult):
            raise TypeError(f"a later job returned {type(result).__name__}, not a StageResult")
        summary.update(result.blocks)
        lines += result.lines
        digests.update(result.digests)
        if result.episode is not None and part is not result:
            record = dataclasses.replace(record, episode=result.episode)
    return summary, lines, digests, record


def main(argv: list | None = None) -> int:
    """Entry point of ``fsv-bench``; returns the exit status."""
    argv = sys.argv[1:] if argv is None else list(argv)
    if argv and argv[0] in SUBCOMMANDS:
        return run_subcommand(argv)
    if argv and argv[0] in ALL_SUBCOMMANDS:  # a floor above this module: the console script runs it
        print(f"fsv-bench: error: {argv[0]} is run by the console script (benchmark.commands.entry.run), "
              f"not by benchmark.commands.cli.main", file=sys.stderr)
        return 2
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        scenario = scenario_from_args(args)
        spec = method_spec_from_args(args)
        check_people((scenario.user,), spec.protocol)
        if args.gates:
            load_gates(args.gates)
        out = args.out or default_out(parser, args)
        check_out(out)
        options = run_options(parser, args)
        defaults = argparse.Namespace(**{a.dest: a.default for a in parser._actions})
        check_same_options(out, options, args.force, run_options(parser, defaults))
    except (ScenarioError, InputError, ValueError) as e:
        print(f"fsv-bench: error: {e}", file=sys.stderr)
        return 2
    if note := split_note(scenario):
        print(note, file=sys.stderr)
    # Every file goes into a temporary sibling folder, moved into place only when the run is complete:
    # an interrupted or failed run leaves the previous output folder as it was.
    tmp = staging_folder(out)
    background = Background()
    start = time.perf_counter()
    try:
        record = Run(scenario=scenario, out=tmp, method_spec=spec, quiet=args.quiet)
        parts, timing, record = run_stages(record, args, background)
        t0 = time.perf_counter()
        background.wait()
        summary, lines, known, record = finish_stages(parts, record)
        timing["wait_background"] = time.perf_counter() - t0
        timing["total"] = time.perf_counter() - start
        summary["digests"] = stage_digests(record.episode, record.estimate, known)
        summary["timing_s"] = timing
        summary["provenance"] = provenance()
        write_json(tmp / "summary.json", summary)
        write_json(tmp / OPTIONS_FILE, {"options": options})
        swap_folder(tmp, out)
    except BaseException as e:
        background.cancel()
        shutil.rmtree(tmp, ignore_errors=True)
        return exit_status(e, "fsv-bench", f"{out} is as it was before the run", (ScenarioError, InputError))
    sc, person, grasp = scenario, summary["scenario"]["person"], summary["scenario"]["grasp_spec"]
    hand = person["anatomy"]
    print(f"fsv-bench: task {sc.task}, user {sc.user} ({person['name']}, hand {1e3 * hand['hand_length_m']:.0f} x "
          f"{1e3 * hand['hand_breadth_m']:.0f} mm), grasp {sc.grasp} ({grasp['name']}), mass {sc.mass}, seed {sc.seed}, "
          f"view {sc.view}, sensor {sc.sensor}, hand seen as {sc.hand_surface}, grip {sc.grip_control}, noise {sc.noise_m} m, {len(record.episode.truth.t)} frames")
    for line in lines:
        print(line.replace(str(tmp), str(out)))
    print(f"episode: {out / 'episode.npz'}\nsummary: {out / 'summary.json'} ({timing['total']:.1f} s)")
    failed = [g["name"] for g in summary["verdict"]["gates"] if not g["passed"]]
    if failed:
        print(f"fsv-bench: {len(failed)} gate(s) failed: {'; '.join(failed)}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
