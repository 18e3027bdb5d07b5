"""The paper's Table 2 and Fig. 6: how well learned internal forces generalise (§4.3-4.4).

Two instances of the networks (:mod:`fsv.learn`) are trained on a dataset made by
:mod:`benchmark.paper.dataset`:

* *partial training*: one user, one grasp, one mass (``Table2Protocol.user/grasp/mass``);
* *full training*: every user, grasp and mass of the dataset.

Both train on the training seeds only and are evaluated on new episodes (the test seeds) of five
combinations, the paper's five rows (○ = the partial training set has it, × = it does not):

    user mass grasp
     ○    ○    ○      the training combination itself
     ×    ○    ○      another user
     ○    ×    ○      the box 10 % heavier
     ○    ○    ×      another grasp
     ×    ×    ×      all three changed

A diagnostic that is not in the paper: *same-user training*, every grasp and mass of the evaluated
row's user only. Our features, like the paper's, cannot tell users apart; where the synthetic
users grip differently, full training learns their average, and this column shows what is lost.
A second one, *user-blind ideal* (:func:`user_blind`): the decomposition's exact targets averaged
over the protocol's two users at the same frames, the best any predictor blind to the user can do
on average, every other error removed; full training can do better only insofar as its inputs
do tell the users apart.

For each evaluation frame, the networks' predicted internal normal forces go into the
reconstruction SOCP (eq. 14, :func:`fsv.forces.reconstruct_forces`), whose total normal force per
finger is compared with the truth's normal force (docs/design.md's metric; the paper used its tactile
readings, ours are those plus sensor noise):
the relative error of finger k at frame i with true normal force f >= 1 N is |f̂ - f| / f, in percent;
the table reports its mean and standard deviation over the scored (frame, finger) pairs.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import time
from dataclasses import asdict, dataclass

import numpy as np
import pandas as pd

from benchmark.atomic import OUT_AS_IT_WAS, check_out, save_figure, staged_folder, write_text
from benchmark.errors import DatasetError
from benchmark.limits import MAX_EPOCHS, MAX_MEMBERS, MAX_SEED, integer, number
from benchmark.paper.dataset import (
    finger_names_of,
    frames_of,
    load_dataset,
    read_episode_file,
    read_manifest,
    training_set,
)
from benchmark.paper.dataset.cli import parse_ints
from benchmark.paper.dataset.files import read_header
from benchmark.scores.samples import DATASET_FORCE_SETTINGS, MAX_EXCESS_N
from fsv import ObjectModel
from fsv.forces import FrameStatus, reconstruct_forces
from fsv.learn import InternalForceModel, LearnConfig, relative_errors_pct, train
from fsv.provenance import provenance

INTERRUPTED = OUT_AS_IT_WAS
"""What Ctrl-C leaves, as the interrupted command says it (`fsv-bench <sub-command>: interrupted; ...`)."""

#: The paper's Table 2: (user, mass, grasp seen in partial training; partial avg, std; full avg, std) [%].
PAPER = (
    (True, True, True, 10.7, 12.4, 9.71, 12.0),
    (False, True, True, 10.9, 12.3, 10.3, 11.8),
    (True, False, True, 10.8, 11.3, 10.4, 12.4),
    (True, True, False, 14.6, 14.5, 10.9, 11.3),
    (False, False, False, 14.9, 14.8, 9.94, 12.6),
)


TABLE2_MEMBERS = 5
"""Networks per ANN in ``fsv-bench table2`` (their predictions averaged, see :mod:`fsv.learn`)."""


@dataclass(frozen=True)
class Table2Protocol:
    """Which dataset slices train and evaluate.

    Attributes:
        user, grasp, mass: The partial training combination (indices into sim_assets lists).
        other_user, other_grasp: The held-out user and grasp of rows 2, 4 and 5. The default pair
            of users, u0 and u4, shares a grip intensity and differs in hand size, finger shares and
            timing, like the paper's users (see ``sim_assets/users.yaml``); ``--users 0,1`` puts a
            user who grips harder in their place.
        heavier_mass: The +10 % variant of ``mass`` (rows 3 and 5).
        train_seeds: Seeds of the training episodes.
        test_seeds: Seeds of the evaluation episodes (never trained on).
    """

    user: int = 0
    grasp: int = 0
    mass: int = 1
    other_user: int = 4
    other_grasp: int = 1
    heavier_mass: int = 4
    train_seeds: tuple = (0, 1, 2, 3)
    test_seeds: tuple = (4, 5)

    def rows(self) -> list[dict]:
        """The five evaluation combinations, in the paper's order."""
        out = []
        for seen_user, seen_mass, seen_grasp, *_ in PAPER:
            out.append(dict(
                user=self.user if seen_user else self.other_user,
                mass=self.mass if seen_mass else self.heavier_mass,
                grasp=self.grasp if seen_grasp else self.other_grasp,
            ))
        return out


def object_models(out) -> dict:
    """The object model and gravity of each episode of a dataset: ``{episode: (ObjectModel, gravity)}``."""

    models = {}
    for row in read_manifest(out).to_dict("records"):  # every file checked against its digests
        ep = row["episode"]
        _, meta, _ = read_episode_file(os.path.join(os.fspath(out), row["file"]), row["sha256"])
        if "object_model" in meta:
            om = meta["object_model"]
            models[ep] = (ObjectModel(**om), np.asarray(meta["gravity"], float))
    return models


def evaluate(model: InternalForceModel | None, df: pd.DataFrame, models: dict, predicted=None) -> dict:
    """Reconstructs full forces (eq. 14) from the model's predictions on the frames of ``df``.

    Args:
        model: Trained networks (None with ``predicted``).
        df: Dataset rows (any number of episodes).
        models: ``{episode: (ObjectModel, gravity)}`` (see :func:`object_models`).
        predicted: Internal normal forces to use instead of the model's, shape (len(df), K), [N].

    Returns:
        A dict with ``errors`` (relative errors in %, shape (M,)), per-row arrays ``t``,
        ``episode``, ``predicted_internal``, ``normal`` (reconstructed total normal force),
        ``measured`` (the truth's normal force), ``status``, and ``residual_rel`` (max relative Newton-Euler
        residual of the reconstruction over OPTIMAL frames).
    """
    names = finger_names_of(df)
    ts = training_set(df)
    if predicted is None:
        if tuple(names) != tuple(model.finger_names):
            raise DatasetError(f"the dataset's fingers {names} differ from the model's {model.finger_names}")
        _, _, pred = model.predict(ts.x, ts.active)
    else:
        pred = np.asarray(predicted, float)
        if pred.shape != ts.internal.shape:
            raise DatasetError(f"predicted must have shape {ts.internal.shape}, got {pred.shape}")
    normal = np.zeros_like(pred)
    status = np.zeros(len(df), np.int8)
    resid = 0.0
    for ep, idx in df.groupby("episode", sort=False).indices.items():
        obj, gravity = models[ep]
        kin, con = frames_of(df.iloc[idx])
        sol = reconstruct_forces(kin, con, obj, np.where(con.active, pred[idx], np.nan), gravity=gravity,
                                 settings=DATASET_FORCE_SETTINGS)  # the protocol of the committed Table 2
        normal[idx] = sol.normal_force
        status[idx] = sol.status
        ok = sol.status == int(FrameStatus.OPTIMAL)
        if ok.any():
            scale = np.maximum(np.linalg.norm(sol.required[ok], axis=1), 1.0)
            resid = max(resid, float(np.max(np.linalg.norm(sol.residual[ok], axis=1) / scale)))
    measured = df[[f"f_true_{n}" for n in names]].to_numpy(float)
    scored = ts.active & (status == int(FrameStatus.OPTIMAL))[:, None]
    return dict(
        errors=relative_errors_pct(normal, measured, scored), t=df["t"].to_numpy(), episode=df["episode"].to_numpy(),
        predicted_internal=pred, normal=normal, measured=measured, active=ts.active, status=status,
        residual_rel=resid, finger_names=names,
    )


def user_blind(df: pd.DataFrame, partner: pd.DataFrame) -> tuple[pd.DataFrame, np.ndarray]:
    """The ideal user-blind prediction: each frame's own decomposition targets averaged with those
    of the same frame of another user's episode (same task, grasp, mass and seed, hence the same
    planned motion), finger by finger where both touch the box.

    Features that do not tell two users apart (p1-p4 do not) cannot do better on average than
    predicting the same internal forces for both; this average is that prediction with every other
    error removed (each user's own contacts and kinematics, the exact targets). Networks trained on
    both users beat it only insofar as their inputs tell the users apart; a diagnostic that is not
    in the paper.

    Returns:
        ``(rows, predicted)``: the rows of ``df`` that have a partner frame, and the averaged
        internal normal forces for them, shape (N, K), [N].
    """
    names = finger_names_of(df)
    key = ["task", "grasp", "mass", "seed", "frame"]
    cols = [f"f_int_{n}" for n in names] + [f"active_{n}" for n in names]
    both = df.reset_index(drop=True).merge(partner[key + cols], on=key, how="inner", suffixes=("", "_partner"))
    own = both[[f"f_int_{n}" for n in names]].to_numpy(float)
    other = both[[f"f_int_{n}_partner" for n in names]].to_numpy(float)
    shared = both[[f"active_{n}_partner" for n in names]].to_numpy(bool)
    return both[df.columns].reset_index(drop=True), np.where(shared, (own + other) / 2, own)


def score(data, protocol: Table2Protocol = Table2Protocol(), config: LearnConfig = LearnConfig(),
          max_excess_n: float | None = MAX_EXCESS_N) -> dict:
    """Trains the partial and full networks on ``data`` and fills the five rows of Table 2.

    Args:
        data: Dataset folder.
        protocol: Which slices train and evaluate.
        config: Networks and training.
        max_excess_n: The plausibility rule (:func:`benchmark.scores.samples.nominal_excess_n`) on the
            training and evaluation samples, [N]; None keeps every sample of the paper's rule.

    Returns:
        ``{"rows": [...], "protocol": ..., "config": ..., "samples": ..., "fig6": ..., ...}``.
    """
    data = os.fspath(data)
    models = object_models(data)
    seeds = list(protocol.train_seeds)
    load = lambda **where: load_dataset(data, max_excess_n=max_excess_n, **where)
    part_df = load(user=protocol.user, grasp=protocol.grasp, mass=protocol.mass, seed=seeds)
    full_df = load(seed=seeds)
    names = finger_names_of(full_df)
    t0 = time.perf_counter()
    nets = {
        "partial": train(training_set(part_df), config, finger_names=names, metadata=dict(training="partial")),
        "full": train(training_set(full_df), config, finger_names=names, metadata=dict(training="full")),
    }
    for user in sorted({protocol.user, protocol.other_user}):
        user_df = load(seed=seeds, user=user)
        nets[f"user{user}"] = train(training_set(user_df), config, finger_names=names, metadata=dict(training=f"user {user}"))
    train_s = time.perf_counter() - t0
    rows, fig6 = [], {}
    for paper, combo in zip(PAPER, protocol.rows()):
        test_df = load(seed=list(protocol.test_seeds), **combo)
        row = dict(combo, seen_user=paper[0], seen_mass=paper[1], seen_grasp=paper[2],
                   paper_partial_avg=paper[3], paper_partial_std=paper[4], paper_full_avg=paper[5], paper_full_std=paper[6])
        for which, net in nets.items():
            if which.startswith("user"):
                if which != f"user{combo['user']}":
                    continue
                which = "same_user"
            ev = evaluate(net, test_df, models)
            row[f"{which}_avg"] = float(np.mean(ev["errors"]))
            row[f"{which}_std"] = float(np.std(ev["errors"]))
            row[f"{which}_n"] = int(ev["errors"].size)
            row[f"{which}_residual_rel"] = ev["residual_rel"]
            if paper[:3] == (False, False, False):
                fig6[which] = ev
        if protocol.user != protocol.other_user:
            other = protocol.other_user if combo["user"] == protocol.user else protocol.user
            partner = load(seed=list(protocol.test_seeds), **dict(combo, user=other))
            rows_ub, pred_ub = user_blind(test_df, partner)
            ev = evaluate(None, rows_ub, models, predicted=pred_ub)
            row["user_blind_avg"] = float(np.mean(ev["errors"]))
            row["user_blind_std"] = float(np.std(ev["errors"]))
            row["user_blind_n"] = int(ev["errors"].size)
        rows.append(row)
    return dict(
        rows=rows, protocol=asdict(protocol), config=asdict(config), train_seconds=train_s,
        samples=dict(partial=len(part_df), full=len(full_df)), fig6=fig6, sources=_sources(data),
        max_excess_n=max_excess_n,
    )


def _sources(data: str) -> dict:
    spec = read_header(data)["spec"]
    return dict(kinematics=spec["kinematics"], contacts=spec["contacts"])


def markdown(result: dict) -> str:
    """Table 2 as Markdown, ours beside the paper's."""
    mark = lambda b: "○" if b else "×"
    lines = [
        "| User | Mass | Grasp | Part. avg [%] | Part. std [%] | Full avg [%] | Full std [%] | Paper part. avg / std | "
        "Paper full avg / std | Same-user full avg / std [%] (diagnostic) | User-blind ideal avg / std [%] (diagnostic) |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in result["rows"]:
        lines.append(
            f"| {mark(r['seen_user'])} | {mark(r['seen_mass'])} | {mark(r['seen_grasp'])} | {r['partial_avg']:.1f} | "
            f"{r['partial_std']:.1f} | {r['full_avg']:.1f} | {r['full_std']:.1f} | {r['paper_partial_avg']} / "
            f"{r['paper_partial_std']} | {r['paper_full_avg']} / {r['paper_full_std']} | "
            f"{r['same_user_avg']:.1f} / {r['same_user_std']:.1f} | "
            + (f"{r['user_blind_avg']:.1f} / {r['user_blind_std']:.1f} |" if "user_blind_avg" in r else "– |")
        )
    s = result["samples"]
    rule = result.get("max_excess_n")
    lines.append("")
    pr = result["protocol"]
    lines.append(
        f"Users: {pr['user']} (partial training) and {pr['other_user']}. "
        f"Training samples: partial {s['partial']}, full {s['full']}; kinematics: {result['sources']['kinematics']}, "
        f"contacts: {result['sources']['contacts']} (tracker = rendered and tracked, the method; error-model = the "
        "truth's with the paper's contact-point error; oracle = the truth's). Samples: the paper's rule (|vision - "
        "tactile net force| <= 1.5 N)"
        + (f" and the plausibility rule (nominal <= tactile + {rule:g} N per finger)" if rule is not None else " only")
        + f"; networks: {result['config'].get('members', 1)} member(s) per ANN, {result['config']['epochs']} Rprop "
        "epochs. Relative error of the reconstructed (eq. 14) normal force per finger with true normal force ≥ 1 N."
    )
    return "\n".join(lines) + "\n"


def plot_fig6(result: dict, path: str) -> None:
    """A plot like the paper's Fig. 6: reconstructed per-finger normal forces against the truth over time
    for the first evaluation episode of the all-changed row (×××)."""
    import matplotlib  # lazy: matplotlib (0.4 s) off `fsv-bench train`'s start-up

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # lazy: matplotlib (0.4 s) off `fsv-bench train`'s start-up

    full, part = result["fig6"]["full"], result["fig6"]["partial"]
    ep = full["episode"][0]
    m = full["episode"] == ep
    used = [k for k in range(len(full["finger_names"])) if full["active"][m, k].any()]
    names = [full["finger_names"][k] for k in used]
    fig, axes = plt.subplots(len(names), 1, figsize=(8, 1.8 * len(names)), sharex=True)
    for k, ax, name in zip(used, np.atleast_1d(axes), names):
        a = full["active"][m, k]
        t = full["t"][m]
        ax.plot(t, np.where(a, full["measured"][m, k], np.nan), "k.", ms=3, label="truth")
        ax.plot(t, np.where(a, full["normal"][m, k], np.nan), "-", color="tab:blue", label="ANN + SOCP, full training")
        ax.plot(t, np.where(a, part["normal"][m, k], np.nan), "-", color="tab:orange", lw=0.8, label="ANN + SOCP, partial")
        ax.set_ylabel(f"{name} [N]")
    np.atleast_1d(axes)[0].legend(fontsize=7, loc="upper right")
    np.atleast_1d(axes)[-1].set_xlabel("t [s]")
    fig.suptitle(f"Normal force per finger, episode {ep} (other user, +10 % mass, other grasp)", fontsize=9)
    fig.tight_layout()
    save_figure(fig, path)
    plt.close(fig)


def write(result: dict, out) -> None:
    """Writes table2.md, table2.csv, table2.json (with the run's provenance,
    :func:`fsv.provenance.provenance`) and fig6.png to folder ``out``."""
    out = os.fspath(out)
    os.makedirs(out, exist_ok=True)
    write_text(os.path.join(out, "table2.md"), markdown(result))
    write_text(os.path.join(out, "table2.csv"), pd.DataFrame(result["rows"]).to_csv(index=False))
    slim = {k: v for k, v in result.items() if k != "fig6"}
    slim["provenance"] = provenance()
    write_text(os.path.join(out, "table2.json"), json.dumps(slim, indent=1))
    plot_fig6(result, os.path.join(out, "fig6.png"))


def add_arguments(p: argparse.ArgumentParser) -> None:
    """The arguments of ``fsv-bench table2``."""
    p.add_argument("--data", required=True, help="dataset folder made by `fsv-bench generate`")
    p.add_argument("--out", default="runs/table2",
                   help="output folder, replaced whole if fsv-bench wrote it (default: runs/table2; the committed "
                        "results/table2 is made by fsv-bench reproduce)")
    p.add_argument("--epochs", type=integer(1, MAX_EPOCHS), default=LearnConfig.epochs,
                   help=f"Rprop epochs per network, 1 to {MAX_EPOCHS:,} (default {LearnConfig.epochs})")
    p.add_argument("--seed", type=integer(0, MAX_SEED), default=0, help=f"seed of the networks' initial weights, 0 to {MAX_SEED}")
    p.add_argument("--train-seeds", default="0-3", help="episode seeds to train on (default 0-3)")
    p.add_argument("--test-seeds", default="4,5", help="episode seeds to evaluate on (default 4,5)")
    p.add_argument("--users", default="0,4",
                   help="the partial training's user and the other user, e.g. 0,4 (default) or 0,1")
    p.add_argument("--members", type=integer(1, MAX_MEMBERS), default=TABLE2_MEMBERS,
                   help=f"networks per ANN, averaged, 1 to {MAX_MEMBERS} (default {TABLE2_MEMBERS}; 1 = the paper's "
                        "single pair)")
    add_max_excess_argument(p)


def add_max_excess_argument(p: argparse.ArgumentParser) -> None:
    """``--max-excess``: the plausibility rule's tolerance (``train``, ``table2``)."""
    p.add_argument("--max-excess", type=number(0, math.inf, "N"), default=MAX_EXCESS_N,
                   help=f"plausibility rule: drop samples whose nominal force exceeds the tactile reading by more "
                        f"than this on a finger, a number >= 0 N (default {MAX_EXCESS_N}; inf: the paper's rule only)")


def run(args: argparse.Namespace) -> dict:
    """Runs ``fsv-bench table2``: prints the table and writes it to ``--out``."""

    check_out(args.out)
    users = parse_ints(args.users, "--users")
    if len(users) != 2 or users[0] == users[1]:
        raise DatasetError(f"--users {args.users!r}: expected two different user indices, e.g. 0,4")
    protocol = Table2Protocol(user=users[0], other_user=users[1], train_seeds=parse_ints(args.train_seeds, "--train-seeds"),
                              test_seeds=parse_ints(args.test_seeds, "--test-seeds"))
    rule = None if not np.isfinite(args.max_excess) else args.max_excess
    result = score(args.data, protocol, LearnConfig(epochs=args.epochs, seed=args.seed, members=args.members), rule)
    with staged_folder(args.out) as tmp:
        write(result, tmp)
    print(markdown(result))
    print(f"written to {args.out}/ (table2.md, table2.csv, table2.json, fig6.png)")
    return result
