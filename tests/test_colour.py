"""The colour renderer: same geometry as the depth, the shading equation, normals, motion blur,
registration onto the depth, and pinned bits."""

import dataclasses
import os

os.environ.setdefault("MUJOCO_GL", "egl")

import mujoco  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
from test_render import BOX_HALF, scene_labels, scene_xml, set_box  # noqa: E402

from benchmark.camera import colour_kernels as ck  # noqa: E402
from benchmark.camera.appearance import Lighting, appearance_of, kelvin_to_rgb  # noqa: E402
from benchmark.camera.camera import look_at  # noqa: E402
from benchmark.camera.colour import (  # noqa: E402
    ColourRenderer,
    interpolated_state,
    register_to_depth,
    render_colour,
    render_colour_video,
)
from benchmark.camera.colour_sensor import colour_camera, colour_preset, encode  # noqa: E402
from benchmark.camera.depth import DepthRenderer, hand_skin, pulp_presses  # noqa: E402
from benchmark.camera.scene import LABEL_BOX, LABEL_TABLE, world_labels  # noqa: E402
from benchmark.camera.views import camera_of  # noqa: E402
from benchmark.errors import BenchmarkError  # noqa: E402
from benchmark.world.assets import build_world, set_frame  # noqa: E402
from benchmark.world.scenario import Scenario  # noqa: E402
from benchmark.world.simulate import simulate  # noqa: E402

LIFT = Scenario(task="lift", duration_s=1.0)


@pytest.fixture(scope="module")
def lift():
    ep = simulate(LIFT)
    return ep, build_world(LIFT)


def _unit(v):
    v = np.asarray(v, dtype=float)
    return v / np.linalg.norm(v)


def _appearance(**kw):
    """A drawn appearance with two known lights."""
    a = appearance_of(Scenario(seed=4))
    warm, cold = kelvin_to_rgb(3200.0), kelvin_to_rgb(6000.0)
    light = Lighting(ambient=0.2 * warm, direction=np.array([_unit([0.3, -0.2, -1.0]), _unit([-1.0, 0.4, -0.5])]),
                     rgb=np.array([0.6 * warm, 0.25 * cold]), kelvin=np.array([3200.0, 6000.0]))
    return dataclasses.replace(a, lighting=light, **kw)


def _scene(appearance):
    """tests/test_render.py's scene and camera pose (320 x 240, the depth camera's intrinsics)."""
    model = mujoco.MjModel.from_xml_string(scene_xml())
    data = mujoco.MjData(model)
    camera = dataclasses.replace(camera_of(0), T_world_cam=look_at([0.2, -0.48, 0.36], [0.0, 0.0, 0.08]))
    return model, data, camera, ColourRenderer(model, camera, scene_labels(model), appearance)


def _ray_world(camera, u, v):
    K, T = camera.K, camera.T_world_cam
    d = np.array([(u - K[0, 2]) / K[0, 0], (v - K[1, 2]) / K[1, 1], 1.0])
    return T[:3, 3], T[:3, :3] @ d


def test_labels_and_depth_are_the_depth_renderers_from_the_same_camera(lift):
    ep, world = lift
    labels = world_labels(world)
    camera = camera_of(0)
    centre, push = pulp_presses(ep.truth)
    data = mujoco.MjData(world.model)
    for skin in (None, hand_skin(world)):
        depth_r = DepthRenderer(world.model, camera, labels, skin=skin)
        colour_r = ColourRenderer(world.model, camera, labels, appearance_of(LIFT), skin=skin)
        for k in (0, 15, 30):
            t = ep.truth
            set_frame(world, data, t.box_pos[k], t.box_quat[k], t.hand_qpos[k])
            args = (data.xpos, data.xmat) + ((centre[k], push[k]) if skin else ())
            depth, lab = depth_r.render(*args)
            radiance, depth_c, lab_c = colour_r.render(*args)
            np.testing.assert_array_equal(depth_c, depth)
            np.testing.assert_array_equal(lab_c, lab)
            assert radiance.shape == depth.shape + (3,) and radiance.dtype == np.float32
            assert {LABEL_TABLE, LABEL_BOX, 9}.issubset(set(np.unique(lab).tolist()))


def test_a_lit_face_has_the_shading_equations_radiance_at_each_pixel():
    """Top-face and table pixels: albedo (the box's print looked up in the box's frame, the table's
    grain in world xy, by the reference kernels) times ambient + sum of light * cos, by hand."""
    app = _appearance()
    model, data, camera, r = _scene(app)
    set_box(model, data, [0.0, 0.0, 0.03], [1, 0, 0, 0])
    radiance, depth, labels = r.render(data.xpos, data.xmat)
    light = app.lighting
    n = np.array([0.0, 0.0, 1.0])
    E = light.ambient + sum(rgb * max(0.0, -(n @ d)) for rgb, d in zip(light.rgb, light.direction))
    rng = np.random.default_rng(0)
    checked = {LABEL_BOX: 0, LABEL_TABLE: 0}
    inked = 0
    pixels = np.concatenate([rng.permutation(np.argwhere(labels == lab))[:150] for lab in (LABEL_BOX, LABEL_TABLE)])
    for v, u in pixels:
        c, d = _ray_world(camera, u, v)
        if labels[v, u] == LABEL_BOX:
            p = c + (2 * BOX_HALF[2] - c[2]) / d[2] * d
            q = p - [0.0, 0.0, 0.03]
            if np.any(np.abs(q[:2]) > BOX_HALF[:2] - 1e-4):
                continue  # a side face or the edge
            ink = ck.box_ink(4, q[0], q[1], BOX_HALF[0], BOX_HALF[1], app.box_par)
            inked += ink
            albedo = app.box_ink[4] if ink else app.box_base[4]
        elif labels[v, u] == LABEL_TABLE and depth[v, u] < 1.0:
            p = c + (0.0 - c[2]) / d[2] * d
            tp = app.table_par
            along, across = p[0] * tp[0] + p[1] * tp[1], p[1] * tp[0] - p[0] * tp[1]
            g = 0.65 * ck.value_noise(along / tp[2], across / tp[3], int(tp[4])) + 0.35 * ck.value_noise(
                2 * along / tp[2], 2 * across / tp[3], int(tp[4]) + 1)
            albedo = app.table_base + g * (app.table_grain - app.table_base)
        else:
            continue
        checked[labels[v, u]] += 1
        np.testing.assert_allclose(radiance[v, u], albedo * E, rtol=2e-6)
    assert checked[LABEL_BOX] > 50 and checked[LABEL_TABLE] > 100 and 0 < inked < checked[LABEL_BOX]
    # nothing hit: the far wall's radiance
    far = labels == 0
    assert far.any()
    np.testing.assert_array_equal(radiance[far], np.tile(app.background.astype(np.float32), (far.sum(), 1)))
    # the plain appearance: one albedo per label
    plain = ColourRenderer(model, camera, scene_labels(model), app.plain()).render(data.xpos, data.xmat)[0]
    top = (labels == LABEL_BOX) & (np.abs(plain[..., 0] - np.float32(app.box_base[0, 0] * E[0])) < 1e-6)
    assert top.sum() > 0.4 * (labels == LABEL_BOX).sum()


def test_box_face_normals_are_the_box_faces_rotated_into_the_camera():
    model, data, camera, r = _scene(_appearance())
    quat = _unit([0.9, 0.2, -0.1, 0.35])
    set_box(model, data, [0.02, -0.01, 0.08], quat)
    _, depth, labels = r.render(data.xpos, data.xmat)
    normals = r.normals()
    R_box = data.xmat[1].reshape(3, 3)
    R_cw = camera.T_world_cam[:3, :3].T
    faces = np.concatenate([(R_cw @ R_box).T, -(R_cw @ R_box).T])  # (6, 3): +-x, +-y, +-z of the box
    box = normals[labels == LABEL_BOX]
    match = box @ faces.T
    assert np.all(match.max(axis=1) > 1 - 1e-12)
    assert len(np.unique(match.argmax(axis=1))) >= 2  # two faces or more seen
    # the hand's capsules: unit normals facing the camera
    v, u = np.nonzero(labels >= 10)
    K = camera.K
    p = depth[v, u, None] * np.stack([(u - K[0, 2]) / K[0, 0], (v - K[1, 2]) / K[1, 1], np.ones(len(u))], 1)
    n = normals[v, u]
    np.testing.assert_allclose(np.linalg.norm(n, axis=1), 1.0, atol=1e-12)
    assert len(u) > 100 and np.all(np.sum(n * p, axis=1) < 0)


def test_ideal_sensor_is_noise_and_blur_free(lift):
    ep, world = lift
    seen = {}
    frames = render_colour(ep, sensor=colour_preset("ideal"), observe=lambda k, d, lab: seen.setdefault(k, d.copy()))
    assert np.all(frames.samples == 1) and frames.exposure_s == 0.0
    video = frames.video  # what fsv receives
    assert video.rgb.shape == (len(ep.truth.t), 480, 640, 3) and video.calib == frames.calib
    np.testing.assert_allclose(video.t_s, ep.truth.t, atol=1e-12)
    camera = colour_camera(camera_of(0), colour_preset("ideal"))
    r = ColourRenderer(world.model, camera, world_labels(world), appearance_of(LIFT), skin=hand_skin(world))
    centre, push = pulp_presses(ep.truth)
    data = mujoco.MjData(world.model)
    for k in (0, 20, 30):
        t = ep.truth
        set_frame(world, data, t.box_pos[k], t.box_quat[k], t.hand_qpos[k])
        radiance, depth, labels = r.render(data.xpos, data.xmat, centre[k], push[k])
        np.testing.assert_array_equal(frames.rgb[k], encode(radiance))
        np.testing.assert_array_equal(seen[k], depth)
        np.testing.assert_array_equal(frames.labels[k], labels)


def test_a_moving_box_edge_spreads_over_its_motion_during_the_exposure():
    """A box top seen from straight above at 0.5 m, moving 0.6 m/s along the image's rows: its
    edges ramp over v e f / z pixels (10.4 px at 1/60 s), and over at most one pixel without exposure."""
    app = _appearance().plain()
    model = mujoco.MjModel.from_xml_string(scene_xml())
    base = colour_camera(camera_of(0), colour_preset("ds325"))
    top = 2 * BOX_HALF[2]
    camera = dataclasses.replace(base, T_world_cam=look_at([0.0, 0.0, top + 0.5], [0.0, 0.0, 0.0], up=(0, 1, 0)))
    speed, fps = 0.6, 30.0
    labels = scene_labels(model)

    def set_state(data, k, s):
        data.qpos[0:7] = [speed * (k / fps + s) - 0.02, 0.0, 0.03, 1, 0, 0, 0]
        data.qpos[7:10] = [0.0, 2.0, 0.3]  # the hand out of view
        mujoco.mj_kinematics(model, data)

    expected = speed * (1 / 60) * camera.K[0, 0] / 0.5
    for exposure, width in ((1 / 60, expected), (0.0, 0.0)):
        sensor = dataclasses.replace(colour_preset("ds325"), exposure_s=exposure, blur_step_px=0.25, max_samples=61)
        r = ColourRenderer(model, camera, labels, app)
        radiance, _, lab, S = r.render_exposure(set_state, mujoco.MjData(model), 1, sensor)
        row = radiance[camera.height // 2, :, 1].astype(np.float64)
        box_value, table_value = row[camera.width // 2], row[5]
        between = np.abs(row - table_value) > 0.02 * abs(box_value - table_value)
        between &= np.abs(row - box_value) > 0.02 * abs(box_value - table_value)
        cols = np.flatnonzero(between)
        left, right = cols[cols < camera.width // 2], cols[cols > camera.width // 2]
        for edge in (left, right):
            assert abs(len(edge) - width) <= 1.5, (len(edge), width, S)
            if len(edge):
                assert np.ptp(edge) == len(edge) - 1  # one contiguous ramp
        assert S == (1 if exposure == 0 else 43)  # 10.4 px / 0.25 px, made odd
    assert expected == pytest.approx(10.4, abs=0.1)


def test_register_to_depth_puts_the_box_colour_on_the_depth_box_pixels(lift):
    ep, world = lift
    depth_cam = camera_of(0)
    frames = render_colour(ep, camera=depth_cam)
    data = mujoco.MjData(world.model)
    r = DepthRenderer(world.model, depth_cam, world_labels(world), skin=hand_skin(world))
    centre, push = pulp_presses(ep.truth)
    for k in (0, 30):
        t = ep.truth
        set_frame(world, data, t.box_pos[k], t.box_quat[k], t.hand_qpos[k])
        depth, labels = r.render(data.xpos, data.xmat, centre[k], push[k])
        # the colour camera's label image, registered like colour: agreement on the depth's box
        # pixels away from edges (every pixel within 2 px is box)
        lab3 = np.repeat(frames.labels[k][..., None], 3, axis=2)
        reg = register_to_depth(lab3, frames.calib, depth, depth_cam.calibration())[..., 0]
        box = labels == LABEL_BOX
        inner = box.copy()
        for dv in range(-2, 3):
            for du in range(-2, 3):
                inner[2:-2, 2:-2] &= box[2 + dv : box.shape[0] - 2 + dv, 2 + du : box.shape[1] - 2 + du]
        inner[:2] = inner[-2:] = False
        inner[:, :2] = inner[:, -2:] = False
        assert inner.sum() > 500
        assert np.mean(reg[inner] == LABEL_BOX) > 0.95
        rgb = register_to_depth(frames.rgb[k], frames.calib, depth, depth_cam.calibration())
        assert np.all(rgb[depth == 0] == 0) and np.all(rgb[inner].max(axis=1) > 0)


def test_interpolated_state_is_exact_at_frames_lerps_between_and_clamps(lift):
    ep, _ = lift
    t, fps = ep.truth, LIFT.fps
    pos, quat, hand = interpolated_state(t, 5, 0.0, fps)
    assert np.array_equal(pos, t.box_pos[5]) and np.array_equal(quat, t.box_quat[5]) and np.array_equal(hand, t.hand_qpos[5])
    pos, quat, hand = interpolated_state(t, 5, 0.25 / fps, fps)
    np.testing.assert_allclose(pos, 0.75 * t.box_pos[5] + 0.25 * t.box_pos[6], atol=1e-15)
    np.testing.assert_allclose(hand[7:], 0.75 * t.hand_qpos[5, 7:] + 0.25 * t.hand_qpos[6, 7:], atol=1e-15)
    assert np.linalg.norm(quat) == pytest.approx(1.0, abs=1e-15) and np.linalg.norm(hand[3:7]) == pytest.approx(1.0)
    T = len(t.t)
    assert np.array_equal(interpolated_state(t, T - 1, 0.01, fps)[0], t.box_pos[-1])
    assert np.array_equal(interpolated_state(t, 0, -0.01, fps)[0], t.box_pos[0])
    with pytest.raises(BenchmarkError, match="frame k"):
        interpolated_state(t, T, 0.0, fps)


def test_the_video_checks_its_arguments():
    model = mujoco.MjModel.from_xml_string(scene_xml())
    camera = colour_camera(camera_of(0), colour_preset("ds325"))
    labels = scene_labels(model)
    with pytest.raises(BenchmarkError, match="differs from the sensor"):
        render_colour_video(model, None, 1, camera=dataclasses.replace(camera, width=320, height=240), labels=labels,
                            appearance=_appearance(), sensor=colour_preset("ds325"), fps=30.0, rng=None)
    two_boxes = labels.copy()
    two_boxes[0] = LABEL_BOX
    with pytest.raises(BenchmarkError, match="one box"):
        ColourRenderer(model, camera, two_boxes, _appearance())


_DIGEST = """
import hashlib
import numpy as np
from benchmark.camera.colour import render_colour
from benchmark.world.scenario import Scenario
from benchmark.world.simulate import simulate
depth = []
frames = render_colour(simulate(Scenario(task="lift", duration_s=1.0)), observe=lambda k, d, l: depth.append(d.copy()))
h = hashlib.sha256()
for a in (frames.rgb, frames.labels, np.stack(depth), frames.samples):
    h.update(a.tobytes())
print(h.hexdigest())
"""

PINNED_COLOUR_SHA256 = "68079aa7237a0682bd4e4a002185e4bfa6dfa3a92a488f86418a6a0577720f24"
"""The colour video (rgb, labels, depth, sub-renders) of ``Scenario(task="lift", duration_s=1.0)``
with the ds325 colour preset: blur, noise and white balance included."""


@pytest.mark.parametrize("kernel", ["Haswell", "Sandybridge", "SkylakeX"])
def test_the_colour_video_is_the_pinned_bits_under_every_openblas_kernel(kernel, kernel_python):
    assert kernel_python(_DIGEST, env={"OPENBLAS_CORETYPE": kernel}).strip() == PINNED_COLOUR_SHA256
