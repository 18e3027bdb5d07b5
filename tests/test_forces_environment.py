"""The table as an environment contact: corner detection from the pose, and forces on it."""

import numpy as np
import pytest
from forces_oracle import box_model, oracle, random_grasp

from fsv import Contacts, InputError, Kinematics
from fsv.forces import ForceSettings, FrameStatus, decompose_forces, nominal_forces, table_contacts
from fsv.forces.environment import UNIT_CORNERS


def _rot_y(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def _rot_x(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def _kin(pos, rot, acc=None):
    T = len(pos)
    z = np.zeros((T, 3))
    return Kinematics(t=np.arange(T) / 30, pos=pos, rot=rot, vel=z, acc=z if acc is None else acc, omega=z,
                      alpha=z, valid=np.ones(T, bool))


def _no_fingers(T, K=2):
    return Contacts(finger_names=[f"f{k}" for k in range(K)], active=np.zeros((T, K), bool),
                    sliding=np.zeros((T, K), bool), point=np.zeros((T, K, 3)), normal=np.zeros((T, K, 3)),
                    slide_dir=np.zeros((T, K, 3)))


def test_corners_on_the_table_from_the_pose():
    model = box_model()
    h = model.half_extents
    tip = np.deg2rad(15)
    small = np.deg2rad(2)
    # Flat; flat on its side (rotated 90 deg about x); tipped 15 deg onto an edge; lifted by 1 cm;
    # seen tilted by 2 degrees (a pose error: the far end is 6 mm up) but still resting.
    rot = np.stack([np.eye(3), _rot_x(np.pi / 2), _rot_y(tip), np.eye(3), _rot_y(small)])
    edge_z = h[0] * np.sin(tip) + h[2] * np.cos(tip)
    small_z = h[0] * np.sin(small) + h[2] * np.cos(small)
    pos = np.array([[0, 0, h[2] - 1e-4], [0, 0, h[1]], [0, 0, edge_z], [0, 0, h[2] + 0.01], [0, 0, small_z]])
    tc = table_contacts(_kin(pos, rot), model)
    assert list(tc.active.sum(axis=1)) == [4, 4, 2, 0, 4]
    assert np.array_equal(tc.active[4], tc.active[0])
    assert table_contacts(_kin(pos, rot), model, max_tilt_deg=1.0).active[4].sum() == 2
    assert np.all(UNIT_CORNERS[tc.active[0]][:, 2] == -1)  # the bottom face
    assert np.all(UNIT_CORNERS[tc.active[1]][:, 1] == -1)  # +90 deg about x turns +y up, -y down
    low = UNIT_CORNERS[tc.active[2]]
    assert np.all(low[:, 0] == 1) and np.all(low[:, 2] == -1)  # the edge at +x, -z
    assert np.allclose(tc.normal[1], _rot_x(np.pi / 2).T @ [0, 0, 1])
    with pytest.raises(InputError, match="height_tol_m"):
        table_contacts(_kin(pos, rot), model, height_tol_m=-1.0)
    with pytest.raises(InputError, match="max_tilt_deg"):
        table_contacts(_kin(pos, rot), model, max_tilt_deg=60.0)


def test_a_box_resting_on_the_table_is_carried_by_it():
    model = box_model(mass_kg=0.4)
    h = model.half_extents
    pos = np.array([[0, 0, h[2]], [0, 0, h[2] + 0.05]])
    sol = nominal_forces(_kin(pos, np.stack([np.eye(3)] * 2)), _no_fingers(2), model)
    assert list(sol.status) == [FrameStatus.OPTIMAL, FrameStatus.NO_CONTACTS]
    assert list(sol.env_active) == [4, 0]
    assert np.allclose(sol.env_wrench[0], [0, 0, 0.4 * 9.81, 0, 0, 0], atol=1e-6)
    off = nominal_forces(_kin(pos, np.stack([np.eye(3)] * 2)), _no_fingers(2), model,
                         settings=ForceSettings(table=False))
    assert list(off.status) == [FrameStatus.NO_CONTACTS] * 2


def test_table_and_fingers_share_the_load_as_the_oracle_says():
    """Fingers grip a box still on the table while it starts to accelerate sideways."""
    rng = np.random.default_rng(4)
    model = box_model(mass_kg=0.6)
    h = model.half_extents
    contacts, _ = random_grasp(rng, 1, 3, model, p_sliding=0.0)
    # Put the fingers on the side faces only (the bottom face rests on the table).
    point = contacts.point.copy()
    normal = contacts.normal.copy()
    for k, (axis, side) in enumerate([(1, -1), (1, 1), (0, 1)]):
        point[0, k] = [0.03 * k, 0.01, 0.0]
        point[0, k, axis] = side * h[axis]
        normal[0, k] = 0
        normal[0, k, axis] = -side
    contacts = Contacts(contacts.finger_names, contacts.active, contacts.sliding, point, normal, contacts.slide_dir)
    acc = np.array([[1.5, 0.3, 0.0]])
    kin = _kin(np.array([[0, 0, h[2]]]), np.eye(3)[None], acc=acc)
    sol = nominal_forces(kin, contacts, model)
    assert sol.status[0] == FrameStatus.OPTIMAL
    assert np.allclose(sol.net_wrench, sol.required, atol=1e-6)
    corners = np.flatnonzero(table_contacts(kin, model).active[0])
    nom, _, corner = oracle("nominal", sol.required[0], contacts, 0, model, corners=corners,
                            table_normal=np.array([0.0, 0.0, 1.0]))
    assert np.abs(sol.force[0] - nom).max() <= 1e-4
    assert np.abs(sol.env_wrench[0, :3] - corner.sum(axis=0)).max() <= 1e-3
    # The table is cheap (weight 0.01): it carries most of the weight.
    assert sol.env_wrench[0, 2] > 0.9 * 0.6 * 9.81


def test_a_finger_pressing_the_box_onto_the_table_is_an_internal_squeeze():
    """One finger presses 3 N down on the top face of a box at rest on the table: no finger force is
    needed (nominal 0), and the measured 3 N is internal, balanced by the table's internal part."""
    model = box_model(mass_kg=0.4)
    h = model.half_extents
    contacts = Contacts(finger_names=["index"], active=[[True]], sliding=[[False]], point=[[[0.02, 0.01, h[2]]]],
                        normal=[[[0.0, 0.0, -1.0]]], slide_dir=np.zeros((1, 1, 3)))
    kin = _kin(np.array([[0, 0, h[2]]]), np.eye(3)[None])
    sol = decompose_forces(kin, contacts, model, [[3.0]])
    assert sol.status[0] == FrameStatus.OPTIMAL
    assert sol.normal_force[0, 0] == pytest.approx(3.0, abs=1e-3)
    assert np.abs(sol.nominal[0]).max() < 1e-3
    assert np.allclose(sol.internal_wrench, 0, atol=1e-7)
    # The table reacts straight up (up to the regularisation's trade-off, about 1e-3 N of friction).
    assert np.allclose(sol.env_internal_wrench[0, :3], [0, 0, 3.0], atol=3e-3)
    assert np.allclose(sol.env_wrench[0, :3], [0, 0, 3.0 + 0.4 * 9.81], atol=3e-3)
    assert np.allclose(sol.net_wrench, sol.required, atol=1e-6)
    corners = np.flatnonzero(table_contacts(kin, model).active[0])
    nom, inner, corner = oracle("decomposition", sol.required[0], contacts, 0, model, target=np.array([[3.0]]),
                                corners=corners, table_normal=np.array([0.0, 0.0, 1.0]))
    assert np.abs(sol.nominal[0] - nom).max() <= 1e-4 and np.abs(sol.internal[0] - inner).max() <= 1e-4
    assert np.abs(sol.env_wrench[0, :3] - corner.sum(axis=0)).max() <= 1e-3
