"""The task contract: every task, user and grasp gives a finite truth of the documented shapes,
lifts the box where the task says so, never drops it, and grips within a human range."""

import numpy as np
import pytest

from benchmark.commands.report import max_slip_m
from benchmark.world.scenario import GRIP_CONTROLS
from benchmark.world.tasks import TASKS

SHORT_S = 2.4


def _check_contract(ep):
    tr, task = ep.truth, TASKS[ep.scenario.task]
    T, K = len(tr.t), len(tr.finger_names)
    assert K == 5 and tr.hand_qpos.shape == (T, 7 + ep.hand_model.num_joints)
    for name, value in tr.as_dict().items():
        if value is not None and np.asarray(value).dtype.kind == "f":
            assert np.isfinite(value).all(), name
    np.testing.assert_allclose(np.linalg.norm(tr.box_quat, axis=1), 1.0, atol=1e-9)
    held = tr.held
    assert held.sum() >= 10
    active = tr.contact_active[held]
    plan_active = active.mean(axis=0) >= 0.95  # measured: a fast place with the heaviest box (user 1, grasp 2)
    # lifts the ring and little fingers off for one of 68 held frames; every other digit and task: every frame
    assert active[:, 0].all() and plan_active.sum() >= 4, "the grasp's digits stay on the box while held"
    fn = tr.normal_force()[held][:, plan_active][active[:, plan_active]]  # while in contact
    assert fn.min() >= 0.5 and fn.max() <= 40.0, (fn.min(), fn.max())
    assert max_slip_m(ep) < 0.004
    force, torque = tr.newton_euler_residual()
    assert np.abs(force).max() < 0.01 and np.abs(torque).max() < 0.001
    z0 = tr.box_pos[0, 2]
    if task.lifts:
        assert tr.box_pos[:, 2].max() > z0 + 0.03
    # no drop: from the grasp on, whenever the table does not touch the box, the hand holds it
    airborne = (np.linalg.norm(tr.env_force, axis=1) == 0) & (tr.t >= tr.t[held][0])
    assert np.all(tr.contact_active[airborne][:, 0]) and tr.contact_active[airborne][:, plan_active].mean() >= 0.95
    assert tr.box_pos[:, 2].min() > z0 - 0.002


@pytest.mark.parametrize("control", GRIP_CONTROLS)
@pytest.mark.parametrize("user", [0, 1, 2, 3])
@pytest.mark.parametrize("grasp", [0, 1, 2, 3])
def test_lift_contract_for_every_user_and_grasp(episode_factory, user, grasp, control):
    _check_contract(episode_factory(task="lift", user=user, grasp=grasp, mass=2, duration_s=SHORT_S, grip_control=control))


@pytest.mark.parametrize("control", GRIP_CONTROLS)
@pytest.mark.parametrize("task", sorted(TASKS))
def test_every_task_keeps_the_contract(episode_factory, task, control):
    _check_contract(episode_factory(task=task, user=1, grasp=2, mass=5, duration_s=TASKS[task].default_duration_s / 3,
                                    grip_control=control))
