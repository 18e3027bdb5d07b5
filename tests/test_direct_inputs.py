"""fsv.learn.direct_inputs: what the end-to-end network sees of a frame, in the object frame."""

import numpy as np
import pytest

from fsv import Contacts, InputError, Kinematics, ObjectModel
from fsv.learn.direct_inputs import MAX_WINDOW, direct_inputs, input_names, lowest_height

SIZE = np.array([0.171, 0.111, 0.06])
G = np.array([0.0, 0.0, -9.81])


def model(mass=0.3):
    return ObjectModel(size_m=SIZE, mass_kg=mass, inertia=ObjectModel.solid_box_inertia(SIZE, mass), friction=0.8)


def rot_z(angle):
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def frames(T=5, K=2, valid=None, acc=(1.0, 0.0, 0.0), z=0.03):
    """A box turned 90 degrees about z, accelerating along world x, spinning about world z."""
    rot = np.repeat(rot_z(np.pi / 2)[None], T, 0)
    pos = np.tile([0.0, 0.0, z], (T, 1))
    kin = Kinematics(t=np.arange(T) / 30, pos=pos, rot=rot, vel=np.tile([0.5, 0.0, 0.0], (T, 1)),
                     acc=np.tile(acc, (T, 1)), omega=np.tile([0.0, 0.0, 2.0], (T, 1)),
                     alpha=np.tile([0.0, 0.0, 3.0], (T, 1)) * np.arange(T)[:, None],
                     valid=np.ones(T, bool) if valid is None else valid)
    active = np.zeros((T, K), bool)
    active[:, 0] = True
    point = np.tile([0.0855, 0.01, 0.0], (T, K, 1))
    normal = np.tile([-1.0, 0.0, 0.0], (T, K, 1))
    con = Contacts(("thumb", "index")[:K], active, np.zeros((T, K), bool), point, normal, np.zeros((T, K, 3)))
    return kin, con


def column(x, name, window=0):
    return x[:, input_names(("thumb", "index"), window).index(name)]


def test_the_kinematics_are_expressed_in_the_object_frame_and_the_required_wrench_follows_eq_1():
    kin, con = frames()
    x, valid = direct_inputs(kin, con, model(), G)
    assert valid.all() and x.shape == (5, len(input_names(("thumb", "index"))))
    # R = Rz(90 deg): world x is the box's -y, world z its z
    spec = np.stack([column(x, f"spec_{a}") for a in "xyz"], axis=1)
    np.testing.assert_allclose(spec, np.tile([0.0, -1.0, 9.81], (5, 1)), atol=1e-12)
    np.testing.assert_allclose(column(x, "vel_y"), -0.5, atol=1e-12)
    np.testing.assert_allclose(column(x, "up_z"), 1.0)
    np.testing.assert_allclose(column(x, "wrench_Fz"), 0.3 * 9.81, rtol=1e-12)
    I = ObjectModel.solid_box_inertia(SIZE, 0.3)
    # omega and alpha along the box's z: I alpha about z, and omega x I omega = 0
    np.testing.assert_allclose(column(x, "wrench_Tz"), I[2, 2] * 3.0 * np.arange(5), rtol=1e-12)
    np.testing.assert_allclose(column(x, "height"), 0.03 - 0.03, atol=1e-15)  # resting on its 60 mm face
    assert column(x, "mass")[0] == 0.3 and column(x, "half_x")[0] == SIZE[0] / 2


def test_an_inactive_finger_reads_zero_and_frames_without_kinematics_nan():
    valid = np.array([False, True, True, True, False])
    kin, con = frames(valid=valid)
    x, ok = direct_inputs(kin, con, model(), G)
    np.testing.assert_array_equal(ok, valid)
    assert np.isnan(x[~valid]).all() and np.isfinite(x[valid]).all()
    assert (column(x, "active_index")[valid] == 0).all() and (column(x, "normal_x_index")[valid] == 0).all()
    assert (column(x, "active_thumb")[valid] == 1).all() and (column(x, "normal_x_thumb")[valid] == -1).all()


def test_the_window_takes_neighbours_and_holds_the_frame_itself_at_the_edges_and_gaps():
    valid = np.array([True, True, True, False, True])
    kin, con = frames(valid=valid)
    x, _ = direct_inputs(kin, con, model(), G, window=1)
    before, after = column(x, "alpha_z@-1", 1), column(x, "alpha_z@+1", 1)
    # alpha_z(t) = 3 t (the box's z is the world's): neighbours where they have kinematics, else the frame's own
    np.testing.assert_allclose(before[[0, 1, 2, 4]], [0.0, 0.0, 3.0, 12.0])
    np.testing.assert_allclose(after[[0, 1, 2, 4]], [3.0, 6.0, 6.0, 12.0])


def test_the_lowest_corner_of_a_tilted_box():
    kin, _ = frames(z=0.1)
    tilt = np.array([[1.0, 0.0, 0.0], [0.0, np.cos(0.3), -np.sin(0.3)], [0.0, np.sin(0.3), np.cos(0.3)]])
    kin = Kinematics(kin.t, kin.pos, np.repeat(tilt[None], 5, 0), kin.vel, kin.acc, kin.omega, kin.alpha, kin.valid)
    corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]) * SIZE / 2
    np.testing.assert_allclose(lowest_height(kin, model()), 0.1 + (corners @ tilt.T)[:, 2].min(), rtol=1e-12)


@pytest.mark.parametrize("window", [-1, MAX_WINDOW + 1, 1.5, True])
def test_a_bad_window_is_refused(window):
    kin, con = frames()
    with pytest.raises(InputError, match="window must be an integer"):
        direct_inputs(kin, con, model(), G, window=window)
