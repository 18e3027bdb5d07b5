"""The learning block of ``fsv-bench``: learned human-like forces on the command's scenario.

The shipped model (:func:`fsv.learn.default_model`, or ``--internal-model FILE``) predicts the
internal forces from the episode's kinematics and contacts (the same inputs as the force stage,
``benchmark.scores.forces.stage_inputs``, labelled the same way); the reconstruction SOCP (eq. 14)
turns them into full forces (:func:`fsv.learn.learned_forces`). The score is the paper's Table 2
metric on the frames the dataset's sample rules keep (valid kinematics, at least two fingers in
contact, vision and tactile net forces within 1.5 N, see :func:`benchmark.paper.dataset.sample_mask`,
and the plausibility rule on the decomposition's nominal forces,
:func:`benchmark.paper.dataset.nominal_excess_n`) and whose program was solved: for finger k at frame i
with true normal force f >= 1 N, |f̂ - f| / f in percent, mean and standard deviation. The same
metric over every solved frame with at least two fingers in contact (no sample rule) is reported
beside it (``rel_err_pct_mean_all``).
"""

from __future__ import annotations

import argparse

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


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Adds ``--internal-model FILE`` to ``fsv-bench``."""
    p.add_argument("--internal-model", default=None,
                   help="internal-force model from `fsv-bench train` (default: the model shipped in fsv/data)")


def run_stage(run) -> None:
    """The ``learning`` block of summary.json and one printed line for a ``benchmark.commands.cli.Run``:
    the method's final forces (``run.estimate.forces``) scored against the truth."""
    from benchmark.scores.forces import stage_inputs

    kin, contacts, labels = stage_inputs(run)
    est = run.estimate
    if est.forces is None:
        run.summary["learning"] = {**labels, "program": None}
        run.lines.append(f"learning: the method has no internal-force stage ({est.labels['internal']})")
        return
    block = score_episode(run.episode, est.forces, kin, contacts)
    path = getattr(run.args, "internal_model", None)
    model_info = {}
    if est.labels["internal"].startswith("learned internal forces"):
        from fsv.learn import default_model, load

        from benchmark.method.grip_file import user_grip

        model_info = {"internal_model": path or "fsv/data/internal_forces.npz",
                      "model": model_block(default_model() if path is None else load(path))}
        if model_info["model"]["grip_inputs"]:
            grip = user_grip(run.episode.scenario.user)
            model_info["grip_calibration"] = None if grip is None else {"baseline_n": grip.baseline_n, "gain": grip.gain}
    block = {**labels, "program": est.labels["internal"], **model_info, **block}
    run.summary["learning"] = block
    tag = f"ORACLE {', '.join(labels['oracle'])}" if labels["oracle"] else "no oracle input"
    run.lines.append(
        f"learning [{tag}] (kinematics {labels['kinematics']}, contacts {labels['contacts']}): learned forces' "
        f"relative error {block['rel_err_pct_mean']:.1f} ± {block['rel_err_pct_std']:.1f} % over {block['scored']} "
        f"finger-frames kept by the sample rules (paper, Table 2: 9.7-10.9 %; {block['rel_err_pct_mean_all']:.1f} ± "
        f"{block['rel_err_pct_std_all']:.1f} % over all {block['scored_all']}); {block['solver_failures']} solver failures"
        + (f"; the user's grip calibration: {g['baseline_n']:.2f} N + {g['gain']:.2f} N per N of load"
           if (g := block.get("grip_calibration")) else "")
    )
