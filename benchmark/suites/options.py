"""The command-line options every suite command shares, declared once: ``--suite --sensor --hand-surface
--grip-control --out --cache --workers --quiet``
(and ``--no-baselines`` for the commands that score one method)."""

from __future__ import annotations

import argparse
import pathlib

from benchmark.limits import MAX_WORKERS, check_grid, folder, integer, parsed
from benchmark.suites.registry import SUITES, get_suite
from fsv.types import STREAMS, check_streams


def add_suite_arguments(p: argparse.ArgumentParser, *, out_help: str, sensor: bool = True, workers: bool = True) -> None:
    """Adds ``--suite``, ``--out`` (described by ``out_help``), ``--cache``, ``--quiet`` and, unless
    turned off, ``--sensor``, ``--hand-surface``, ``--grip-control`` and ``--workers``."""
    p.add_argument("--suite", required=True, help=f"suite name ({', '.join(SUITES)})")
    if sensor:
        p.add_argument("--sensor", default=None, help="depth sensor preset replacing the suite's (ds325, kinect-v1, ideal)")
        p.add_argument("--hand-surface", default=None,
                       help="what the camera sees of the hand, replacing the suite's: capsules (the collision "
                            "primitives), skin (the person's skin, benchmark.world.skin) or skin-rigid (its pulps rigid)")
        p.add_argument("--grip-control", default=None,
                       help="how the simulated people control the grip, replacing the suite's: per-digit (the world's) or whole-hand "
                            "(benchmark.world.grip)")
    p.add_argument("--out", required=True, type=pathlib.Path, help=out_help)
    p.add_argument("--cache", default=None, type=folder,
                   help="episode cache, a folder (default: ~/.cache/fsv-bench/episodes)")
    if workers:
        p.add_argument("--workers", type=integer(1, MAX_WORKERS), default=1,
                       help=f"local worker processes over episodes, 1 to {MAX_WORKERS} (default 1)")
    p.add_argument("--quiet", action="store_true", help="no progress bar")


def add_baseline_argument(p: argparse.ArgumentParser) -> None:
    """Adds ``--no-baselines``: skip the trivial baselines scored beside the method for its skill."""
    p.add_argument("--no-baselines", action="store_true",
                   help="do not score the trivial baselines beside the method (report.md then gives no skill)")


def suite_of(args: argparse.Namespace):
    """The suite a command's arguments name, with ``--sensor``, ``--hand-surface`` and
    ``--grip-control`` applied where the command has them (``benchmark.suites.registry.get_suite``;
    raises its ValueError, and ``benchmark.limits.RangeError`` for a suite of more than
    ``benchmark.limits.MAX_EPISODES`` episodes)."""

    suite = get_suite(args.suite, getattr(args, "sensor", None), getattr(args, "hand_surface", None),
                      getattr(args, "grip_control", None))
    check_grid({f"--suite {args.suite}": len(suite.scenarios)})
    return suite


def add_streams_argument(p) -> None:
    """``--streams depth,colour``: the camera streams to render and hand over, beyond what the method reads."""
    p.add_argument("--streams", default=("depth",), metavar=",".join(STREAMS), type=parsed(check_streams),
                   help="camera streams to record, comma-separated, beyond those the method declares it reads: "
                        f"{', '.join(STREAMS)} (the depth always); default depth")
