"""Camera views (benchmark.camera.views): view 0 is the paper's set-up, view N is drawn around it."""

import numpy as np
import pytest

from benchmark.camera.camera import load_camera
from benchmark.camera.views import AZIMUTH_DEG, DISTANCE_M, ELEVATION_DEG, TARGET, TARGET_JITTER_M, camera_of, view_of
from benchmark.errors import ScenarioError
from benchmark.world.scenario import Scenario, episode_name


def test_view_0_is_camera_yaml():
    cam, yaml_cam = camera_of(0), load_camera()
    np.testing.assert_array_equal(cam.T_world_cam, yaml_cam.T_world_cam)
    v = view_of(0)
    assert v.distance_m == pytest.approx(0.549, abs=1e-3) and v.elevation_deg == pytest.approx(36.96, abs=0.01)
    assert v.azimuth_deg == pytest.approx(65.77, abs=0.01)


def test_drawn_views_lie_in_the_stated_ranges_and_are_the_same_for_every_call():
    views = [view_of(i) for i in range(1, 60)]
    assert view_of(7) == view_of(7) and view_of(7) != view_of(8)
    for v in views:
        assert DISTANCE_M[0] <= v.distance_m <= DISTANCE_M[1]
        assert ELEVATION_DEG[0] <= v.elevation_deg <= ELEVATION_DEG[1]
        assert AZIMUTH_DEG[0] <= v.azimuth_deg <= AZIMUTH_DEG[1]
        assert np.all(np.abs(np.subtract(v.target[:2], TARGET[:2])) <= TARGET_JITTER_M)
    assert np.ptp([v.azimuth_deg for v in views]) > 60  # they spread over the range


@pytest.mark.parametrize("index", [1, 5, 23])
def test_a_views_camera_stands_where_the_view_says_and_looks_at_its_target(index):
    v, cam = view_of(index), camera_of(index)
    centre = cam.T_world_cam[:3, 3]
    d = centre - np.asarray(v.target)
    assert np.linalg.norm(d) == pytest.approx(v.distance_m)
    assert np.degrees(np.arcsin(d[2] / np.linalg.norm(d))) == pytest.approx(v.elevation_deg)
    assert np.degrees(np.arctan2(d[1], d[0])) == pytest.approx(v.azimuth_deg)
    p = np.linalg.inv(cam.T_world_cam) @ np.append(v.target, 1.0)  # the target projects to the principal point
    np.testing.assert_allclose(cam.K @ p[:3] / p[2], [cam.K[0, 2], cam.K[1, 2], 1.0], atol=1e-9)
    assert cam.T_world_cam[2, 1] < 0  # the image's up is the world's up
    np.testing.assert_array_equal(cam.K, load_camera().K)


def test_a_view_is_part_of_the_scenario_and_its_name():
    assert episode_name(Scenario(task="lift", seed=3)) == "lift-u0-g0-m0-s3"
    assert episode_name(Scenario(task="lift", seed=3, view=5)) == "lift-u0-g0-m0-s3-v5"
    with pytest.raises(ScenarioError, match="view must be a non-negative integer, got -1"):
        Scenario(view=-1)


def test_a_lift_from_another_view_shows_the_box_and_the_hand_and_gives_its_calibration():
    from benchmark.camera.render import render
    from benchmark.camera.scene import LABEL_BOX, LABEL_FINGER0
    from benchmark.world.simulate import simulate

    ep = render(simulate(Scenario(task="lift", seed=1, duration_s=1.0, view=4)))
    np.testing.assert_array_equal(ep.calib.T_world_cam, camera_of(4).T_world_cam)  # the method gets the view's calibration
    assert np.sum(ep.labels[0] == LABEL_BOX) > 1000 and np.sum(ep.labels[-1] >= LABEL_FINGER0) > 100
