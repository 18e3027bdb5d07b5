"""``fsv-bench train-direct``: train the end-to-end force network on a dataset of every frame and save it.

    fsv-bench train-direct --data DIR --out model.npz [--users ...] [--seeds ...] [--epochs 60]
                           [--hidden 128,128] [--window 0] [--batch 256] [--lr 0.001] [--val-fraction 0.1]

The dataset must hold every frame with kinematics (``fsv-bench generate --rows all``); one of the
paper's rows is refused, as it keeps only the frames the internal-force networks learn from. Each
row gives the network's inputs (:func:`fsv.learn.direct_inputs`, from the row's kinematics and
contacts and the episode's box) and its targets: each finger's true 3D force and the table's
wrench on the box, both in the object frame (``F_true_*``, ``env_F_*``, ``env_T_*``). The model
(:class:`fsv.learn.DirectForceModel`) is trained by :func:`fsv.learn.train_direct` and saved with
a description of the data and the command; ``fsv-bench --method direct --direct-model FILE`` runs it.
"""

from __future__ import annotations

import argparse
import sys

import numpy as np
import pandas as pd
from tqdm import tqdm

from benchmark.atomic import OUT_AS_IT_WAS, check_file_out
from benchmark.limits import MAX_EPOCHS, MAX_SEED, integer, number
from benchmark.paper.dataset import finger_names_of, frames_of, load_dataset
from benchmark.paper.dataset.cli import parse_ints
from benchmark.paper.dataset.files import read_header
from benchmark.paper.table2 import object_models
from benchmark.paper.training import check_training_people
from fsv.errors import InputError
from fsv.learn import DirectConfig, DirectSamples, direct_inputs, train_direct
from fsv.learn.direct import on_table
from fsv.learn.direct_inputs import MAX_WINDOW, input_names
from fsv.types import Contacts, Kinematics

INTERRUPTED = f"{OUT_AS_IT_WAS} (the same command again trains from the start)"
"""What Ctrl-C leaves, as the interrupted command says it (`fsv-bench <sub-command>: interrupted; ...`)."""

_AX = "xyz"
MAX_BATCH = 65_536
MAX_WIDTH = 4096
MAX_LAYERS = 8


def hidden_sizes(text: str) -> tuple:
    """``--hidden``: comma-separated layer sizes, e.g. ``128,128`` (1 to 8 layers of 1 to 4096)."""
    try:
        sizes = tuple(int(v) for v in text.split(","))
    except ValueError:
        sizes = ()
    if not 1 <= len(sizes) <= MAX_LAYERS or any(not 1 <= s <= MAX_WIDTH for s in sizes):
        raise argparse.ArgumentTypeError(f"expected 1 to {MAX_LAYERS} comma-separated layer sizes from 1 to "
                                         f"{MAX_WIDTH:,}, got {text!r}")
    return sizes


def add_arguments(p: argparse.ArgumentParser) -> None:
    d = DirectConfig()
    p.add_argument("--data", required=True, help="dataset folder made by `fsv-bench generate --rows all`")
    p.add_argument("--out", required=True, help="model file to write (.npz); an existing file needs --force")
    p.add_argument("--force", action="store_true", help="replace --out if it exists")
    p.add_argument("--seeds", default=None, help="episode seeds to train on (default: all)")
    p.add_argument("--users", default=None, help="people to train on, e.g. 1000-1039 (default: all)")
    p.add_argument("--epochs", type=integer(1, MAX_EPOCHS), default=d.epochs,
                   help=f"passes over the samples, 1 to {MAX_EPOCHS:,} (default {d.epochs})")
    p.add_argument("--hidden", type=hidden_sizes, default=d.hidden,
                   help=f"hidden layer sizes, e.g. 128,128 (1 to {MAX_LAYERS} layers of 1 to {MAX_WIDTH:,}; default "
                        f"{','.join(map(str, d.hidden))})")
    p.add_argument("--window", type=integer(0, MAX_WINDOW), default=d.window,
                   help=f"frames of kinematics on either side among the inputs, 0 to {MAX_WINDOW} (default {d.window})")
    p.add_argument("--batch", type=integer(1, MAX_BATCH), default=d.batch,
                   help=f"samples per Adam step, 1 to {MAX_BATCH:,} (default {d.batch})")
    p.add_argument("--lr", type=number(1e-8, 1.0), default=d.lr, help=f"Adam's step size, 1e-08 to 1 (default {d.lr:g})")
    p.add_argument("--val-fraction", type=number(0.0, 0.9), default=d.val_fraction,
                   help=f"share of the episodes held out to choose the epoch, 0 to 0.9 (default {d.val_fraction:g})")
    p.add_argument("--seed", type=integer(0, MAX_SEED), default=d.seed, help=f"seed of the training, 0 to {MAX_SEED}")
    p.add_argument("--quiet", action="store_true", help="no progress bar (also hidden when stderr is not a terminal)")


def check_all_rows(data) -> dict:
    """The dataset's header; InputError (one line) unless it was made with ``--rows all``."""
    header = read_header(data)
    if header["spec"].get("rows", "paper") != "all":
        raise InputError(f"--data {data}: a dataset of the paper's rows only; the direct network learns from every "
                         f"frame: make one with `fsv-bench generate --rows all ...`")
    return header


def direct_samples(df: pd.DataFrame, models: dict, config: DirectConfig) -> tuple[DirectSamples, tuple]:
    """The network's samples of a dataset table of every frame (``--rows all``).

    Args:
        df: Rows of one or more episodes (:func:`benchmark.paper.dataset.load_dataset` with ``rows="all"``).
        models: ``{episode: (ObjectModel, gravity)}`` (:func:`benchmark.paper.table2.object_models`).
        config: The inputs' window and the off-table height.

    Returns:
        ``(samples, finger names)``: one sample per row with finite inputs (every row of such a
        dataset, whose rows have kinematics; a tracked contact without a point would be left out),
        in the table's order.
    """
    names = finger_names_of(df)
    xs, order = [], []
    for episode, rows in df.groupby("episode", sort=False):
        om, gravity = models[episode]
        kin, con = _timeline(rows)
        x, _ = direct_inputs(kin, con, om, gravity, window=config.window)
        xs.append(x[rows["frame"].to_numpy()])
        order.append(rows.index.to_numpy())
    x = np.concatenate(xs)[np.argsort(np.concatenate(order), kind="stable")]
    keep = np.all(np.isfinite(x), axis=1)
    df, x = df[keep], x[keep]
    force = np.concatenate([df[[f"F_true_{a}_{n}" for a in _AX]].to_numpy(float) for n in names], axis=1)
    table = df[[f"env_{q}_{a}" for q in "FT" for a in _AX]].to_numpy(float)
    active = df[[f"active_{n}" for n in names]].to_numpy(bool)
    height = x[:, input_names(names, config.window).index("height")]
    mask = np.concatenate([np.repeat(active, 3, axis=1), np.repeat(on_table(height, config.off_table_m)[:, None], 6,
                                                                     axis=1)], axis=1)
    groups = pd.factorize(df["episode"])[0]
    return DirectSamples(x, np.concatenate([force, table], axis=1), mask, groups), names


def _timeline(rows: pd.DataFrame) -> tuple[Kinematics, Contacts]:
    """An episode's rows placed at their frames (``frame`` column) on a timeline 0..max frame; the
    frames without a row have no kinematics and no contact."""
    kin, con = frames_of(rows)
    frames = rows["frame"].to_numpy()
    T = int(frames.max()) + 1

    def place(v, fill):
        out = np.full((T, *v.shape[1:]), fill, dtype=v.dtype)
        out[frames] = v
        return out

    t = np.arange(T, dtype=float)
    t[frames] = kin.t
    kin = Kinematics(t, place(kin.pos, np.nan), place(kin.rot, np.nan), place(kin.vel, np.nan), place(kin.acc, np.nan),
                     place(kin.omega, np.nan), place(kin.alpha, np.nan), place(kin.valid, False), method=kin.method)
    con = Contacts(con.finger_names, place(con.active, False), place(con.sliding, False), place(con.point, 0.0),
                   place(con.normal, 0.0), place(con.slide_dir, 0.0))
    return kin, con


def train_on(datasets, config: DirectConfig, *, where: dict | None = None, command: str = "fsv.learn.train_direct",
             on_epoch=None, timing: dict | None = None):
    """Trains the direct network on the rows of one or more datasets of every frame.

    Args:
        datasets: Dataset folders made with ``fsv-bench generate --rows all`` (their episodes are
            taken in this order; an episode name in two of them is refused).
        config: The network and its training (:class:`fsv.learn.DirectConfig`).
        where: Row selection, e.g. ``{"user": [1000, 1001], "seed": [100]}``.
        command: The command line stored in the model's metadata.
        on_epoch, timing: As :func:`fsv.learn.train_direct`.

    Returns:
        The model (:class:`fsv.learn.DirectForceModel`).

    Raises:
        InputError: A dataset of the paper's rows only, an episode in two datasets, or a dev or
            test person among the selected rows (one line each).
    """
    datasets = [str(d) for d in datasets]
    where = dict(where or {})
    headers = [check_all_rows(d) for d in datasets]
    frames, models = [], {}
    for d in datasets:
        df = load_dataset(d, rows="all", **where)
        twice = sorted(set(df["episode"].unique()) & set(models))
        if twice:
            raise InputError(f"--data {d}: episode {twice[0]} is in another dataset too; accepted: datasets of "
                             "other episodes")
        models.update(object_models(d))
        frames.append(df)
    df = pd.concat(frames, ignore_index=True) if len(frames) > 1 else frames[0]
    check_training_people(df["user"].unique())
    samples, names = direct_samples(df, models, config)
    spec = headers[0]["spec"] if len(headers) == 1 else [h["spec"] for h in headers]
    meta = dict(command=command, dataset=spec, selection=where, episodes=int(df["episode"].nunique()),
                rows_left_out=int(len(df) - len(samples)))  # rows whose inputs are not all finite
    return train_direct(samples, names, config, metadata=meta, on_epoch=on_epoch, timing=timing)


def train_job(job: tuple) -> dict:
    """One model of a learning curve: ``job = (datasets, users, out, config)`` trains the network
    with ``config`` (keyword arguments of :class:`fsv.learn.DirectConfig`; ``{}``: the shipped
    model's choices) on ``users``' episodes of ``datasets`` and saves it to ``out``; returns what the
    curve reports of the training (episodes, samples, held-out samples, the epoch kept, counting
    from 1, parameters, seconds)."""
    datasets, users, out, config = job
    timing = {}
    model = train_on(datasets, DirectConfig(**config), where={"user": list(users)},
                     command=f"direct-curve: the first {len(users)} people", timing=timing)
    model.save(out)
    m = model.metadata
    return {"episodes": m["episodes"], "samples": m["samples"], "held_out_samples": m["held_out_samples"],
            "best_epoch": m["best_epoch"] + 1, "parameters": model.num_parameters, "train_seconds": timing["seconds"]}


def run(args: argparse.Namespace):
    check_file_out(args.out, force=args.force)
    where = {} if args.seeds is None else dict(seed=list(parse_ints(args.seeds, "--seeds")))
    if args.users is not None:
        where["user"] = list(parse_ints(args.users, "--users"))
    config = DirectConfig(hidden=args.hidden, window=args.window, epochs=args.epochs, batch=args.batch, lr=args.lr,
                          val_fraction=args.val_fraction, seed=args.seed)
    command = ("fsv-bench train-direct " + " ".join(sys.argv[2:]) if sys.argv[1:2] == ["train-direct"]
               else "fsv.learn.train_direct")
    timing = {}
    with tqdm(total=config.epochs, desc="train-direct", unit="epoch", leave=False, disable=True if args.quiet else None,
              mininterval=0.5) as bar:
        model = train_on([args.data], config, where=where, command=command, on_epoch=bar.update, timing=timing)
    seconds = timing["seconds"]
    model.save(args.out)
    m = model.metadata
    val = m["val_loss"][m["best_epoch"]]
    print(f"trained the direct network ({model.num_parameters:,} parameters, {model.num_inputs} inputs, hidden "
          f"{','.join(map(str, config.hidden))}) on {m['samples']} samples of {m['episodes'] - m['held_out_episodes']} episodes "
          f"(and {m['held_out_samples']} samples of {m['held_out_episodes']} episodes held out) in {seconds:.1f} s on one "
          f"thread; epoch {m['best_epoch'] + 1} of {config.epochs} kept, standardised MSE "
          f"{m['train_loss'][m['best_epoch']]:.4f} on the training samples"
          + (f", {val:.4f} held out" if val is not None else "") + f"; saved {args.out}")
    return model
