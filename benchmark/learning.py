"""The learning block of ``fsv-bench``: learned human-like forces on the command's scenario.

The shipped model (:func:`fsv.learn.default_model`, or ``--internal-model FILE``) predicts the
internal forces from the episode's kinematics and contacts; the reconstruction SOCP (eq. 14)
turns them into full forces (:func:`fsv.learn.learned_forces`). The score is the paper's Table 2
metric on the frames the paper's sample rule keeps (valid kinematics, at least two fingers in
contact, vision and tactile net forces within 1.5 N, see :func:`benchmark.dataset.sample_mask`)
and whose program was solved: for finger k at frame i with true normal force f >= 1 N,
|f̂ - f| / f in percent, mean and standard deviation.
"""

from __future__ import annotations

import argparse

import numpy as np

from benchmark.dataset import measured_normal_forces, oracle_contacts, sample_mask
from fsv import Contacts, Kinematics
from fsv.features import grasp_features
from fsv.forces import FrameStatus
from fsv.learn import InternalForceModel, default_model, learned_forces, load, relative_errors_pct


def score_episode(episode, model: InternalForceModel, kinematics: Kinematics, contacts: Contacts | None = None) -> dict:
    """Learned forces on one episode, scored against the truth's normal forces.

    Args:
        episode: A simulated ``benchmark.Episode``.
        model: The internal-force networks.
        kinematics: The object kinematics the method estimated (or the oracle, labelled by its
            ``method``).
        contacts: The contacts the method found; None uses the truth's (*oracle*, labelled).

    Returns:
        ``(block, solution, predicted)``: the ``learning`` block of summary.json
        (``rel_err_pct_mean``, ``rel_err_pct_std``, ``scored`` finger-frames, ``frames``,
        ``solver_failures``, ``residual_rel_max``, ``kinematics``, ``contacts`` and ``model``, what
        it was trained on), the reconstruction (:class:`fsv.forces.ForceSolution`) and the
        predicted internal normal forces, shape (T, K), [N].
    """
    tr = episode.truth
    con = oracle_contacts(tr) if contacts is None else contacts
    sol, pred = learned_forces(model, kinematics, con, episode.object_model, gravity=tr.gravity)
    feats = grasp_features(kinematics, con, episode.object_model, gravity=tr.gravity)
    _, keep, _ = sample_mask(kinematics, con, feats, tr)
    ok = keep & (sol.status == int(FrameStatus.OPTIMAL))
    measured = measured_normal_forces(tr)
    err = relative_errors_pct(sol.normal_force, measured, con.active & tr.contact_active & ok[:, None])
    scale = np.maximum(np.linalg.norm(sol.required[ok], axis=1), 1.0)
    resid = float(np.max(np.linalg.norm(sol.residual[ok], axis=1) / scale)) if ok.any() else float("nan")
    meta = model.metadata
    return dict(
        rel_err_pct_mean=float(np.mean(err)) if err.size else float("nan"),
        rel_err_pct_std=float(np.std(err)) if err.size else float("nan"),
        scored=int(err.size), frames=int(ok.sum()),
        solver_failures=int(np.sum(keep & (sol.status != int(FrameStatus.OPTIMAL)))),
        residual_rel_max=resid, kinematics=kinematics.method or "estimated",
        contacts="oracle" if contacts is None else "tracked",
        model=dict(episodes=meta.get("episodes"), samples=meta.get("samples"), command=meta.get("command")),
    ), sol, pred


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--internal-model", default=None,
                   help="internal-force model file from `fsv-bench train` (default: the shipped model)")


def model_from_args(args: argparse.Namespace) -> InternalForceModel:
    path = getattr(args, "internal_model", None)
    return default_model() if path is None else load(path)


def format_block(block: dict) -> str:
    """One line for the printed summary."""
    return (
        f"learned forces (ANN + eq. 14): rel. error {block['rel_err_pct_mean']:.1f} ± {block['rel_err_pct_std']:.1f} % "
        f"over {block['scored']} finger-frames (paper: 9.7-10.9 %); kinematics={block['kinematics']}, "
        f"contacts={block['contacts']}" + (" (oracle = from the truth)" if "oracle" in (block["kinematics"], block["contacts"]) else "")
    )
