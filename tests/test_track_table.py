import numpy as np
import pytest

from fsv import InputError
from fsv.forces.environment import table_contacts
from fsv.kinematics import kinematics_in_frame
from fsv.linalg import mm, mv, rigid_inverse
from fsv.models import ObjectModel
from fsv.track.table import TableFitConfig, TablePlane, fit_table, table_frame
from fsv.types import Calibration, Kinematics

SIZE = np.array([0.171, 0.111, 0.06])
MODEL = ObjectModel(size_m=SIZE, mass_kg=0.5, inertia=ObjectModel.solid_box_inertia(SIZE, 0.5), friction=0.8)


def _camera():
    """A 160 x 120 camera 0.5 m above the table, 0.45 m back, looking down at 50 degrees."""
    a = np.radians(50.0)
    R = np.array([[1.0, 0.0, 0.0], [0.0, -np.sin(a), np.cos(a)], [0.0, -np.cos(a), -np.sin(a)]])  # cam -> world
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = R, [0.0, -0.45, 0.5]
    return Calibration(K=np.array([[150.0, 0, 79.5], [0, 150.0, 59.5], [0, 0, 1]]), T_world_cam=T, width=160, height=120)


def _plane_depth(calib, normal, offset, noise=0.0, seed=0):
    v, u = np.mgrid[0:calib.height, 0:calib.width]
    d = np.stack([(u - calib.K[0, 2]) / calib.K[0, 0], (v - calib.K[1, 2]) / calib.K[1, 1], np.ones(u.shape)], -1)
    ray = d @ calib.T_world_cam[:3, :3].T
    z = (offset - normal @ calib.T_world_cam[:3, 3]) / (ray @ normal)
    z = z + noise * np.random.default_rng(seed).standard_normal(z.shape)
    return np.where(z > 0, z, 0.0).astype(np.float32)


def _tilted(deg=0.5, offset=0.004):
    t = np.radians(deg)
    return np.array([np.sin(t), 0.0, np.cos(t)]), offset


def test_the_table_is_fitted_where_the_depth_shows_it():
    calib = _camera()
    n, d = _tilted(0.5, 0.004)  # a calibration 0.5 degrees and 4 mm off
    depth = _plane_depth(calib, n, d, noise=0.005)
    box = np.array([0.1, 0.05, 0.03])
    height = fit_table(depth, calib, box, np.eye(3), MODEL)  # the default: its height under the box
    assert height.fitted and height.normal.tolist() == [0.0, 0.0, 1.0]
    assert height.offset == pytest.approx((d - n[0] * 0.1) / n[2], abs=3e-4)  # 3.1 mm, not 4
    plane = fit_table(depth, calib, box, np.eye(3), MODEL, config=TableFitConfig(tilt=True))
    assert plane.fitted and plane.points > 10000
    assert np.degrees(np.arccos(plane.normal @ n)) < 0.05
    assert plane.offset == pytest.approx(d, abs=3e-4)
    assert plane.sigma_m == pytest.approx(0.005 * 0.77, rel=0.3)  # axial noise times the rays' vertical part


def test_the_box_and_what_stands_above_the_table_are_left_out():
    calib = _camera()
    n, d = _tilted(0.3, -0.002)
    depth = _plane_depth(calib, n, d)
    box = _plane_depth(calib, np.array([0.0, 0.0, 1.0]), 0.015)  # a slab 15 mm above the table ...
    v, u = np.mgrid[0:calib.height, 0:calib.width]
    patch = (abs(u - 80) < 30) & (abs(v - 60) < 20)
    depth = np.where(patch, box, depth)  # ... seen over a patch of the image
    centre = calib.T_world_cam[:3, 3] + box[60, 80] * (calib.T_world_cam[:3, :3] @ [0.0, 0.0, 1.0])
    plane = fit_table(depth, calib, centre, np.eye(3), MODEL, config=TableFitConfig(box_margin_m=0.0, tilt=True))
    assert np.degrees(np.arccos(plane.normal @ n)) < 0.01 and plane.offset == pytest.approx(d, abs=1e-4)


def test_no_table_near_the_believed_one_keeps_the_calibrations():
    calib = _camera()
    far = fit_table(_plane_depth(calib, np.array([0.0, 0.0, 1.0]), 0.05), calib, np.zeros(3), np.eye(3), MODEL)
    assert not far.fitted and far.offset == 0.0 and far.normal.tolist() == [0.0, 0.0, 1.0]
    steep = fit_table(_plane_depth(calib, *_tilted(5.0, 0.0)), calib, np.zeros(3), np.eye(3), MODEL,
                      config=TableFitConfig(band_m=0.2, tilt=True))
    assert not steep.fitted
    empty = fit_table(np.zeros((120, 160), np.float32), calib, np.zeros(3), np.eye(3), MODEL)
    assert not empty.fitted
    with pytest.raises(InputError, match="band_m"):
        TableFitConfig(band_m=0.0)


def test_the_table_frame_puts_the_plane_at_zero_and_its_normal_up():
    n, d = _tilted(0.7, 0.003)
    M = table_frame(TablePlane(normal=n, offset=d, points=1))
    R = M[:3, :3]
    assert np.allclose(mm(R.T, R), np.eye(3), atol=1e-15) and np.linalg.det(R) == pytest.approx(1.0)
    assert np.allclose(mv(R, n), [0, 0, 1], atol=1e-15)
    on_plane = np.array([[0.3, -0.2, 0.0], [-0.1, 0.4, 0.0]])
    on_plane[:, 2] = (d - on_plane[:, :2] @ n[:2]) / n[2]
    assert np.allclose((mv(R, on_plane) + M[:3, 3])[:, 2], 0.0, atol=1e-15)
    assert np.allclose(mm(rigid_inverse(M), M), np.eye(4), atol=1e-15)
    assert np.array_equal(table_frame(TablePlane.believed()), np.eye(4))


def test_a_box_on_the_seen_table_rests_on_it_in_the_tables_frame():
    # 3 mm below a believed table tilted by 0.5 degrees the box floats; in the fitted table's frame it rests.
    n, d = _tilted(0.5, 0.006)
    R_box = table_frame(TablePlane(normal=n, offset=d, points=1))[:3, :3].T  # the box's faces along the table
    pos = np.array([0.1, 0.0, (d - 0.1 * n[0]) / n[2]]) + 0.03 * n  # on the plane, 30 mm (half its height) up
    z = np.zeros((2, 3))
    kin = Kinematics(t=[0.0, 0.1], pos=[pos, pos], rot=[R_box, R_box], vel=z, acc=z, omega=z, alpha=z,
                     valid=[True, True])
    assert not table_contacts(kin, MODEL).active.any()
    on = kinematics_in_frame(kin, table_frame(TablePlane(normal=n, offset=d, points=1)))
    assert table_contacts(on, MODEL).active.sum(axis=1).tolist() == [4, 4]
    assert np.allclose(on.rot[0], np.eye(3), atol=1e-12)
