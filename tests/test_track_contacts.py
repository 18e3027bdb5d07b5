"""Contact detection from tracked fingertips: projection, hysteresis, sliding, occlusion prior."""

import numpy as np
import pytest

from fsv import InputError, ObjectModel, Poses
from fsv.track.contacts import ContactConfig, detect_contacts, surface_contact

SIZE = np.array([0.171, 0.111, 0.060])
HALF = SIZE / 2
MODEL = ObjectModel(size_m=SIZE, mass_kg=0.4, inertia=ObjectModel.solid_box_inertia(SIZE, 0.4), friction=0.8)


def box_poses(T, pos=(0.1, 0.2, 0.03), rot=np.eye(3)):
    return Poses(t=np.arange(T) / 30, pos=np.tile(pos, (T, 1)), rot=np.tile(rot, (T, 1, 1)))


def test_surface_contact_projects_onto_the_nearest_face_with_inward_normal():
    pts = np.array([[0.01, HALF[1] + 0.02, 0.0], [0.0, 0.0, HALF[2] - 0.005], [-HALF[0] - 0.003, 0.01, -0.01]])
    point, normal, dist = surface_contact(pts, HALF)
    np.testing.assert_allclose(point, [[0.01, HALF[1], 0.0], [0.0, 0.0, HALF[2]], [-HALF[0], 0.01, -0.01]])
    np.testing.assert_allclose(normal, [[0, -1, 0], [0, 0, -1], [1, 0, 0]])
    np.testing.assert_allclose(dist, [0.02, -0.005, 0.003])


def test_contact_hysteresis_and_object_frame_point():
    R = np.array([[0.0, -1, 0], [1, 0, 0], [0, 0, 1]])  # box x along world y
    pos = np.array([0.1, 0.2, 0.03])
    r = 0.008
    gaps = np.array([0.02, 0.005, 0.009, 0.011, 0.013, 0.004])
    # the finger sits over the box's +x face (world +y) at object point (HALF_x, 0.01, 0.005)
    tips = np.array([[pos + R @ [HALF[0] + r + g, 0.01, 0.005]] for g in gaps])
    c = detect_contacts(tips, np.array([r]), np.ones((6, 1), bool), box_poses(6, pos, R), MODEL, ("thumb",))
    assert c.active[:, 0].tolist() == [False, True, True, True, False, True]
    np.testing.assert_allclose(c.point[1, 0], [HALF[0], 0.01, 0.005], atol=1e-12)
    np.testing.assert_allclose(c.normal[1, 0], [-1, 0, 0])


def test_sliding_direction_follows_the_finger_over_the_surface():
    T, r = 20, 0.008
    y = -0.03 + 0.1 * np.arange(T) / 30  # 0.1 m/s along +y on the top face
    tips = np.stack([[0.1 + 0.0, 0.2 + yy, 0.03 + HALF[2] + r] for yy in y])[:, None, :]
    tips2 = np.tile([[0.1 + 0.05, 0.2, 0.03 + HALF[2] + r]], (T, 1))[:, None, :]  # a finger at rest
    c = detect_contacts(np.concatenate([tips, tips2], 1), np.array([r, r]), np.ones((T, 2), bool), box_poses(T),
                        MODEL, ("a", "b"), ContactConfig(slide_window=2))
    assert c.active.all()
    assert c.sliding[2:-2, 0].all() and not c.sliding[:, 1].any()
    np.testing.assert_allclose(c.slide_dir[5, 0], [0, 1, 0], atol=1e-9)


def test_an_unseen_finger_keeps_its_last_observed_contact_point():
    T, r = 6, 0.008
    tips = np.tile([[0.1, 0.2 + HALF[1] + r, 0.03]], (T, 1))[:, None, :].copy()
    tips[3:, 0] += [0.03, 0.05, 0.0]  # the tracker lost the hidden finger: it drifts away
    observed = np.array([[True], [True], [True], [False], [False], [True]])
    c = detect_contacts(tips, np.array([r]), observed, box_poses(T), MODEL, ("index",))
    assert c.active[:5, 0].all() and not c.active[5, 0]
    np.testing.assert_allclose(c.point[4, 0], c.point[2, 0])
    off = detect_contacts(tips, np.array([r]), observed, box_poses(T), MODEL, ("index",),
                          ContactConfig(occlusion_prior=False))
    assert not off.active[3:, 0].any()


def test_bad_inputs_are_named():
    with pytest.raises(InputError, match="on_m"):
        ContactConfig(on_m=0.02, off_m=0.01)
    with pytest.raises(InputError, match="fingertips"):
        detect_contacts(np.zeros((3, 2)), np.ones(2), np.ones((3, 2), bool), box_poses(3), MODEL, ("a", "b"))
