import numpy as np
import pytest

from fsv import Calibration, Contacts, DepthVideo, InputError, Kinematics, ObjectModel, Poses


def test_depth_video_rejects_negative_depth():
    with pytest.raises(InputError, match=">= 0"):
        DepthVideo(depth_m=-np.ones((2, 4, 5)), fps=30)


def test_depth_video_times():
    v = DepthVideo(depth_m=np.zeros((4, 3, 2)), fps=30)
    np.testing.assert_allclose(v.t, [0, 1 / 30, 2 / 30, 3 / 30])
    assert v.depth_m.dtype == np.float32


def test_backproject_principal_point_lies_on_axis():
    K = np.array([[200.0, 0, 2], [0, 200.0, 1], [0, 0, 1]])
    cal = Calibration(K=K, T_world_cam=np.eye(4), width=5, height=3)
    pts = cal.backproject(np.full((3, 5), 0.5))
    np.testing.assert_allclose(pts[1, 2], [0, 0, 0.5])
    np.testing.assert_allclose(pts[1, 4], [2 / 200 * 0.5, 0, 0.5])


def test_calibration_rejects_non_rotation():
    T = np.eye(4)
    T[0, 0] = 2
    with pytest.raises(InputError, match="rotation"):
        Calibration(K=np.eye(3), T_world_cam=T, width=2, height=2)


def test_poses_check_lengths():
    with pytest.raises(InputError, match="differ"):
        Poses(t=np.zeros(3), pos=np.zeros((2, 3)), rot=np.tile(np.eye(3), (3, 1, 1)))


def test_kinematics_imu_is_specific_force_in_object_frame():
    T = 2
    R = np.array([[0.0, -1, 0], [1, 0, 0], [0, 0, 1]])  # object x along world y
    kin = Kinematics(
        t=np.arange(T) / 30, pos=np.zeros((T, 3)), rot=np.tile(R, (T, 1, 1)),
        vel=np.zeros((T, 3)), acc=np.tile([0.0, 1.0, 0.0], (T, 1)),
        omega=np.tile([0.0, 0.0, 2.0], (T, 1)), alpha=np.zeros((T, 3)), valid=np.ones(T, bool),
    )
    acc, gyro = kin.imu(np.array([0, 0, -9.81]))
    np.testing.assert_allclose(acc[0], [1.0, 0, 9.81])
    np.testing.assert_allclose(gyro[0], [0, 0, 2.0])


def test_contacts_sliding_requires_active():
    z = np.zeros((1, 1, 3))
    with pytest.raises(InputError, match="sliding"):
        Contacts(("thumb",), active=[[False]], sliding=[[True]], point=z, normal=z, slide_dir=z)


def test_contacts_gap_defaults_to_unknown_and_rejects_inf():
    z = np.zeros((2, 1, 3))
    c = Contacts(("thumb",), active=[[False], [True]], sliding=[[False], [False]], point=z, normal=z, slide_dir=z)
    assert c.gap.shape == (2, 1) and np.isnan(c.gap).all()
    g = Contacts(("thumb",), [[False], [True]], [[False], [False]], z, z, z, gap=[[0.01], [np.nan]])
    assert g.gap[0, 0] == 0.01 and not g.gap.flags.writeable
    with pytest.raises(InputError, match="Contacts.gap"):
        Contacts(("thumb",), [[False], [True]], [[False], [False]], z, z, z, gap=[[np.inf], [0.0]])
    with pytest.raises(InputError, match="Contacts.gap must have shape"):
        Contacts(("thumb",), [[False], [True]], [[False], [False]], z, z, z, gap=[0.0, 0.0])


def test_object_model_inertia_of_paper_box():
    I = ObjectModel.solid_box_inertia([0.171, 0.111, 0.06], 0.45)
    m = ObjectModel(size_m=[0.171, 0.111, 0.06], mass_kg=0.45, inertia=I, friction=0.8)
    assert m.inertia[2, 2] == pytest.approx(0.45 / 12 * (0.171**2 + 0.111**2))
    with pytest.raises(InputError, match="mass_kg"):
        ObjectModel(size_m=[1, 1, 1], mass_kg=0, inertia=np.eye(3), friction=0.5)


def _colour_calib(width=4, height=3):
    return Calibration(K=np.array([[300.0, 0, 1.5], [0, 300.0, 1.0], [0, 0, 1]]), T_world_cam=np.eye(4),
                       width=width, height=height)


def test_colour_video_holds_uint8_images_of_its_calibrations_size():
    from fsv import ColourVideo

    rgb = np.arange(2 * 3 * 4 * 3, dtype=np.uint8).reshape(2, 3, 4, 3)
    v = ColourVideo(rgb=rgb, fps=30, calib=_colour_calib(), t_s=[0.0, 1 / 30], exposure_s=0.01)
    assert v.num_frames == 2 and not v.rgb.flags.writeable and v.rgb[1, 2, 3, 2] == rgb[1, 2, 3, 2]
    with pytest.raises(InputError, match="uint8"):
        ColourVideo(rgb=rgb.astype(np.float32), fps=30, calib=_colour_calib(), t_s=[0.0, 1 / 30])
    with pytest.raises(InputError, match="its calibration says 5x3"):
        ColourVideo(rgb=rgb, fps=30, calib=_colour_calib(width=5), t_s=[0.0, 1 / 30])
    with pytest.raises(InputError, match="t_s must have shape"):
        ColourVideo(rgb=rgb, fps=30, calib=_colour_calib(), t_s=[0.0])
    with pytest.raises(InputError, match="exposure_s must lie in"):  # longer than a frame period
        ColourVideo(rgb=rgb, fps=30, calib=_colour_calib(), t_s=[0.0, 1 / 30], exposure_s=0.04)


def test_stream_names_are_checked_and_ordered_with_the_depth_always_in():
    from fsv.types import STREAMS, check_streams

    assert STREAMS == ("depth", "colour")
    assert check_streams("colour") == ("depth", "colour")
    assert check_streams(["colour", "depth"]) == ("depth", "colour")
    assert check_streams("depth") == ("depth",)
    with pytest.raises(InputError, match="stream 'rgb': accepted: depth, colour"):
        check_streams("depth,rgb")


def _recording(T=4, nan_in=None):
    """``(recording, buffer, asked)``: a DepthRecording over a (T, 3, 5) buffer whose frames are
    written when ``wait(n)`` is called (frame k = 0.5 + k m, one NaN pixel in frame ``nan_in``),
    ``asked`` the n's asked for."""
    from fsv.types import DepthRecording

    buffer = np.zeros((T, 3, 5), np.float32)
    asked = []

    def wait(n):
        for k in range(max(asked, default=0), n):
            buffer[k] = 0.5 + k
            buffer[k, 2, 3] = np.nan if k == nan_in else buffer[k, 2, 3]
        asked.append(n)

    return DepthRecording(buffer, 30.0, wait), buffer, asked


def test_a_depth_recording_hands_each_frame_over_once_it_is_recorded_and_is_the_whole_video_when_read_whole():
    import pickle

    rec, buffer, asked = _recording()
    assert isinstance(rec, DepthVideo) and rec.num_frames == 4 and list(rec.t) == [0, 1 / 30, 2 / 30, 0.1]
    assert asked == []  # its length and times are known before any frame
    frames = rec.frames()
    first = next(frames)
    assert asked == [1] and np.all(first == 0.5) and np.all(buffer[1:] == 0)  # frame 0 only
    assert [float(f[0, 0]) for f in frames] == [1.5, 2.5, 3.5] and asked == [1, 2, 3, 4]
    assert not first.flags.writeable
    rec, buffer, asked = _recording()
    whole = rec.depth_m
    assert asked == [4] and whole.shape == (4, 3, 5) and not whole.flags.writeable
    again = pickle.loads(pickle.dumps(rec))
    assert type(again) is DepthVideo and np.array_equal(again.depth_m, whole) and again.fps == 30.0
    assert "4 frames of 5x3 at 30 Hz" in repr(rec)


def test_a_depth_recording_checks_each_frame_as_a_depth_video_does():
    from fsv.types import DepthRecording

    rec, _, _ = _recording(nan_in=1)
    frames = rec.frames()
    next(frames)
    with pytest.raises(InputError, match="must be finite and >= 0 .*: frame 1 is not"):
        next(frames)
    with pytest.raises(InputError, match="frame 1 is not"):
        _recording(nan_in=1)[0].depth_m
    with pytest.raises(InputError, match="float32 array"):
        DepthRecording(np.zeros((2, 3, 5)), 30.0, lambda n: None)
    with pytest.raises(InputError, match="fps"):
        DepthRecording(np.zeros((2, 3, 5), np.float32), 0.0, lambda n: None)
