"""The world: assets load, indices point where they say, set_frame poses a frame of the truth."""

import mujoco
import numpy as np
import pytest

from benchmark.errors import ScenarioError
from benchmark.world.assets import build_world, grasps, hand_model, masses, object_model, set_frame, users, validate
from benchmark.world.scenario import Scenario
from fsv.hand import capsule_endpoints, forward_kinematics_qpos


def test_assets_have_what_the_benchmark_promises():
    assert len(users()) >= 4 and len(grasps()) >= 3 and len(masses()) >= 6
    kg = [m["mass_kg"] for m in masses()]
    for base in (0.30, 0.45, 0.60):
        assert base in kg and pytest.approx(1.1 * base) in kg  # each mass has its +10 % variant
    digits = [len(g["spots"]) for g in grasps()]
    assert 5 in digits and digits.count(4) >= 3
    assert all("thumb" in g["spots"] for g in grasps())


def test_model_matches_the_scenario():
    sc = Scenario(user=2, mass=4)
    w = build_world(sc)
    m, om = w.model, object_model(sc)
    assert m.body_mass[w.box_body] == pytest.approx(0.495)
    np.testing.assert_allclose(m.body_inertia[w.box_body], np.diag(om.inertia), rtol=1e-9)
    np.testing.assert_allclose(m.body_ipos[w.box_body], 0.0)  # centre of mass at the body origin
    np.testing.assert_allclose(2 * m.geom_size[w.box_geom], [0.171, 0.111, 0.060])
    assert m.opt.timestep <= 0.001 and m.opt.cone == mujoco.mjtCone.mjCONE_ELLIPTIC
    assert m.opt.integrator == mujoco.mjtIntegrator.mjINT_IMPLICITFAST and m.opt.impratio == 10
    # friction: MuJoCo takes the larger coefficient of the two geoms
    pad = int(np.flatnonzero(w.geom_finger == 1)[-1])
    assert max(m.geom_friction[pad, 0], m.geom_friction[w.box_geom, 0]) == pytest.approx(om.friction)
    assert max(m.geom_friction[w.table_geom, 0], m.geom_friction[w.box_geom, 0]) == pytest.approx(om.table_friction)
    assert hand_model(sc).joint_names == w.hand.joint_names
    assert len(w.hand_qadr) == 7 + 20 and len(set(w.hand_qadr)) == 27


def test_set_frame_poses_box_and_hand_for_a_frame_of_the_truth(lift_episode):
    ep, _ = lift_episode
    tr = ep.truth
    w = build_world(ep.scenario)
    d = mujoco.MjData(w.model)
    i = int(np.flatnonzero(tr.held)[-1])
    set_frame(w, d, tr.box_pos[i], tr.box_quat[i], tr.hand_qpos[i])
    np.testing.assert_allclose(d.geom_xpos[w.box_geom], tr.box_pos[i], atol=1e-12)
    np.testing.assert_allclose(d.geom_xmat[w.box_geom].reshape(3, 3), tr.box_rot[i], atol=1e-12)
    np.testing.assert_allclose(d.site_xpos[w.tip_site], tr.fingertip_pos[i], atol=1e-9)
    ends = capsule_endpoints(w.hand, forward_kinematics_qpos(w.hand, tr.hand_qpos[i]))
    hand_geoms = np.flatnonzero(w.geom_segment >= 0)
    assert len(hand_geoms) == len(ends)
    np.testing.assert_allclose(d.geom_xpos[hand_geoms], ends.mean(axis=1), atol=1e-9)
    with pytest.raises(ScenarioError, match="27 entries"):
        set_frame(w, d, tr.box_pos[i], tr.box_quat[i], tr.hand_qpos[i, :10])


@pytest.mark.parametrize("kw, needle", [
    (dict(task="juggle"), "unknown task 'juggle'; accepted: lift, place"),
    (dict(mass=6), "mass 6 does not exist; accepted: 0 (light), 1 (medium)"),
    (dict(task="rotate", duration_s=2.0), "duration 2.0 s is too short for task 'rotate'; accepted: >= 2.5 s"),
])
def test_validate_names_bad_value_and_accepted_ones(kw, needle):
    with pytest.raises(ScenarioError, match=needle.replace("(", r"\(").replace(")", r"\)")):
        validate(Scenario(**kw))
