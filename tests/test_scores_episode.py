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
