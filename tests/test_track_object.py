"""The box tracker: analytic Jacobian, exact predicted depth, and accuracy on synthetic depth."""

import numpy as np
import pytest
from raycast import look_at_calibration, render_depth

from fsv import InputError, ObjectModel
from fsv.rotation import angle_between, exp_so3
from fsv.track.camera import CameraRays
from fsv.track.object import BoxTracker, BoxTrackerConfig, predict_box_depth, track_box
from fsv.types import DepthVideo

SIZE = np.array([0.171, 0.111, 0.060])
CALIB = look_at_calibration([0.05, -0.45, 0.40], [0.0, 0.0, 0.05])


def box_model():
    return ObjectModel(size_m=SIZE, mass_kg=0.4, inertia=ObjectModel.solid_box_inertia(SIZE, 0.4), friction=0.8)


def fingers(pos):
    """Two finger-like capsules touching the box's x faces (occluders)."""
    return [(pos + [0.094, -0.03, 0.0], pos + [0.12, -0.03, 0.05], 0.009),
            (pos + [-0.094, 0.0, 0.0], pos + [-0.12, 0.0, 0.05], 0.009)]


def test_depth_jacobian_matches_central_differences():
    rays = CameraRays.from_calibration(CALIB)
    pos, rot = np.array([0.01, 0.02, 0.06]), exp_so3([0.1, 0.2, 0.5])
    idx = np.arange(rays.ray.shape[0])
    _, w, _, J = predict_box_depth(rays, idx, pos, rot, SIZE / 2, CALIB.K[0, 0], 0.5, jacobian=True)
    h = 1e-6
    Jn = np.zeros_like(J)
    for k in range(6):
        d = np.zeros(6)
        d[k] = h
        zp = predict_box_depth(rays, idx, pos + d[:3], exp_so3(d[3:]) @ rot, SIZE / 2, CALIB.K[0, 0])[0]
        zm = predict_box_depth(rays, idx, pos - d[:3], exp_so3(-d[3:]) @ rot, SIZE / 2, CALIB.K[0, 0])[0]
        Jn[:, k] = (zp - zm) / (2 * h)
    on = w > 1e-3
    assert on.sum() > 2000
    rel = np.abs(J - Jn)[on].max(1) / (np.abs(Jn)[on].max(1) + 1e-3)
    assert np.percentile(rel, 99.5) < 1e-4


def test_predicted_depth_equals_ray_cast_inside_the_silhouette():
    rays = CameraRays.from_calibration(CALIB)
    pos, rot = np.array([0.0, 0.01, 0.08]), exp_so3([0.3, -0.2, 0.4])
    idx = np.arange(rays.ray.shape[0])
    z, w, _ = predict_box_depth(rays, idx, pos, rot, SIZE / 2, CALIB.K[0, 0], 0.5)
    truth = render_depth(CALIB, pos, rot, SIZE / 2).reshape(-1)
    inside, outside = w > 1 - 1e-6, w < 1e-6
    assert inside.sum() > 1500
    np.testing.assert_allclose(z[inside], truth[inside], atol=1e-6)
    np.testing.assert_allclose(z[outside], truth[outside], atol=1e-6)  # the table


def test_tracks_a_lifted_rotating_box_through_noise_and_occluders():
    rng = np.random.default_rng(3)
    T = 30
    pos = [np.array([0.0, 0.0, 0.03 + 0.12 * max(0.0, (k - 8) / 22) ** 2]) for k in range(T)]
    rot = [exp_so3([0.0, 0.15 * k / T, 0.4 * k / T]) for k in range(T)]
    frames = np.stack([render_depth(CALIB, p, R, SIZE / 2, fingers(p), 0.01, rng) for p, R in zip(pos, rot)])
    poses, inliers = track_box(DepthVideo(frames, 30.0), CALIB, box_model(), pos[0] + [0.012, -0.01, 0.006],
                               exp_so3([0.0, 0.03, 0.1]) @ rot[0], rng=np.random.default_rng(0))
    pos_err = np.linalg.norm(poses.pos - np.array(pos), axis=1)
    rot_err = np.degrees(angle_between(poses.rot, np.array(rot)))
    assert np.median(pos_err) <= 0.002, pos_err
    assert np.median(rot_err) <= 1.5, rot_err
    assert pos_err.max() < 0.006 and rot_err.max() < 4.0
    assert np.all(inliers > 0.8)


def test_lost_fit_is_recovered_by_the_particle_search():
    rng = np.random.default_rng(5)
    pos, rot = np.array([0.02, 0.0, 0.1]), exp_so3([0.0, 0.0, 0.3])
    frame = render_depth(CALIB, pos, rot, SIZE / 2, (), 0.005, rng)
    tracker = BoxTracker(CALIB, box_model(), pos + [0.03, 0.025, -0.02], exp_so3([0.0, 0.1, 0.3]) @ rot,
                         rng=np.random.default_rng(1))
    fit = tracker.update(frame)
    assert np.linalg.norm(fit.pos - pos) < 0.003
    assert np.degrees(angle_between(fit.rot, rot)) < 2.0


def test_bad_inputs_are_named():
    with pytest.raises(InputError, match="pos0"):
        BoxTracker(CALIB, box_model(), [0.0, 0.0], np.eye(3))
    with pytest.raises(InputError, match="rot0"):
        BoxTracker(CALIB, box_model(), [0.0, 0.0, 0.03], 2 * np.eye(3))
    with pytest.raises(InputError, match="max_pixels"):
        BoxTrackerConfig(max_pixels=0)
    tracker = BoxTracker(CALIB, box_model(), [0.0, 0.0, 0.03], np.eye(3))
    with pytest.raises(InputError, match="240, 320"):
        tracker.update(np.zeros((10, 10), np.float32))
