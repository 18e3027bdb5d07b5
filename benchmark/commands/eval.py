"""``fsv-bench eval``: score the method on a suite and give a verdict for CI (see :mod:`benchmark.suites.evaluate`).

    fsv-bench eval --suite smoke --out DIR [--pictures worst|all] [...]

``--pictures all`` writes every episode's tracking overlay (with the truth) and Fig. 5 into
``DIR/pictures/``; ``worst`` those of the episodes that score worst on some gate's metric.
"""

from __future__ import annotations

import argparse
import tempfile

from benchmark.atomic import OUT_AS_IT_WAS_EPISODES_CACHED
from benchmark.commands.pictures.episodes import PICTURES, EpisodePictures, chosen
from benchmark.suites import evaluate as suite_eval

INTERRUPTED = OUT_AS_IT_WAS_EPISODES_CACHED
"""What Ctrl-C leaves, as the interrupted command says it (`fsv-bench <sub-command>: interrupted; ...`)."""


def add_picture_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--pictures", choices=PICTURES, default=None,
                   help="also write the tracking overlay and Fig. 5 of every episode (all) or of the episodes "
                        "worst on some gate's metric (worst) into DIR/pictures/")


def add_arguments(p: argparse.ArgumentParser) -> None:
    suite_eval.add_arguments(p)
    add_picture_arguments(p)


def run(args: argparse.Namespace) -> dict:
    if not args.pictures:
        return suite_eval.run(args)
    with tempfile.TemporaryDirectory(prefix="fsv-bench-pictures-") as folder:
        writer = EpisodePictures(folder)
        return suite_eval.run(args, observer=writer, pictures=chosen(writer, args.pictures))
