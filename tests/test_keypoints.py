"""benchmark.camera.keypoints: the 21 hand keypoints of a simulated lift and the MANO order."""

import mujoco
import numpy as np
import pytest

from benchmark.camera.keypoints import (
    KEYPOINT_FINGER,
    KEYPOINT_NAMES,
    MANO_NAMES,
    MANO_TO_OPENPOSE,
    OPENPOSE_TO_MANO,
    keypoint_radius,
    keypoint_tolerance,
    keypoints_world,
)
from benchmark.world.assets import build_world, set_frame
from benchmark.world.scenario import Scenario
from benchmark.world.simulate import simulate


@pytest.fixture(scope="module")
def lift():
    sc = Scenario(task="lift", duration_s=1.0, hand_surface="capsules")
    ep = simulate(sc)
    world = build_world(sc)
    return world, ep.truth, keypoints_world(world, ep.truth)


def test_order_names_and_mano_mapping():
    assert len(KEYPOINT_NAMES) == 21 and KEYPOINT_NAMES[:5] == ("wrist", "thumb_cmc", "thumb_mcp", "thumb_ip",
                                                                 "thumb_tip")
    assert KEYPOINT_NAMES[5:9] == ("index_mcp", "index_pip", "index_dip", "index_tip")
    assert KEYPOINT_NAMES[17:] == ("little_mcp", "little_pip", "little_dip", "little_tip")
    # manopth's reorder of its MANO-ordered joints into this order (manolayer.py):
    assert MANO_TO_OPENPOSE.tolist() == [0, 13, 14, 15, 16, 1, 2, 3, 17, 4, 5, 6, 18, 10, 11, 12, 19, 7, 8, 9, 20]
    assert np.array_equal(OPENPOSE_TO_MANO[MANO_TO_OPENPOSE], np.arange(21))
    # the names agree through the mapping: MANO's "index1" is our index MCP, "thumb1" our thumb CMC
    joint = {"thumb": ("cmc", "mcp", "ip"), "other": ("mcp", "pip", "dip")}
    for j, name in enumerate(MANO_NAMES):
        digit, _, rest = name.partition("_")
        if name == "wrist":
            want = "wrist"
        elif rest == "tip":
            want = name
        else:
            digit = name[:-1]
            want = f"{digit}_{joint['thumb' if digit == 'thumb' else 'other'][int(name[-1]) - 1]}"
        assert KEYPOINT_NAMES[OPENPOSE_TO_MANO[j]] == want, (j, name)


def test_joints_are_the_segment_origins_and_the_chain_lengths_are_the_bones(lift):
    world, truth, kp = lift
    hand = world.hand
    assert kp.shape == (len(truth.t), 21, 3) and kp.dtype == np.float64
    # consecutive joints of a digit are one bone apart (the child's offset): 0 to 1e-12 m
    for d in range(5):
        segs = [b for b in range(1, len(hand.segment_names)) if hand.segment_names[b].startswith(hand.finger_names[d])]
        for i in range(2):
            bone = float(np.linalg.norm(hand.offset_pos[segs[i + 1]]))
            got = np.linalg.norm(kp[:, 2 + 4 * d + i] - kp[:, 1 + 4 * d + i], axis=-1)
            np.testing.assert_allclose(got, bone, atol=1e-12)
    # the base joints sit at the palm's finger bases: distance to the wrist constant over the episode
    base = np.linalg.norm(kp[:, [1, 5, 9, 13, 17]] - kp[:, :1], axis=-1)
    assert np.ptp(base, axis=0).max() < 1e-12


def test_tips_are_one_pad_radius_beyond_the_truths_fingertips(lift):
    world, truth, kp = lift
    r = np.asarray(world.hand.fingertip_radius)
    off = kp[:, 4::4] - truth.fingertip_pos
    np.testing.assert_allclose(np.linalg.norm(off, axis=-1), np.broadcast_to(r, off.shape[:2]), rtol=0, atol=1e-12)
    # thumb tip: 9.51 mm from the pad centre (user 0), along the distal phalanx, away from the IP joint
    assert 0.009 < r[0] < 0.010
    bone = truth.fingertip_pos[:, 0] - kp[:, 3]
    cos = (off[:, 0] * bone).sum(-1) / (np.linalg.norm(off[:, 0], axis=-1) * np.linalg.norm(bone, axis=-1))
    np.testing.assert_allclose(cos, 1.0, atol=1e-12)


def test_wrist_and_joints_match_an_independent_forward_kinematics(lift):
    """Frame 15 posed again; the wrist from MuJoCo's geom pose of the middle metacarpal capsule."""
    world, truth, kp = lift
    k = 15
    data = mujoco.MjData(world.model)
    set_frame(world, data, truth.box_pos[k], truth.box_quat[k], truth.hand_qpos[k])
    # hand.yaml's second palm capsule, meta_middle, is the hand model's geom 1: MJCF "hand_palm_1"
    g = mujoco.mj_name2id(world.model, mujoco.mjtObj.mjOBJ_GEOM, "hand_palm_1")
    centre, rot = data.geom_xpos[g], data.geom_xmat[g].reshape(3, 3)
    half = world.model.geom_size[g, 1]
    # a capsule geom's axis is its local z; the proximal end is the one at -half along it
    ends = centre + np.array([-1.0, 1.0])[:, None] * half * rot[:, 2]
    wrist = ends[np.argmax(np.linalg.norm(ends - kp[k, 9], axis=-1))]  # the end away from the MCP
    np.testing.assert_allclose(kp[k, 0], wrist, atol=1e-12)
    assert KEYPOINT_FINGER[0] == -1 and KEYPOINT_FINGER[4] == 0 and KEYPOINT_FINGER[20] == 4


def test_local_radii_and_tolerance(lift):
    world, _, _ = lift
    hand = world.hand
    r = keypoint_radius(hand)
    # user 0's hand: the wrist's metacarpal radius, the index PIP the larger of its proximal and middle
    # phalanges', the tips the pads'
    assert r.shape == (21,)
    geom_r = np.asarray(hand.geom_radius)
    assert r[0] == geom_r[1]
    np.testing.assert_array_equal(r[4::4], hand.fingertip_radius)
    assert 0.006 < r.min() and r.max() < 0.014  # 6.7 mm (little tip) to 12.5 mm (thumb CMC) for user 0
    np.testing.assert_allclose(keypoint_tolerance(hand), 1.5 * r)
