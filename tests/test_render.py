"""Depth rendering: camera conventions, exact depth of the box, labels, errors."""

import dataclasses
import importlib
import os

os.environ.setdefault("MUJOCO_GL", "egl")

import mujoco  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

# The module: the attribute `benchmark.camera.render` is the function render() of the public API.
R = importlib.import_module("benchmark.camera.render")
C = importlib.import_module("benchmark.camera.camera")
S = importlib.import_module("benchmark.camera.scene")
G = importlib.import_module("benchmark.camera.depth")

FINGERS = ("thumb", "index")
BOX_HALF = np.array([0.0855, 0.0555, 0.03])


def scene_xml():
    fingers = ""
    for k, name in enumerate(FINGERS):
        fingers += f"""
        <body name="{name}_1" pos="{-0.03 + 0.06 * k} 0.06 0"><joint type="hinge" axis="1 0 0"/>
          <geom type="capsule" fromto="0 0 0 0 0 -0.04" size="0.009"/>
          <body name="{name}_2" pos="0 0 -0.04"><joint type="hinge" axis="1 0 0"/>
            <geom type="capsule" fromto="0 0 0 0 0 -0.03" size="0.008"/>
            <geom type="sphere" pos="0 0 -0.03" size="0.0085"/>
          </body>
        </body>"""
    return f"""<mujoco><worldbody>
      <geom name="table" type="plane" size="0 0 1"/>
      <body name="box" pos="0 0 0.03"><freejoint/><geom type="box" size="{BOX_HALF[0]} {BOX_HALF[1]} {BOX_HALF[2]}"/></body>
      <body name="palm" pos="0 0.1 0.25"><freejoint/>
        <geom type="box" size="0.045 0.03 0.01" pos="0 0.04 0"/>
        {fingers}
      </body>
      <body name="marker" mocap="true" pos="0 0 0.2"><geom type="sphere" size="0.03" contype="0" conaffinity="0"/></body>
      <body name="probe" mocap="true" pos="0 0 -1"><geom type="sphere" size="0.005"/></body>
    </worldbody></mujoco>"""


def scene_labels(model):
    """Labels of the test scene's geoms: table 1, box 2, finger k 10 + k, palm and probe 9, marker 0."""
    labels = np.zeros(model.ngeom, dtype=np.uint8)
    for g in range(model.ngeom):
        name = model.body(model.geom_bodyid[g]).name
        fingers = [k for k, f in enumerate(FINGERS) if name.startswith(f)]
        labels[g] = (
            S.LABEL_TABLE if name == "world" else S.LABEL_BOX if name == "box" else 0 if name == "marker"
            else S.LABEL_FINGER0 + fingers[0] if fingers else S.LABEL_PALM
        )
    return labels


@pytest.fixture(scope="module")
def world():
    model = mujoco.MjModel.from_xml_string(scene_xml())
    data = mujoco.MjData(model)
    # the DS325 intrinsics, posed in front of the test scene (the hand stays clear of the box)
    camera = dataclasses.replace(C.load_camera(), T_world_cam=C.look_at([0.2, -0.48, 0.36], [0.0, 0.0, 0.08]))
    return model, data, camera, G.DepthRenderer(model, camera, scene_labels(model))


def set_box(model, data, pos, quat):
    data.qpos[0:3] = pos
    data.qpos[3:7] = np.asarray(quat) / np.linalg.norm(quat)
    mujoco.mj_kinematics(model, data)


def rays_world(camera):
    """Unit-depth rays (z_cam = 1) through every pixel centre, in the world frame, (H, W, 3)."""
    v, u = np.mgrid[0 : camera.height, 0 : camera.width]
    K = camera.K
    d_cam = np.stack([(u - K[0, 2]) / K[0, 0], (v - K[1, 2]) / K[1, 1], np.ones(u.shape)], axis=-1)
    return d_cam @ camera.T_world_cam[:3, :3].T


def test_camera_from_yaml_has_the_ds325_field_of_view_and_looks_at_the_target():
    cam = C.load_camera()
    assert (cam.width, cam.height) == (320, 240)
    assert np.rad2deg(2 * np.arctan(cam.width / 2 / cam.K[0, 0])) == pytest.approx(74.0)
    assert np.rad2deg(2 * np.arctan(cam.height / 2 / cam.K[1, 1])) == pytest.approx(58.0)
    # the look-at point projects to the principal point, in front of the camera
    target = np.array([0.0, 0.0, 0.09])  # look_at of sim_assets/camera.yaml
    p = np.linalg.inv(cam.T_world_cam) @ np.append(target, 1.0)
    assert p[2] > 0.4
    np.testing.assert_allclose(cam.K @ p[:3] / p[2], [cam.K[0, 2], cam.K[1, 2], 1.0], atol=1e-9)
    # image "up" is world up: the camera's y axis (down in the image) points down in the world
    assert cam.T_world_cam[2, 1] < 0
    calib = C.camera_calibration()
    np.testing.assert_array_equal(calib.K, cam.K)
    np.testing.assert_array_equal(calib.T_world_cam, cam.T_world_cam)


def test_gl_from_cv_flips_y_and_z():
    np.testing.assert_array_equal(C.GL_FROM_CV @ [0.1, 0.2, 0.5, 1.0], [0.1, -0.2, -0.5, 1.0])
    np.testing.assert_array_equal(C.GL_FROM_CV @ C.GL_FROM_CV, np.eye(4))


def test_clip_from_cam_puts_the_opencv_pixel_at_the_gl_pixel_centre_with_rows_top_first():
    cam = C.load_camera()
    P = C.clip_from_cam(cam)
    rng = np.random.default_rng(0)
    X = np.column_stack([rng.uniform(-0.3, 0.3, 50), rng.uniform(-0.2, 0.2, 50), rng.uniform(0.2, 2.0, 50)])
    clip = np.column_stack([X, np.ones(50)]) @ P.T
    ndc = clip[:, :3] / clip[:, 3:]
    window = np.column_stack([(ndc[:, 0] + 1) * cam.width / 2, (ndc[:, 1] + 1) * cam.height / 2])
    uv = X @ cam.K.T
    np.testing.assert_allclose(clip[:, 3], X[:, 2])  # w = depth along the optical axis
    np.testing.assert_allclose(window, uv[:, :2] / uv[:, 2:] + 0.5, atol=1e-9)  # row v is framebuffer row v
    # the clipping planes map to normalised depth -1 and 1, increasing with depth
    for z, expected in ((cam.znear, -1.0), (cam.zfar, 1.0)):
        c = P @ [0.0, 0.0, z, 1.0]
        assert c[2] / c[3] == pytest.approx(expected)


@pytest.mark.parametrize("u, v", [(40, 200), (250, 30), (159, 119)])
def test_a_point_appears_where_the_opencv_calibration_projects_it(world, u, v):
    """A small sphere centred on the ray of pixel (u, v) covers exactly the pixels whose
    OpenCV rays (through the calibration) meet it, at the ray-sphere depth."""
    model, data, camera, renderer = world
    set_box(model, data, [0, 0, -1], [1, 0, 0, 0])  # out of the way, under the table
    probe = model.body("probe").mocapid[0]
    z, radius = 0.4, 0.005
    origin, rays = camera.T_world_cam[:3, 3], rays_world(camera)
    centre = origin + z * rays[v, u]
    data.mocap_pos[probe] = centre
    mujoco.mj_kinematics(model, data)
    depth, labels = renderer.render(data.xpos, data.xmat)
    data.mocap_pos[probe] = [0, 0, -1]
    seen = labels == S.LABEL_PALM  # the probe is a collidable geom of a non-box body
    seen &= depth < 0.45
    oc = origin - centre
    p, dd = rays @ oc, np.sum(rays * rays, axis=-1)
    h = p * p - dd * (oc @ oc - radius**2)
    hit = h > 0
    assert 20 < hit.sum() < 200
    np.testing.assert_array_equal(seen, hit)
    t = (-p - np.sqrt(np.maximum(h, 0))) / dd  # depth: the rays have z_cam = 1
    assert np.abs(depth[hit] - t[hit]).max() < 1e-6
    ray_len = np.linalg.norm(np.linalg.inv(camera.K) @ [u, v, 1.0])  # per unit of depth
    assert depth[v, u] == pytest.approx(z - radius / ray_len, abs=1e-6)  # front of the sphere


def test_capsule_depth_is_the_exact_ray_capsule_distance(world):
    """Capsules are ray-cast, not tessellated: every finger pixel's depth is the distance along
    its ray to the nearest true capsule or sphere of the hand (sampled here as spheres along
    each axis, 50 um apart: within 0.05 um of the capsule)."""
    model, data, camera, renderer = world
    set_box(model, data, [0, 0, -1], [1, 0, 0, 0])
    depth, labels = renderer.render(data.xpos, data.xmat)
    origin, rays = camera.T_world_cam[:3, 3], rays_world(camera)
    fingers = labels >= S.LABEL_FINGER0
    assert fingers.sum() > 150
    d = rays[fingers]
    dd = np.sum(d * d, axis=-1)
    best = np.full(len(d), np.inf)
    for g in range(model.ngeom):
        if S.LABEL_FINGER0 <= scene_labels(model)[g]:
            half = model.geom_size[g, 1] if model.geom_type[g] == mujoco.mjtGeom.mjGEOM_CAPSULE else 0.0
            axis = data.geom_xmat[g].reshape(3, 3)[:, 2]
            r = model.geom_size[g, 0]
            for s in np.linspace(-half, half, int(2 * half / 5e-5) + 1):
                oc = origin - (data.geom_xpos[g] + s * axis)
                p = d @ oc
                h = p * p - dd * (oc @ oc - r * r)
                best = np.where(h >= 0, np.minimum(best, (-p - np.sqrt(np.maximum(h, 0))) / dd), best)
    err = np.abs(depth[fingers] - best)
    assert np.median(err) < 1e-6 and np.percentile(err, 99) < 2e-5, (np.median(err), np.percentile(err, 99))


BOX_POSES = [
    ([0.0, 0.0, 0.03], [1.0, 0.0, 0.0, 0.0]),
    ([0.03, -0.02, 0.12], [np.cos(0.3), 0.1, -0.15, np.sin(0.3)]),  # lifted, tilted and turned
]


@pytest.mark.parametrize("pos, quat", BOX_POSES)
def test_top_face_depth_equals_ray_plane_distance(world, pos, quat):
    model, data, camera, renderer = world
    set_box(model, data, pos, quat)
    depth, labels = renderer.render(data.xpos, data.xmat)
    c, Rb = data.xpos[model.body("box").id], data.xmat[model.body("box").id].reshape(3, 3)
    n = Rb[:, 2]
    o = camera.T_world_cam[:3, 3]
    d = rays_world(camera)
    t = ((c + BOX_HALF[2] * n - o) @ n) / (d @ n)  # depth along the optical axis: d has z_cam = 1
    local = (o + t[..., None] * d - c) @ Rb
    margin = 0.002  # keep away from the face's edges, where a pixel may see a side face
    on_top = (np.abs(local[..., 0]) < BOX_HALF[0] - margin) & (np.abs(local[..., 1]) < BOX_HALF[1] - margin)
    on_top &= (t > 0) & ((o - c) @ n > BOX_HALF[2])  # the top face faces the camera
    assert on_top.sum() > 800
    assert np.all(labels[on_top] == S.LABEL_BOX)
    err = np.abs(depth[on_top] - t[on_top])
    assert err.max() < 1e-3, err.max()
    assert np.median(err) < 1e-4


@pytest.mark.parametrize("pos, quat", BOX_POSES)
def test_backprojected_box_pixels_lie_on_the_box_surface(world, pos, quat):
    model, data, camera, renderer = world
    set_box(model, data, pos, quat)
    depth, labels = renderer.render(data.xpos, data.xmat)
    calib = camera.calibration()
    pts_cam = calib.backproject(depth)[labels == S.LABEL_BOX]
    pts = pts_cam @ calib.T_world_cam[:3, :3].T + calib.T_world_cam[:3, 3]
    c, Rb = data.xpos[model.body("box").id], data.xmat[model.body("box").id].reshape(3, 3)
    local = np.abs((pts - c) @ Rb)
    outside = np.linalg.norm(np.maximum(local - BOX_HALF, 0), axis=1)
    inside = np.min(BOX_HALF - local, axis=1).clip(min=0)
    dist = outside + inside  # distance to the box's surface
    assert len(dist) > 1000
    assert dist.mean() < 1e-3, dist.mean()
    assert np.percentile(dist, 99) < 3e-3


def test_world_labels_mark_table_box_palm_and_each_finger():
    from benchmark.world.assets import build_world
    from benchmark.world.scenario import Scenario

    w = build_world(Scenario())
    labels = S.world_labels(w)
    assert labels[w.table_geom] == S.LABEL_TABLE and labels[w.box_geom] == S.LABEL_BOX
    palm = w.model.body_geomadr[w.palm_body]
    assert labels[palm] == S.LABEL_PALM
    for k, finger in enumerate(w.hand.finger_names):
        tip = w.model.site_bodyid[w.tip_site[k]]
        tip_geoms = np.flatnonzero(w.model.geom_bodyid == tip)
        assert len(tip_geoms) > 0 and np.all(labels[tip_geoms] == S.LABEL_FINGER0 + k), finger
    assert sorted(np.unique(labels)) == [1, 2, 9, 10, 11, 12, 13, 14]


def test_each_label_is_drawn_and_undrawn_geoms_are_invisible(world):
    model, data, camera, renderer = world
    set_box(model, data, [0, 0, 0.03], [1, 0, 0, 0])
    depth, image = renderer.render(data.xpos, data.xmat)
    assert set(np.unique(image)) == {0, 1, 2, 9, 10, 11}
    assert np.all((depth > 0) == (image > 0))
    # the marker sphere (not collidable) hangs over the box in view but is not drawn
    u, v, w = camera.K @ (np.linalg.inv(camera.T_world_cam) @ [0, 0, 0.2, 1])[:3]
    assert 0 <= u / w < camera.width and 0 <= v / w < camera.height
    data.mocap_pos[model.body("marker").mocapid[0]] = [5, 5, 5]
    mujoco.mj_kinematics(model, data)
    np.testing.assert_array_equal(renderer.render(data.xpos, data.xmat)[0], depth)
    data.mocap_pos[model.body("marker").mocapid[0]] = [0, 0, 0.2]


def test_depth_agrees_with_mujocos_own_renderer_from_the_same_camera(world):
    """An independent peer: MuJoCo's renderer, given the calibration as a MuJoCo camera."""
    from benchmark.perf.render import add_mujoco_camera

    _, _, camera, _ = world
    spec = mujoco.MjSpec.from_string(scene_xml())
    add_mujoco_camera(spec, camera, "ds325")
    model = spec.compile()
    data = mujoco.MjData(model)
    data.qpos[0:7] = [0.03, -0.02, 0.12, np.cos(0.3), 0.1, -0.15, np.sin(0.3)]
    data.qpos[3:7] /= np.linalg.norm(data.qpos[3:7])
    mujoco.mj_kinematics(model, data)
    mujoco.mj_camlight(model, data)  # MuJoCo's camera pose
    ours, labels = G.DepthRenderer(model, camera, scene_labels(model)).render(data.xpos, data.xmat)
    with mujoco.Renderer(model, camera.height, camera.width) as peer:
        peer.enable_depth_rendering()
        peer.update_scene(data, camera="ds325")
        theirs = peer.render()
    both = (ours > 0) & (ours < 1.5) & (labels != S.LABEL_NONE)
    diff = np.abs(ours - theirs)[both]
    assert both.sum() > 30000
    assert np.median(diff) < 1e-5
    assert np.mean(diff < 1e-4) > 0.98  # the rest: silhouette pixels, where MuJoCo resolves 4 samples


def test_rendering_is_deterministic(world):
    model, data, camera, renderer = world
    set_box(model, data, *BOX_POSES[1])
    a = renderer.render(data.xpos, data.xmat)
    b = renderer.render(data.xpos, data.xmat)
    np.testing.assert_array_equal(a[0], b[0])
    np.testing.assert_array_equal(a[1], b[1])


def test_labels_must_match_the_model(world):
    model, _, camera, _ = world
    with pytest.raises(Exception, match=f"shape \\({model.ngeom},\\)"):
        G.DepthRenderer(model, camera, np.ones(3, dtype=np.uint8))


# --- render(episode): the whole stage on the benchmark's world ---------------------------------


def synthetic_episode(noise_m=0.01, seed=0, duration_s=1.0):
    """An episode of the real world whose truth is an analytic box lift with a still hand above it."""

    from conftest import make_analytic_truth

    from benchmark.world.assets import build_world
    from benchmark.world.episode import Episode
    from benchmark.world.scenario import Scenario

    # the analytic truth has four contact slots, not the hand's five digits: the hand drawn as its
    # primitives (no pulp to press)
    sc = Scenario(noise_m=noise_m, seed=seed, duration_s=duration_s, hand_surface="capsules")
    w = build_world(sc)
    truth = make_analytic_truth(duration_s=duration_s, fps=sc.fps)
    hand = np.zeros(7 + len(w.hand.joint_names))
    hand[:7] = [0.0, -0.12, 0.16, 1.0, 0.0, 0.0, 0.0]
    truth = dataclasses.replace(truth, hand_qpos=np.tile(hand, (len(truth.t), 1)))
    return Episode(scenario=sc, truth=truth, object_model=w.obj, hand_model=w.hand)


@pytest.fixture(scope="module")
def rendered():
    return {(noise, seed): R.render(synthetic_episode(noise, seed)) for noise, seed in ((0.01, 0), (0.01, 1), (0.0, 0))}


def test_render_gives_one_frame_per_truth_frame_with_calibration_and_labels(rendered):
    ep = rendered[(0.01, 0)]
    assert ep.depth.depth_m.shape == (30, 240, 320) == ep.labels.shape  # 1 s at 30 fps
    assert ep.depth.depth_m.dtype == np.float32 and ep.labels.dtype == np.uint8
    assert ep.depth.fps == 30.0
    np.testing.assert_allclose(ep.depth.t, ep.truth.t)
    np.testing.assert_array_equal(ep.calib.K, C.camera_calibration().K)
    seen = set(np.unique(ep.labels).tolist())
    assert {1, 2, 9}.issubset(seen) and len(seen & {10, 11, 12, 13, 14}) >= 3
    valid = ep.depth.depth_m > 0
    assert 0.5 < valid.mean() < 0.98
    clean = rendered[(0.0, 0)].depth.depth_m  # the range limits apply to the true depth (0.15-1 m);
    # the DS325's own noise (14 mm at 1 m, more at grazing angles) spreads the measured depth around it
    assert clean[clean > 0].min() >= 0.15 - 0.05 and np.percentile(clean[clean > 0], 99) <= 1.0 + 0.03
    assert clean.max() > 0.95


def test_render_same_seed_same_bits_other_seed_other_noise(rendered):
    again = R.render(synthetic_episode(0.01, 0))
    np.testing.assert_array_equal(again.depth.depth_m, rendered[(0.01, 0)].depth.depth_m)
    other = rendered[(0.01, 1)]
    assert not np.array_equal(other.depth.depth_m, again.depth.depth_m)
    np.testing.assert_array_equal(other.labels, again.labels)  # labels are exact, noise-free


def test_render_noise_has_the_scenario_std_on_valid_pixels():
    """The scenario's white noise on top of the sensor's masks (the preset's own noise, jitter,
    multipath and flying pixels off: tests/test_sensor_presets.py checks those)."""
    from dataclasses import replace

    from benchmark.camera.sensor import sensor_preset

    def white(noise):
        return replace(sensor_preset("ds325", noise), axial="none", lateral="none", multipath_m=0.0, flying_frac=0.0)

    noisy = R.render(synthetic_episode(0.01, 0), sensor=white(0.01)).depth.depth_m
    clean = R.render(synthetic_episode(0.0, 0), sensor=white(0.0)).depth.depth_m
    both = (noisy > 0) & (clean > 0)
    assert both.sum() > 1e6
    assert np.std(noisy[both] - clean[both]) == pytest.approx(0.01, rel=0.05)
    assert np.array_equal(noisy > 0, clean > 0)  # which pixels are missing does not depend on the noise


def test_render_rejects_a_sensor_with_another_noise():
    from benchmark.camera.sensor import SensorModel
    from benchmark.errors import BenchmarkError

    with pytest.raises(BenchmarkError, match="scenario's noise_m = 0.01"):
        R.render(synthetic_episode(0.01, 0), sensor=SensorModel(noise_m=0.02))


def test_a_simulated_lift_renders_one_frame_per_truth_frame_and_shows_box_and_fingers(rendered_lift_episode):
    ep = rendered_lift_episode
    sc = ep.scenario
    T = int(round(sc.duration_s * sc.fps)) + 1  # frames at t = k / fps from 0 to the duration
    assert ep.depth.num_frames == len(ep.truth.t) == T == ep.labels.shape[0]
    np.testing.assert_allclose(ep.depth.t, ep.truth.t, atol=1e-9)
    box_px = (ep.labels == S.LABEL_BOX).sum(axis=(1, 2))
    assert box_px.min() > 1500  # the box is in view all along the lift
    fingers = {int(v) for v in np.unique(ep.labels[-1]) if v >= S.LABEL_FINGER0}
    assert len(fingers) >= 4  # the camera faces the fingers on the box's far face
    # the box's depth pixels back-project near the box's true pose (noise 1 cm, so a loose bound)
    k = T - 1
    pts = ep.calib.backproject(ep.depth.depth_m[k])[(ep.labels[k] == S.LABEL_BOX) & (ep.depth.depth_m[k] > 0)]
    world_pts = pts @ ep.calib.T_world_cam[:3, :3].T + ep.calib.T_world_cam[:3, 3]
    local = np.abs((world_pts - ep.truth.box_pos[k]) @ ep.truth.box_rot[k])
    half = ep.object_model.half_extents
    assert np.median(np.max(local / half, axis=1)) == pytest.approx(1.0, abs=0.1)  # on the surface


_WORLD_DIGEST = """
import dataclasses, hashlib, numpy as np
from benchmark.camera.render import render
from benchmark.world.scenario import Scenario
from benchmark.world.simulate import simulate
ep = render(simulate(Scenario(task="lift", seed=0, duration_s=3.0, hand_surface="capsules")))
h = hashlib.sha256()
for f in dataclasses.fields(ep.truth):
    v = getattr(ep.truth, f.name)
    if isinstance(v, np.ndarray):
        h.update(f.name.encode()); h.update(np.ascontiguousarray(v).tobytes())
skin = render(simulate(Scenario(task="lift", seed=0, duration_s=3.0, hand_surface="skin")))
print(h.hexdigest(), hashlib.sha256(ep.depth.depth_m.tobytes()).hexdigest(),
      hashlib.sha256(skin.depth.depth_m.tobytes()).hexdigest())
"""


def test_truth_and_depth_are_bit_identical_under_every_openblas_kernel(kernel_python):
    """The simulation loop and the renderer's inputs keep BLAS out (fixed-order fsv.linalg, stored
    grasp plans), so the kernel OpenBLAS picks for the CPU cannot change the world."""
    digests = set()
    for kernel in ("Haswell", "Sandybridge", "Nehalem", "Prescott"):
        digests.add(kernel_python(_WORLD_DIGEST, env={"OPENBLAS_CORETYPE": kernel}).strip())
    assert len(digests) == 1, digests


_PINNED = """
import hashlib, sys
from benchmark.camera.render import render
from benchmark.world.scenario import Scenario
from benchmark.world.simulate import simulate
ep = render(simulate(Scenario(task="lift", seed=0, duration_s=2.0, hand_surface="capsules")))
skin = render(simulate(Scenario(task="lift", seed=0, duration_s=2.0, hand_surface="skin")))
maps = open("/proc/self/maps").read()
gl = sorted({lib for lib in ("libEGL", "libGL", "libGLX", "libnvidia", "libOSMesa", "llvmpipe", "swrast")
             if lib in maps} | ({"OpenGL"} & set(sys.modules)))
print(hashlib.sha256(ep.depth.depth_m.tobytes()).hexdigest(), float(ep.depth.depth_m.astype("float64").sum()),
      hashlib.sha256(skin.depth.depth_m.tobytes()).hexdigest(), gl)
"""

PINNED_DEPTH_SHA256 = "5047d5b40cbb4eceb6bf5b4d5c9e13367de16d777ab14421dbeb0a871197ff64"
"""The depth of ``Scenario(task="lift", seed=0, duration_s=2.0, hand_surface="capsules")`` (ds325 sensor, 1 cm noise) as this
project's rasteriser and sensor make it: the same on every machine, with or without a GPU (the
previous world's pin was measured alike on a 2-core AMD EPYC without a GPU and on a 16-core Intel
Xeon with an NVIDIA H200; this one, of the world whose people grip at their drawn margins, on a
2-core Intel Xeon under its OpenBLAS kernels)."""
PINNED_SKIN_DEPTH_SHA256 = "748625eeed803b4562da179322ce6e67a7db2fb09a24b835b033d26bb5aba684"
"""The same scenario's depth with the hand drawn as its skin (``hand_surface="skin"``)."""


def test_the_depth_is_the_pinned_rasterisers_and_no_gl_library_takes_part():
    """A rendered scenario's depth hashes to the pinned value, and rendering loads no GL, EGL or
    GPU driver library (nor PyOpenGL): a machine's GPU cannot change the depth."""
    import subprocess
    import sys

    env = {k: v for k, v in os.environ.items() if k not in ("MUJOCO_GL", "PYOPENGL_PLATFORM")}  # as a user runs it
    out = subprocess.run([sys.executable, "-c", _PINNED], env=env, capture_output=True, text=True,
                         check=True).stdout.split()
    assert out[-1] == "[]", out
    assert out[0] == PINNED_DEPTH_SHA256, out
    assert out[2] == PINNED_SKIN_DEPTH_SHA256, out


def test_the_box_and_table_meshes_are_trimeshs_without_importing_it():
    """``scene.geom_mesh`` builds and moves boxes and planes as trimesh does, bit for bit (the
    rasteriser's input), so that a render worker need not import trimesh."""
    import trimesh  # noqa: F401 (the reference)

    from benchmark.world.assets import build_world
    from benchmark.world.scenario import Scenario
    from fsv.rotation import quat_to_rot

    world = build_world(Scenario(task="lift"))
    model = world.model
    rng = np.random.default_rng(11)
    poses = [np.eye(4)]
    for k in range(6):
        T = np.eye(4)
        T[:3, :3] = quat_to_rot(rng.standard_normal(4)) if k != 1 else np.eye(3)  # k = 1: a translation only
        T[:3, 3] = rng.uniform(-0.5, 0.5, 3)
        poses.append(T)
    mirror = np.diag([1.0, -1.0, 1.0, 1.0])  # turns the triangles' winding
    poses.append(mirror)
    kinds = set()
    for g in (world.table_geom, world.box_geom):
        kinds.add(int(model.geom_type[g]))
        for T in poses:
            vertices, faces = S.geom_mesh(model, g, T)
            mesh = S.geom_trimesh(model, g)
            mesh.apply_transform(T)
            assert vertices.tobytes() == np.asarray(mesh.vertices, dtype=np.float64).tobytes()
            assert faces.tobytes() == np.asarray(mesh.faces, dtype=np.int64).tobytes()
    assert kinds == {int(mujoco.mjtGeom.mjGEOM_PLANE), int(mujoco.mjtGeom.mjGEOM_BOX)}
    vertices, faces = S.geom_mesh(model, world.box_geom, mirror)
    assert faces[0].tolist() == [0, 3, 1]  # trimesh's first triangle (1, 3, 0), reversed


def test_a_render_worker_imports_no_trimesh():
    import subprocess
    import sys

    code = ("import sys; from benchmark.world.scenario import Scenario; from benchmark.world.simulate import simulate; "
            "from benchmark.camera.render import render; render(simulate(Scenario(task='lift', duration_s=1.0))); "
            "print('trimesh' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                         env={**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)})
    assert out.stdout.split()[-1] == "False"
