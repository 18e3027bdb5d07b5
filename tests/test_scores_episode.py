"""Per-episode metrics: the truth scores perfectly, a biased estimate scores its bias."""

import dataclasses

import numpy as np

from benchmark.scores.episode import kinematics_errors
from benchmark.world.motion import oracle_kinematics


def test_the_true_kinematics_have_no_error_and_a_bias_shows(lift_episode):
    truth = lift_episode[0].truth
    kin = oracle_kinematics(truth)
    e = kinematics_errors(kin, truth)
    assert e["acc_err_rms"] < 1e-9 and e["gyro_err_rms"] < 1e-9
    biased = dataclasses.replace(kin, omega=kin.omega + np.array([0.0, 0.0, 0.3]))
    assert abs(kinematics_errors(biased, truth)["gyro_err_rms"] - 0.3 / np.sqrt(3)) < 1e-6


def test_the_learned_errors_are_taken_from_scores_already_computed(tracked_lift):
    """The main command's verdict takes the learned forces' errors from the learn stage's scores
    (``learned=``) instead of solving the paper rule's decomposition again."""
    from benchmark.scores.episode import score_episode

    episode, estimate = tracked_lift
    estimate = dataclasses.replace(estimate, forces=estimate.nominal)  # final forces to score
    planted = {"rel_err_pct_mean": 12.5, "mae_n": 0.25, "paper_rule": {"rel_err_pct_mean": 7.0}}
    taken = score_episode(episode, estimate, learned=planted)
    assert (taken["learned_rel_err_pct"], taken["learned_mae_n"], taken["learned_rel_err_pct_paper"]) == (12.5, 0.25, 7.0)
    computed = score_episode(episode, estimate)
    assert computed["learned_rel_err_pct"] != 12.5 and np.isfinite(computed["learned_rel_err_pct"])
    assert {k: v for k, v in taken.items() if not k.startswith("learned_")} == {
        k: v for k, v in computed.items() if not k.startswith("learned_")}
