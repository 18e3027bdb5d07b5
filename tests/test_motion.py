"""benchmark.world.motion: which kinematics the later stages get."""

from types import SimpleNamespace

import numpy as np
import pytest

from benchmark.errors import ScenarioError
from benchmark.world.motion import CHOICES, DECLARED, episode_kinematics, observed_poses, oracle_kinematics
from benchmark.world.scenario import Scenario
from fsv.kinematics import CentralConfig, differentiate_poses


@pytest.fixture(scope="module")
def episode(analytic_truth):
    # The stage reads only .truth and .scenario of an Episode.
    return SimpleNamespace(truth=analytic_truth, scenario=Scenario(seed=3))


def test_oracle_is_the_truth_and_says_so(episode):
    kin = episode_kinematics(episode, "oracle")
    assert kin.method == "oracle" and kin.valid.all() and kin.delay_s == 0
    np.testing.assert_array_equal(kin.acc, episode.truth.box_acc)
    np.testing.assert_array_equal(kin.omega, episode.truth.box_omega)
    np.testing.assert_allclose(kin.rot, episode.truth.box_rot)


@pytest.mark.parametrize("choice", [c for c in CHOICES if c != "oracle"])
def test_methods_differentiate_the_observed_poses_with_declared_parameters(episode, choice):
    kin = episode_kinematics(episode, choice)
    ref = differentiate_poses(observed_poses(episode), DECLARED[choice])
    assert kin.method == choice
    np.testing.assert_array_equal(kin.acc, ref.acc)
    assert not np.allclose(kin.pos, episode.truth.box_pos)  # observed, not true, poses


def test_config_and_poses_overrides(episode):
    kin = episode_kinematics(episode, "central", config=CentralConfig(step_frames=2))
    assert kin.valid.sum() == len(episode.truth.t) - 4
    exact = oracle_kinematics(episode.truth)
    from fsv import Poses

    kin = episode_kinematics(episode, "central", poses=Poses(t=exact.t, pos=exact.pos, rot=exact.rot))
    np.testing.assert_array_equal(kin.pos[kin.valid], episode.truth.box_pos[kin.valid])  # no smoothing


def test_bad_choices_fail_clearly(episode):
    with pytest.raises(ScenarioError, match="one of algebraic, central, gaussian, oracle"):
        episode_kinematics(episode, "kalman")
    with pytest.raises(ScenarioError, match="does not match"):
        episode_kinematics(episode, "algebraic", config=CentralConfig())
    with pytest.raises(ScenarioError, match="oracle"):
        episode_kinematics(episode, "oracle", config=CentralConfig())
