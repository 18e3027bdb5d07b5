"""benchmark.world.pose_error: correlated tracker-like pose errors."""

import numpy as np
import pytest

from benchmark.errors import ScenarioError
from benchmark.world.pose_error import PoseErrorModel, tracker_like_poses
from benchmark.world.scenario import Scenario
from fsv.kinematics import so3


def test_errors_are_stationary_gauss_markov_with_the_set_std_and_correlation():
    model = PoseErrorModel(pos_std_m=0.002, rot_std_rad=0.05, corr_time_s=0.1)
    pos_err, rot_err = model.errors(40000, 1 / 30, np.random.default_rng(3))
    rho = np.exp(-1 / 3)
    for e, sigma in ((pos_err, 0.002), (rot_err, 0.05)):
        assert np.std(e, axis=0) == pytest.approx([sigma] * 3, rel=0.05)
        lag1 = [np.corrcoef(e[:-1, i], e[1:, i])[0, 1] for i in range(3)]
        assert lag1 == pytest.approx([rho] * 3, abs=0.02)
        lag3 = np.corrcoef(e[:-3, 0], e[3:, 0])[0, 1]
        assert lag3 == pytest.approx(rho**3, abs=0.03)
    assert abs(np.corrcoef(pos_err[:, 0], rot_err[:, 0])[0, 1]) < 0.05


def test_zero_correlation_time_gives_white_errors():
    pos_err, _ = PoseErrorModel(corr_time_s=0.0).errors(20000, 1 / 30, np.random.default_rng(0))
    assert abs(np.corrcoef(pos_err[:-1, 0], pos_err[1:, 0])[0, 1]) < 0.03


def test_same_scenario_same_bits_and_scaling_with_noise(analytic_truth):
    a = tracker_like_poses(analytic_truth, Scenario(seed=5))
    b = tracker_like_poses(analytic_truth, Scenario(seed=5))
    c = tracker_like_poses(analytic_truth, Scenario(seed=6))
    assert np.array_equal(a.pos, b.pos) and np.array_equal(a.rot, b.rot)
    assert not np.array_equal(a.pos, c.pos)
    exact = tracker_like_poses(analytic_truth, Scenario(seed=5, noise_m=0.0))
    np.testing.assert_array_equal(exact.pos, analytic_truth.box_pos)
    np.testing.assert_allclose(exact.rot, analytic_truth.box_rot, atol=1e-12)
    double = tracker_like_poses(analytic_truth, Scenario(seed=5, noise_m=0.02))
    np.testing.assert_allclose(double.pos - analytic_truth.box_pos, 2 * (a.pos - analytic_truth.box_pos), atol=1e-15)


def test_rotation_error_is_a_body_frame_perturbation(analytic_truth):
    model = PoseErrorModel(pos_std_m=0.0, rot_std_rad=0.04, corr_time_s=0.05)
    poses = model.corrupt(analytic_truth.t, analytic_truth.box_pos, analytic_truth.box_rot, np.random.default_rng(1))
    _, rot_err = model.errors(len(analytic_truth.t), 1 / 30, np.random.default_rng(1))
    rel = np.einsum("tji,tjk->tik", analytic_truth.box_rot, poses.rot)  # R_true^T R_obs
    np.testing.assert_allclose(so3.quat_log(so3.quat_from_matrix(rel)), rot_err, atol=1e-9)
    np.testing.assert_array_equal(poses.pos, analytic_truth.box_pos)


@pytest.mark.parametrize("field", ["pos_std_m", "rot_std_rad", "corr_time_s"])
def test_rejects_negative_parameters(field):
    with pytest.raises(ScenarioError, match=field):
        PoseErrorModel(**{field: -1.0})
