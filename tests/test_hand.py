"""The hand: `benchmark.world.hand` exports the simulated hand as `fsv.HandModel`; `fsv.hand` moves it.

Forward kinematics of the exported model must reproduce MuJoCo's own kinematics of the MJCF written
from the same model (segment poses, capsule end points, fingertip sites) to 1e-9.
"""

import mujoco
import numpy as np
import pytest

from benchmark.errors import ScenarioError
from benchmark.world.assets import build_world
from benchmark.world.hand import geom_name, hand_model
from benchmark.world.scenario import Scenario
from fsv import InputError
from fsv.hand import capsule_endpoints, finger_of_segment, fingertip_centres, forward_kinematics_qpos
from fsv.rotation import axis_angle_to_rot, quat_to_rot


@pytest.fixture(scope="module", params=[0, 2])
def world(request):
    return build_world(Scenario(user=request.param))


def _random_qpos(rng, hand, batch):
    q = rng.uniform(hand.joint_range[:, 0], hand.joint_range[:, 1], size=(batch, hand.num_joints))
    quat = rng.normal(size=(batch, 4))
    quat /= np.linalg.norm(quat, axis=1, keepdims=True)
    return np.concatenate([rng.normal(scale=0.3, size=(batch, 3)), quat, q], axis=1)


def test_forward_kinematics_matches_mujoco(world):
    m, hand = world.model, world.hand
    d = mujoco.MjData(m)
    hq = _random_qpos(np.random.default_rng(3), hand, 20)
    pose = forward_kinematics_qpos(hand, hq)  # batched over the 20 configurations
    ends = capsule_endpoints(hand, pose)
    tips = fingertip_centres(hand, pose)
    gid = [mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, geom_name(hand, g)) for g in range(len(hand.geom_segment))]
    for i in range(len(hq)):
        d.qpos[world.hand_qadr] = hq[i]
        mujoco.mj_kinematics(m, d)
        np.testing.assert_allclose(pose.pos[i], d.xpos[world.segment_body], atol=1e-9)
        np.testing.assert_allclose(pose.rot[i], d.xmat[world.segment_body].reshape(-1, 3, 3), atol=1e-9)
        np.testing.assert_allclose(tips[i], d.site_xpos[world.tip_site], atol=1e-9)
        for g, mg in enumerate(gid):
            centre = d.geom_xpos[mg]
            if m.geom_type[mg] == mujoco.mjtGeom.mjGEOM_SPHERE:
                np.testing.assert_allclose(ends[i, g], [centre, centre], atol=1e-9)
            else:
                half = m.geom_size[mg, 1] * d.geom_xmat[mg].reshape(3, 3)[:, 2]
                got = sorted([tuple(centre - half), tuple(centre + half)])
                want = sorted([tuple(ends[i, g, 0]), tuple(ends[i, g, 1])])
                np.testing.assert_allclose(got, want, atol=1e-9)
            assert m.geom_size[mg, 0] == pytest.approx(hand.geom_radius[g], abs=1e-12)


def test_hand_model_has_twenty_joints_thumb_first_and_scales():
    small, big = hand_model(0.9), hand_model(1.1)
    assert small.num_joints == 20
    assert small.finger_names == ("thumb", "index", "middle", "ring", "little")
    assert sum(n.startswith("thumb_cmc") for n in small.joint_names) == 2  # 2-DoF thumb base
    assert sum(n.startswith("index_mcp") for n in small.joint_names) == 2  # 2-DoF knuckle
    np.testing.assert_allclose(big.geom_radius / small.geom_radius, 1.1 / 0.9)
    np.testing.assert_allclose(big.offset_pos[1:] / 1.1, small.offset_pos[1:] / 0.9, atol=1e-15)
    np.testing.assert_array_equal(big.joint_range, small.joint_range)
    # A hand of scale 1 spans ~190 mm from the wrist end of the palm to the middle fingertip.
    ref = hand_model(1.0)
    pose = forward_kinematics_qpos(ref, np.concatenate([[0, 0, 0, 1, 0, 0, 0], np.zeros(20)]))
    tip = fingertip_centres(ref, pose)[2]
    length = tip[1] + ref.fingertip_radius[2] - ref.geom_fromto[:, [1, 4]].min()
    assert 0.17 < length < 0.21


def test_rotation_helpers_agree_with_finite_rotation_and_mujoco():
    rng = np.random.default_rng(0)
    axis = rng.normal(size=3)
    axis /= np.linalg.norm(axis)
    R = axis_angle_to_rot(axis, 0.7)
    q = np.concatenate([[np.cos(0.35)], np.sin(0.35) * axis])
    np.testing.assert_allclose(R, quat_to_rot(q), atol=1e-14)
    mat = np.zeros(9)
    mujoco.mju_quat2Mat(mat, q)
    np.testing.assert_allclose(R, mat.reshape(3, 3), atol=1e-14)
    # d/dθ R(θ) = [axis]x R(θ)
    eps = 1e-6
    dR = (axis_angle_to_rot(axis, 0.7 + eps) - axis_angle_to_rot(axis, 0.7 - eps)) / (2 * eps)
    K = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    np.testing.assert_allclose(dR, K @ R, atol=1e-8)


def test_bad_inputs():
    with pytest.raises(ScenarioError, match="scale"):
        hand_model(-1.0)
    with pytest.raises(InputError, match="27"):
        forward_kinematics_qpos(hand_model(1.0), np.zeros(10))


def test_each_segment_belongs_to_the_finger_of_its_tip():
    hand = hand_model(1.0)
    finger = finger_of_segment(hand)
    assert finger[0] == -1 and finger.dtype == np.int64
    for k, name in enumerate(hand.finger_names):  # three segments per digit, named after it
        assert [hand.segment_names[b] for b in np.flatnonzero(finger == k)] == [
            s for s in hand.segment_names if s.startswith(f"{name}_")]
