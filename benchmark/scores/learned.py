"""The learned forces against the truth: a method's final forces (nominal plus learned internal forces).

The method's internal-force stage (the shipped model, :func:`fsv.learn.default_model`, or another)
predicts the internal forces from the episode's kinematics and contacts; the reconstruction SOCP
(eq. 14) turns them into full forces. Two scores of the final normal forces:

* **Every contact frame** (the benchmark's, ``rel_err_pct_mean`` and ``mae_n``): every finger-frame
  where the estimate and the truth both have the finger in contact, contact transitions and frames
  resting on the table included. A frame whose program was not solved (any status outside
  :data:`fsv.forces.SOLVED`: no kinematics at the differentiator's ends, least violation, failed,
  implausible) is a failure, scored as an estimate of 0 N (relative error 100 %, absolute error the
  true force), not left out. The relative error |f̂ - f| / f [%] exists where the true normal force
  is at least :data:`MIN_FORCE_N` (the paper's rule, which defines the quantity); the absolute error
  [N] on every such finger-frame.
* **The paper's rule** (``paper_rule``, for comparison with Table 2): the same relative error on the
  frames the dataset's sample rules keep (valid kinematics, at least two fingers in contact, vision
  and tactile net forces within 1.5 N, :func:`benchmark.scores.samples.sample_mask`; the
  plausibility rule on the decomposition's nominal forces, :func:`benchmark.scores.samples.nominal_excess_n`)
  and whose program was solved. These rules choose *training* samples by the truth; as a score they
  drop the hard frames (on ``place``, most frames resting on the table), which is why it is secondary.
"""

from __future__ import annotations

import numpy as np

from benchmark.scores.forces import true_normal_forces
from benchmark.scores.samples import (
    DATASET_FORCE_SETTINGS,
    MAX_EXCESS_N,
    nominal_excess_n,
    sample_mask,
)
from benchmark.scores.samples import take_contacts as _take_con
from benchmark.scores.samples import take_kinematics as _take_kin
from benchmark.world.tactile import tactile_normal_forces
from fsv import Contacts, Kinematics
from fsv.features import grasp_features
from fsv.forces import SOLVED, FrameStatus, decompose_forces
from fsv.learn import relative_errors_pct

MIN_FORCE_N = 1.0
"""Smallest true normal force whose relative error is scored, [N] (the paper's Table 2)."""


def contact_frame_errors(solution, contacts: Contacts, truth) -> dict:
    """The final normal forces on every finger-frame in contact for the estimate and the truth.

    Args:
        solution: The method's final forces (:class:`fsv.forces.ForceSolution`), T frames, K fingers.
        contacts: The contacts the method used (``active`` (T, K)).
        truth: The episode's truth.

    Returns:
        ``rel_err_pct_mean``/``rel_err_pct_std`` over the ``scored`` finger-frames with a true force of
        at least :data:`MIN_FORCE_N`, ``mae_n`` over the ``pairs`` finger-frames in contact for both,
        and ``unsolved_frac``, the fraction of those pairs on unsolved frames (scored as 0 N).
    """
    f_true = true_normal_forces(truth)
    both = np.asarray(contacts.active, bool) & np.asarray(truth.contact_active, bool)
    solved = np.isin(solution.status, [int(s) for s in SOLVED])
    f_est = np.where(solved[:, None], np.nan_to_num(np.asarray(solution.normal_force, float), nan=0.0), 0.0)
    err = np.abs(f_est - f_true)
    rel = both & (f_true >= MIN_FORCE_N)
    nan = float("nan")
    rel_err = 100.0 * err[rel] / f_true[rel]
    return dict(
        rel_err_pct_mean=float(np.mean(rel_err)) if rel_err.size else nan,
        rel_err_pct_std=float(np.std(rel_err)) if rel_err.size else nan,
        scored=int(rel_err.size),
        mae_n=float(np.mean(err[both])) if both.any() else nan,
        pairs=int(both.sum()),
        unsolved_frac=float(np.mean(~np.broadcast_to(solved[:, None], both.shape)[both])) if both.any() else nan,
    )


def paper_rule_errors(episode, solution, kinematics: Kinematics, contacts: Contacts) -> dict:
    """The relative error on the frames the paper's sample rules keep (see the module docstring).

    Returns:
        ``rel_err_pct_mean``, ``rel_err_pct_std``, ``scored`` finger-frames, ``frames`` kept,
        ``dropped_gap``, ``dropped_plausibility``, ``solver_failures`` (kept frames unsolved, left
        out by this rule) and ``residual_rel_max``.
    """

    tr, sol = episode.truth, solution
    feats = grasp_features(kinematics, contacts, episode.object_model, gravity=tr.gravity)
    usable, keep, _ = sample_mask(kinematics, contacts, feats, tr)
    # the plausibility rule, as in the dataset: the decomposition (eq. 9) with the tactile readings
    measured = tactile_normal_forces(tr, episode.scenario.rng("tactile"), full_scale_n=np.inf)
    idx = np.flatnonzero(keep)
    excess = np.full(len(tr.t), np.inf)
    if idx.size:
        dec = decompose_forces(_take(kinematics, idx), _take(contacts, idx), episode.object_model, measured[idx],
                               gravity=tr.gravity, settings=DATASET_FORCE_SETTINGS)
        solved = dec.status == int(FrameStatus.OPTIMAL)
        excess[idx[solved]] = nominal_excess_n(dec.nominal_normal, measured[idx], contacts.active[idx])[solved]
    plausible = excess <= MAX_EXCESS_N
    solved = np.isin(sol.status, [int(s) for s in SOLVED])
    ok = keep & plausible & solved
    both = contacts.active & tr.contact_active
    err = relative_errors_pct(sol.normal_force, true_normal_forces(tr), both & ok[:, None], min_force_n=MIN_FORCE_N)
    scale = np.maximum(np.linalg.norm(sol.required[ok], axis=1), 1.0)
    resid = float(np.max(np.linalg.norm(sol.residual[ok], axis=1) / scale)) if ok.any() else float("nan")
    return dict(
        rel_err_pct_mean=float(np.mean(err)) if err.size else float("nan"),
        rel_err_pct_std=float(np.std(err)) if err.size else float("nan"),
        scored=int(err.size), frames=int(ok.sum()),
        dropped_gap=int(np.sum(usable & ~keep)), dropped_plausibility=int(np.sum(keep & ~plausible)),
        solver_failures=int(np.sum(keep & ~solved)),
        residual_rel_max=resid,
    )


def score_episode(episode, solution, kinematics: Kinematics, contacts: Contacts) -> dict:
    """A method's final forces on one episode, scored against the truth's normal forces.

    A pure function of the estimate (``solution``, ``kinematics``, ``contacts``) and the episode's
    truth.

    Args:
        episode: A simulated ``benchmark.world.episode.Episode``.
        solution: The method's final forces (:class:`fsv.forces.ForceSolution`; the reference: the
            reconstruction of eq. 14 with learned internal forces).
        kinematics: The object kinematics the method used (estimated, or the oracle).
        contacts: The contacts the method used (tracked, vision-like, or the oracle).

    Returns:
        :func:`contact_frame_errors`'s keys, ``frames`` (frames with a scored pair) and
        ``paper_rule`` (:func:`paper_rule_errors`).
    """
    block = contact_frame_errors(solution, contacts, episode.truth)
    both = np.asarray(contacts.active, bool) & np.asarray(episode.truth.contact_active, bool)
    block["frames"] = int(both.any(axis=1).sum())
    block["paper_rule"] = paper_rule_errors(episode, solution, kinematics, contacts)
    return block


def model_block(model) -> dict:
    """What an internal-force model was trained on (episodes, samples, the command) and whether it
    takes the user's grip calibration."""
    meta = model.metadata
    return dict(episodes=meta.get("episodes"), samples=meta.get("samples"), command=meta.get("command"),
                grip_inputs=model.config.grip_inputs)


def _take(x, idx):
    """The frames ``idx`` of a :class:`fsv.Kinematics` or :class:`fsv.Contacts`."""

    return _take_kin(x, idx) if isinstance(x, Kinematics) else _take_con(x, idx)
