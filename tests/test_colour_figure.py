"""The colour pictures: written, sane images; the skeleton, the crop and the frame choices."""

import numpy as np
import pytest
from PIL import Image

from benchmark.camera.labelling import StreamLabels
from benchmark.commands.pictures import colour_figure as cf
from benchmark.errors import BenchmarkError


def test_the_pictures_are_written_and_show_something(tmp_path):
    shot = cf.Shot(tone=6, grasp=0, view=1, seed=2)
    blur = cf.Shot(tone=6, grasp=0, view=1, seed=4, task="shake")
    paths = cf.write_colour_figures(tmp_path / "new", shots=(shot,), blur=blur, duration_s=1.5, shake_duration_s=3.0,
                                    fps=10.0)
    assert [p.name for p in paths] == list(cf.FILES)
    for p in paths:
        assert p.stat().st_size < 400_000
        with Image.open(p) as im:
            assert im.format == "PNG"
            rgb = np.asarray(im.convert("RGB")).astype(int)
        assert rgb.shape[0] >= 300 and rgb.shape[1] >= 600, (p.name, rgb.shape)
        # not blank: many distinct colours and a spread of brightness (a frame, not an empty axes)
        assert len(np.unique(rgb.reshape(-1, 3), axis=0)) > 100, p.name
        assert rgb.std() > 20, p.name
    labels = np.asarray(Image.open(paths[1]).convert("RGB")).astype(int)
    r_g, b_g = labels[..., 0] - labels[..., 1], labels[..., 2] - labels[..., 1]
    hand = (np.abs(r_g - 0.35 * 235) < 25) & (np.abs(b_g - 0.35 * 127) < 25)  # deep pink at 35 % over grey
    assert hand.mean() > 0.005  # the translucent hand mask drawn over the depth
    assert not list((tmp_path / "new").glob("*.tmp*"))


def test_the_skeleton_joins_the_wrist_to_each_digit_and_runs_along_it():
    assert len(cf.SKELETON) == 20
    assert [b for a, b in cf.SKELETON if a == 0] == [1, 5, 9, 13, 17]
    assert (7, 8) in cf.SKELETON and (19, 20) in cf.SKELETON and (4, 5) not in cf.SKELETON


def test_the_crop_holds_the_hand_and_the_box_with_a_margin():
    lab = np.zeros((100, 200), np.uint8)
    lab[40:60, 100:120] = 2  # the box
    lab[50:52, 90:95] = 10  # a finger
    u0, u1, v0, v1 = cf.crop_of(lab, np.full((21, 2), np.nan), margin=0.25)
    assert u0 <= 90 and u1 >= 120 and v0 <= 40 and v1 >= 60
    assert (u1 - u0) == pytest.approx(1.5 * 29 + 2, abs=2)  # 30 px wide box of labels, widened by 25 % each side
    assert cf.crop_of(lab, np.array([[5.0, 5.0]] + [[np.nan, np.nan]] * 20))[:4:2] == (0, 0)  # a keypoint widens it


def _labels(uv, vis):
    T = len(uv)
    z = np.zeros((T, 21))
    return StreamLabels(keypoints_uv=uv, keypoints_z=z, keypoint_visibility=vis, cam_R_m2c=np.zeros((T, 3, 3)),
                        cam_t_m2c=np.zeros((T, 3)), contact_point_cam=np.zeros((T, 5, 3)),
                        contact_normal_cam=np.zeros((T, 5, 3)), contact_force_cam=np.zeros((T, 5, 3)))


def test_the_fastest_frame_is_where_the_visible_keypoints_move_most():
    T = 8
    x = np.array([0, 1, 2, 3, 10, 20, 21, 22], float)  # fastest about frame 4-5
    uv = np.zeros((T, 21, 2))
    uv[..., 0] = x[:, None]
    vis = np.zeros((T, 21), np.uint8)
    lab = _labels(uv, vis)
    assert cf.image_speed(lab, 4) == pytest.approx((20 - 3) / 2)
    assert cf.fastest_frame(lab) == 4
    assert cf.fastest_frame(lab, frames=[1, 2, 5, 6]) == 5
    hidden = vis.copy()
    hidden[3:7] = 2  # not seen around the fast frames
    assert cf.image_speed(_labels(uv, hidden), 4) == -1.0
    assert cf.fastest_frame(_labels(uv, hidden)) == 1
    with pytest.raises(BenchmarkError, match="at least 3 frames"):
        cf.fastest_frame(_labels(uv[:2], vis[:2]))
