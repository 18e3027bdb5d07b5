"""``fsv-bench generate``: training data for the internal-force networks (:mod:`benchmark.paper.dataset`).

    fsv-bench generate --out DIR [--split train|dev|test] [--design grid|people]
                       [--tasks ... --users ... --grasps ... --views ... --masses ... --seeds ...]

With ``--split``, ``--users``, ``--grasps`` and ``--views`` are positions in that split
(``benchmark.suites.splits``): ``--split train --users 0-79`` is people 1000-1079, none of whom
any dev or test episode meets. Training data comes from the training split (``fsv-bench train``
refuses dev and test people); a dev or test person is recorded only for their calibration
(``fsv-bench calibrate``), never scored. With ``--design people`` each person holds their own
grasp and view (``benchmark.paper.dataset.spec.DatasetSpec``):

    fsv-bench generate --split train --design people --users 0-39 --tasks lift,place,... --masses 0-5 --seeds 100

With ``--frames`` it writes every frame of the rendered streams (``--streams depth,colour``) with its
labels instead, one HDF5 shard per episode, an index, a dataset card and Croissant metadata
(:mod:`benchmark.paper.dataset.frames`); dev and test people are refused.
"""

from __future__ import annotations

import argparse
import pathlib
import time

import pandas as pd

from benchmark import limits
from benchmark.atomic import check_out
from benchmark.errors import DatasetError
from benchmark.paper.dataset.build import generate
from benchmark.paper.dataset.files import made_by_generate
from benchmark.paper.dataset.frames import FramesSpec, check_training_people, generate_frames, made_by_generate_frames
from benchmark.paper.dataset.shards import COLOUR_ENCODINGS
from benchmark.paper.dataset.spec import CONTACTS, DESIGNS, KINEMATICS, ROWS, DatasetSpec
from benchmark.parallel import check_ray_address

INTERRUPTED = "the complete episodes are kept: the same command again makes only the missing ones"
"""What Ctrl-C leaves, as the interrupted command says it (`fsv-bench <sub-command>: interrupted; ...`)."""


def parse_ints(text: str, option: str = "") -> tuple:
    """Parses "0,2,5-7" into (0, 2, 5, 6, 7); DatasetError naming ``option`` for anything but
    non-negative integers and ascending ranges, or more than ``benchmark.limits.MAX_EPISODES`` values
    (counted before they are built)."""
    try:
        return limits.parse_ints(text, option or "list")
    except limits.RangeError as e:
        raise DatasetError(str(e)) from None


def grid_size(args: argparse.Namespace) -> int:
    """The number of episodes the command line asks for, from the counts of its ranges (nothing
    built); DatasetError above ``benchmark.limits.MAX_EPISODES``."""
    counts = {"--tasks": len([t for t in args.tasks.split(",") if t.strip()])}
    names = ("--users", "--seeds") if args.design == "people" else ("--users", "--grasps", "--views", "--masses", "--seeds")
    try:
        counts.update({name: limits.count_ints(getattr(args, name[2:]), name) for name in names})
        return limits.check_grid(counts)
    except limits.RangeError as e:
        raise DatasetError(str(e)) from None


def add_arguments(p: argparse.ArgumentParser) -> None:
    """The arguments of ``fsv-bench generate``."""
    p.add_argument("--out", required=True,
                   help="dataset folder (created, or resumed if generate made it; a folder with other files is refused)")
    p.add_argument("--tasks", default="lift", help="comma-separated task names (default: lift)")
    p.add_argument("--split", default=None, metavar="train|dev|test",
                   help="draw people, grasps and views from a split: --users/--grasps/--views are then positions "
                        "in it (train: 0 is index 1000); `fsv-bench train` refuses dev and test people, whose "
                        "recordings are for calibration only")
    p.add_argument("--design", default="grid", metavar="|".join(DESIGNS),
                   help="grid: every combination; people: each user with their own grasp and view through every "
                        "task and seed, the masses rotating (default: grid)")
    p.add_argument("--users", default="0", help="user indices, e.g. 0,1 or 0-3 (N >= 5: drawn people)")
    p.add_argument("--grasps", default="0", help="grasp indices (N >= 4: drawn grasps)")
    p.add_argument("--views", default="0", help="camera views (0: the paper's set-up; N >= 1 drawn)")
    p.add_argument("--masses", default="0", help="mass indices")
    p.add_argument("--seeds", default="0",
                   help=f"seeds, e.g. 0-9; the grid (tasks x users x grasps x views x masses x seeds, or users x "
                        f"tasks x seeds for --design people) holds at most {limits.MAX_EPISODES:,} episodes")
    p.add_argument("--duration", type=float, default=None, help="episode length in seconds, up to 120 (default: the task's)")
    p.add_argument("--noise", type=float, default=0.01,
                   help="depth noise in metres, 0 to 0.1 (sets the pose errors; default 0.01)")
    p.add_argument("--kinematics", default="algebraic", choices=KINEMATICS, help="kinematics source (default: algebraic)")
    p.add_argument("--contacts", default="tracker", choices=CONTACTS,
                   help="contacts (and poses) source: tracker (render and track every episode, the method; "
                        "default), error-model (truth + the paper's contact error, tracker-like poses; cheaper) "
                        "or oracle (the truth's contacts; an ablation)")
    p.add_argument("--rows", default="paper", choices=ROWS,
                   help="paper: the frames the paper's sample rules keep (the internal-force networks' samples; "
                        "default); all: every frame with kinematics, with the column paper_rule marking the paper's "
                        "(the end-to-end network's samples, `fsv-bench train-direct`)")
    p.add_argument("--workers", type=limits.integer(1, limits.MAX_WORKERS), default=None,
                   help=f"local worker processes, 1 to {limits.MAX_WORKERS} (default: all cores)")
    p.add_argument("--ray-address", default=None, help="run on a Ray cluster at this address (needs the 'ray' extra)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.add_argument("--frames", action="store_true",
                   help="write the rendered frames and every per-frame label (forces, contacts, box and hand state, "
                        "keypoints, masks) as one HDF5 shard per episode, with index.parquet, README.md and "
                        "croissant.json, instead of the networks' features (training data: dev and test people refused)")
    from benchmark.suites.options import (  # lazy: scipy.stats (0.4 s) off `fsv-bench generate`'s start-up
        add_streams_argument,
    )

    add_streams_argument(p)
    p.add_argument("--colour-encoding", default="raw", choices=COLOUR_ENCODINGS,
                   help="with --frames --streams depth,colour: raw (lossless uint8, ~160 MB per 10 s episode) or "
                        "jpeg (quality 90, lossy, ~12 MB; for training data) (default: raw)")


def run(args: argparse.Namespace) -> pd.DataFrame:
    """Runs ``fsv-bench generate`` with parsed arguments; prints a one-paragraph summary."""
    grid_size(args)  # before any list is built
    if args.ray_address is not None:
        check_ray_address(args.ray_address)
    users, grasps, views = (parse_ints(getattr(args, name), f"--{name}") for name in ("users", "grasps", "views"))
    if args.split is not None:
        from benchmark.suites.splits import SPLITS  # lazy: scipy.stats (0.4 s) off `fsv-bench generate`'s start-up

        if args.split not in SPLITS or args.split == "cohort":
            raise DatasetError(f"--split {args.split!r}: accepted: train, dev, test")
        split = SPLITS[args.split]
        try:
            users, grasps, views = (tuple(split.index(p) for p in ps) for ps in (users, grasps, views))
        except ValueError as e:
            raise DatasetError(str(e)) from None
    spec = DatasetSpec(
        tasks=tuple(t.strip() for t in args.tasks.split(",") if t.strip()), users=users,
        grasps=grasps, masses=parse_ints(args.masses, "--masses"), seeds=parse_ints(args.seeds, "--seeds"), views=views, design=args.design,
        duration_s=args.duration,
        noise_m=args.noise, kinematics=args.kinematics, contacts=args.contacts, rows=args.rows,
    )

    if args.frames:
        if args.rows != "paper":
            raise DatasetError("--rows applies to the networks' features, not to --frames (whose shards hold every frame)")
        return run_frames(args, spec)
    if args.streams != ("depth",) or args.colour_encoding != "raw":
        raise DatasetError("--streams and --colour-encoding apply to --frames only (the features come from the depth)")
    if not made_by_generate(args.out):  # new, empty, or fsv-bench's: resumed, never a user's folder
        check_out(pathlib.Path(args.out), replace=False)
    t0 = time.perf_counter()
    man = generate(spec, args.out, workers=args.workers, ray_address=args.ray_address, progress=not args.no_progress)
    failed = int((man["status"] != "ok").sum())
    paper_rows = int((man["frames"] - man["dropped_contacts"] - man["dropped_gap"] - man["dropped_solver"]).sum())
    print(
        f"dataset {args.out}: {len(man)} episodes ({failed} failed), "
        + (f"{int(man['rows'].sum())} rows (every frame with kinematics), {paper_rows} of them kept by "
           "the paper's rule; " if spec.rows == "all" else f"{int(man['rows'].sum())} samples kept; ")
        + f"dropped {int(man['dropped_gap'].sum())} for |vision - tactile net force| > {spec.max_gap_n} N, "
        f"{int(man['dropped_contacts'].sum())} with < {spec.min_fingers} fingers or invalid kinematics, "
        f"{int(man['dropped_solver'].sum())} unsolved; kinematics={spec.kinematics}, contacts={spec.contacts} "
        f"(oracle = from the truth; error-model = truth + the paper's contact error; tracker = rendered and tracked); {time.perf_counter() - t0:.1f} s"
    )
    return man


def run_frames(args: argparse.Namespace, spec: DatasetSpec) -> pd.DataFrame:
    """``fsv-bench generate --frames``: a frames dataset (:func:`benchmark.paper.dataset.frames.generate_frames`)."""

    frames = FramesSpec(grid=spec, streams=args.streams, colour_encoding=args.colour_encoding)
    check_training_people(spec)  # before the folder is touched
    if not made_by_generate_frames(args.out):
        check_out(pathlib.Path(args.out), replace=False)
    t0 = time.perf_counter()
    index = generate_frames(frames, args.out, workers=args.workers, ray_address=args.ray_address,
                            progress=not args.no_progress)
    failed = int((index["status"] != "ok").sum())
    seconds = time.perf_counter() - t0
    print(f"frames dataset {args.out}: {len(index)} episodes ({failed} failed), {int(index['frames'].sum())} frames, "
          f"streams {', '.join(frames.streams)}, {index['bytes'].sum() / 1e6:.1f} MB; README.md and croissant.json "
          f"written; {seconds:.1f} s")
    return index
