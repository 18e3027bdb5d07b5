"""``fsv-bench train``: fit the internal-force networks on a generated dataset and save them.

    fsv-bench train --data DIR --out model.npz [--seeds 0-2] [--epochs 1500] [--folds 5] [--members 5]
                    [--amount-loss squared|relative] [--grip grip_calibration.json]

Runs k-fold cross-validation (folds made of whole episodes) to report the expected error, then
trains on every selected sample and saves the model with its normalisation and a description of
the data and command (:meth:`fsv.learn.InternalForceModel.save`, atomic). Samples: those of the
dataset (the paper's rule) that also pass the plausibility rule
(:func:`benchmark.scores.samples.nominal_excess_n`, ``--max-excess``, a number >= 0 N; inf turns it off). With
``--grip`` (a file of ``fsv-bench calibrate``), the networks also take the grip calibration of each
sample's user (``LearnConfig.grip_inputs``).
"""

from __future__ import annotations

import argparse
import json
import sys
import time

import numpy as np

from benchmark.atomic import OUT_AS_IT_WAS, check_file_out
from benchmark.limits import MAX_EPOCHS, MAX_FOLDS, MAX_MEMBERS, MAX_SEED, integer
from benchmark.method.grip_file import CalibrationError, read_calibration
from benchmark.paper.dataset import finger_names_of, load_dataset, training_set
from benchmark.paper.dataset.cli import parse_ints
from benchmark.paper.dataset.files import read_header
from benchmark.paper.table2 import TABLE2_MEMBERS, add_max_excess_argument
from fsv.errors import InputError
from fsv.learn import AMOUNT_LOSSES, LearnConfig, cross_validate, train

INTERRUPTED = f"{OUT_AS_IT_WAS} (the same command again trains from the start)"
"""What Ctrl-C leaves, as the interrupted command says it (`fsv-bench <sub-command>: interrupted; ...`)."""


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--data", required=True, help="dataset folder made by `fsv-bench generate`")
    p.add_argument("--out", required=True, help="model file to write (.npz); an existing file needs --force")
    p.add_argument("--force", action="store_true", help="replace --out if it exists (without it an existing file is refused)")
    p.add_argument("--seeds", default=None, help="episode seeds to train on (default: all)")
    p.add_argument("--users", default=None, help="people to train on, e.g. 1000-1019 (default: all)")
    p.add_argument("--epochs", type=integer(1, MAX_EPOCHS), default=LearnConfig.epochs,
                   help=f"Rprop epochs per network, 1 to {MAX_EPOCHS:,} (default {LearnConfig.epochs})")
    p.add_argument("--folds", type=folds, default=LearnConfig.folds,
                   help=f"cross-validation folds, 2 to {MAX_FOLDS} and at most the dataset's episodes (0: skip; "
                        f"default {LearnConfig.folds})")
    p.add_argument("--seed", type=integer(0, MAX_SEED), default=0, help=f"seed of the initial weights, 0 to {MAX_SEED}")
    p.add_argument("--quiet", action="store_true", help="no progress bar (it is also hidden when stderr is not a terminal)")
    p.add_argument("--members", type=integer(1, MAX_MEMBERS), default=TABLE2_MEMBERS,
                   help=f"networks per ANN, averaged, 1 to {MAX_MEMBERS} (default {TABLE2_MEMBERS}; 1 = the paper's "
                        "single pair)")
    p.add_argument("--amount-loss", choices=AMOUNT_LOSSES, default=LearnConfig.amount_loss,
                   help="ANN_L2's training loss: squared (the paper's) or relative (|a_hat - a| / a, as the forces "
                        f"are scored; default {LearnConfig.amount_loss})")
    p.add_argument("--grip", default=None, metavar="FILE",
                   help="grip-calibration file (`fsv-bench calibrate`): the networks also take each sample's user's "
                        "grip line (default: none, user-blind as in the paper)")
    add_max_excess_argument(p)


def folds(text: str) -> int:
    """``--folds``: 0 (no cross-validation) or 2 to ``MAX_FOLDS``."""
    value = integer(0, MAX_FOLDS)(text)
    if value == 1:
        raise argparse.ArgumentTypeError(f"expected 0 (skip) or an integer from 2 to {MAX_FOLDS}, got {text!r}")
    return value


def check_training_people(users) -> None:
    """Raises InputError if any of ``users`` is a dev or test person (they choose and score, never train)."""
    from benchmark.suites.splits import SPLITS  # lazy: scipy.stats (0.4 s) off `fsv-bench train`'s start-up

    for name in ("dev", "test"):
        bad = sorted(int(u) for u in users if SPLITS[name].holds(u))
        if bad:
            raise InputError(f"the dataset holds {name} people ({bad[0]}{'...' if len(bad) > 1 else ''}), who never "
                             f"train a model; accepted: training people (1000 and above, `fsv-bench generate --split "
                             f"train`) and the named cohort; select them with --users")


def run(args: argparse.Namespace):
    check_file_out(args.out, force=args.force)
    where = {} if args.seeds is None else dict(seed=list(parse_ints(args.seeds, "--seeds")))
    if args.users is not None:
        where["user"] = list(parse_ints(args.users, "--users"))
    rule = None if not np.isfinite(args.max_excess) else args.max_excess
    try:
        grips = None if args.grip is None else read_calibration(args.grip)
    except CalibrationError as e:
        raise InputError(f"--grip: {e}") from e
    df = load_dataset(args.data, max_excess_n=rule, **where)
    header = read_header(args.data)  # before any training: a damaged header is refused at once
    check_training_people(df["user"].unique())
    data = training_set(df, grips)
    episodes = int(df["episode"].nunique())
    if args.folds and not 2 <= args.folds <= episodes:
        raise InputError(f"--folds {args.folds} needs between 2 and the dataset's {episodes} episodes; "
                         f"pass --folds {min(max(episodes, 2), 5)} or --folds 0 to skip cross-validation")
    config = LearnConfig(epochs=args.epochs, folds=max(args.folds, 2), seed=args.seed, members=args.members,
                         amount_loss=args.amount_loss, grip_inputs=grips is not None)
    from tqdm import tqdm  # lazy: tqdm (30 ms) off `fsv-bench train`'s start-up

    t0 = time.perf_counter()
    per_model = 2 * config.members * config.epochs  # epochs of every network of one model
    bar = tqdm(total=per_model * ((args.folds if args.folds else 0) + 1), desc="train", unit="epoch", leave=False,
               disable=True if args.quiet else None, mininterval=0.5)  # None: hidden when stderr is not a terminal
    try:
        cv = cross_validate(data, config, on_epoch=bar.update).summary() if args.folds else None
        meta = dict(
            command="fsv-bench train " + " ".join(sys.argv[2:]) if sys.argv[1:2] == ["train"] else "fsv.learn.train",
            dataset=header["spec"], selection=where, max_excess_n=rule, episodes=int(df["episode"].nunique()),
            cross_validation=cv,
        )
        if grips is not None:
            with open(args.grip) as fh:
                meta["grip_calibration"] = {k: v for k, v in json.load(fh).items() if k != "provenance"}
        model = train(data, config, finger_names=finger_names_of(df), metadata=meta, on_epoch=bar.update)
    finally:
        bar.close()
    model.save(args.out)
    msg = f"trained on {len(data)} samples from {meta['episodes']} episodes in {time.perf_counter() - t0:.1f} s"
    if cv:
        msg += (f"; {cv['folds']}-fold CV: internal-force rel. error {cv['rel_err_pct_mean']:.1f} %, "
                f"L2 norm rel. error {cv['l2_rel_err_pct_mean']:.1f} %, share RMSE {cv['share_rmse_mean']:.3f}")
    print(msg + f"; saved {args.out}")
    return model
