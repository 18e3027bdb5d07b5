"""The learned forces against the truth: a method's final forces (nominal plus learned internal forces).

The method's internal-force stage (the shipped model, :func:`fsv.learn.default_model`, or another)
predicts the internal forces from the episode's kinematics and contacts; the reconstruction SOCP
(eq. 14) turns them into full forces. The score is the paper's Table 2 metric on the frames the
dataset's sample rules keep (valid kinematics, at least two fingers in contact, vision and tactile
net forces within 1.5 N, see :func:`benchmark.scores.samples.sample_mask`, and the plausibility
rule on the decomposition's nominal forces, :func:`benchmark.scores.samples.nominal_excess_n`) and
whose program was solved: for finger k at frame i
with true normal force f >= 1 N, |f̂ - f| / f in percent, mean and standard deviation. The same
metric over every solved frame with at least two fingers in contact (no sample rule) is reported
beside it (``rel_err_pct_mean_all``).
"""

from __future__ import annotations


import numpy as np

from benchmark.scores.forces import true_normal_forces
from benchmark.scores.samples import DATASET_FORCE_SETTINGS, MAX_EXCESS_N, nominal_excess_n, sample_mask
from fsv import Contacts, Kinematics
from fsv.features import grasp_features
from fsv.forces import SOLVED, FrameStatus


def score_episode(episode, solution, kinematics: Kinematics, contacts: Contacts) -> dict:
    """A method's final forces on one episode, scored against the truth's normal forces.

    A pure function of the estimate (``solution``, ``kinematics``, ``contacts``) and the episode's
    truth: the frames scored are chosen by the sample rules of the module docstring.

    Args:
        episode: A simulated ``benchmark.Episode``.
        solution: The method's final forces (:class:`fsv.forces.ForceSolution`; the reference: the
            reconstruction of eq. 14 with learned internal forces).
        kinematics: The object kinematics the method used (estimated, or the oracle).
        contacts: The contacts the method used (tracked, vision-like, or the oracle).

    Returns:
        The scores: ``rel_err_pct_mean``, ``rel_err_pct_std``, ``scored`` finger-frames, ``frames``,
        ``solver_failures``, ``residual_rel_max`` and the same error over all usable frames.
    """
    from benchmark.world.tactile import tactile_normal_forces
    from fsv.forces import decompose_forces
    from fsv.learn import relative_errors_pct

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
    err = relative_errors_pct(sol.normal_force, true_normal_forces(tr), both & ok[:, None])
    err_all = relative_errors_pct(sol.normal_force, true_normal_forces(tr), both & (usable & solved)[:, None])
    scale = np.maximum(np.linalg.norm(sol.required[ok], axis=1), 1.0)
    resid = float(np.max(np.linalg.norm(sol.residual[ok], axis=1) / scale)) if ok.any() else float("nan")
    block = dict(
        rel_err_pct_mean=float(np.mean(err)) if err.size else float("nan"),
        rel_err_pct_std=float(np.std(err)) if err.size else float("nan"),
        scored=int(err.size), frames=int(ok.sum()),
        dropped_gap=int(np.sum(usable & ~keep)), dropped_plausibility=int(np.sum(keep & ~plausible)),
        rel_err_pct_mean_all=float(np.mean(err_all)) if err_all.size else float("nan"),
        rel_err_pct_std_all=float(np.std(err_all)) if err_all.size else float("nan"),
        scored_all=int(err_all.size),
        solver_failures=int(np.sum(keep & ~solved)),
        residual_rel_max=resid,
    )
    return block


def model_block(model) -> dict:
    """What an internal-force model was trained on (episodes, samples, the command) and whether it
    takes the user's grip calibration."""
    meta = model.metadata
    return dict(episodes=meta.get("episodes"), samples=meta.get("samples"), command=meta.get("command"),
                grip_inputs=model.config.grip_inputs)


def _take(x, idx):
    """The frames ``idx`` of a :class:`fsv.Kinematics` or :class:`fsv.Contacts`."""
    from benchmark.scores.samples import take_contacts as _take_con, take_kinematics as _take_kin

    return _take_kin(x, idx) if isinstance(x, Kinematics) else _take_con(x, idx)
