"""Speed of the depth renderer, against MuJoCo's own renderer on the same scene as a peer.

Run: ``python -m benchmark.perf.render [--frames N]``. It simulates a short lift of the
default scenario, then renders its frames at 320 x 240 three ways in this process:

- this benchmark's renderer (:class:`benchmark.camera.depth.DepthRenderer`, the CPU rasteriser on
  one core): exact depth + label image per frame;
- the same + the sensor model (what ``render()`` does per frame);
- the same with the hand drawn as its skin (:mod:`benchmark.world.skin`, pulps pressed), without
  and with the ``ds325`` sensor model;
- MuJoCo's ``mujoco.Renderer`` with depth rendering (EGL) from an identical camera (same
  pose and intrinsics, added to the model as a MuJoCo camera).

The three are timed in turn within each of ``--repeats`` rounds (so a change of the machine's
load hits all of them alike). It prints, per way, the best and the median frames per second over
the rounds (wall clock) and the process's CPU time per frame (all threads, MuJoCo's llvmpipe's included),
the ratios against MuJoCo, and how far the two renderers' depths differ on the pixels both see
(a check that the scenes and cameras really are the same).
"""

from __future__ import annotations

import argparse
import os
import time

os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("PYOPENGL_PLATFORM", "egl")

import mujoco  # noqa: E402
import numpy as np  # noqa: E402

from benchmark.camera.camera import GL_FROM_CV, Camera, load_camera  # noqa: E402
from benchmark.camera.depth import DepthRenderer, pulp_presses  # noqa: E402
from benchmark.camera.render import hand_skin
from benchmark.camera.scene import world_labels
from benchmark.camera.sensor import SENSORS, sensor_preset
from benchmark.world.assets import build_world, set_frame, user_of, world_xml
from benchmark.world.scenario import Scenario
from benchmark.world.simulate import simulate
from benchmark.world.tasks import TASKS


def add_mujoco_camera(spec, camera: Camera, name: str = "depth_camera"):
    """Adds `camera` to a MuJoCo model spec as a MuJoCo camera with the same pose and intrinsics.

    MuJoCo cameras look along their -z axis with y up (OpenGL's convention), and their principal
    point is given as an offset in pixels from the image centre ((W - 1) / 2, (H - 1) / 2).
    """
    T = camera.T_world_cam @ GL_FROM_CV
    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, T[:3, :3].flatten())
    cam = spec.worldbody.add_camera(name=name, pos=T[:3, 3], quat=quat)
    cam.resolution = [camera.width, camera.height]
    cam.sensor_size = [camera.width * 1e-5, camera.height * 1e-5]  # any size: focal is in pixels
    cam.focal_pixel = [camera.K[0, 0], camera.K[1, 1]]
    cam.principal_pixel = [camera.K[0, 2] - (camera.width - 1) / 2, camera.K[1, 2] - (camera.height - 1) / 2]
    spec.visual.global_.offwidth = max(spec.visual.global_.offwidth, camera.width)
    spec.visual.global_.offheight = max(spec.visual.global_.offheight, camera.height)
    return cam


def _rates(fns: dict, frames: int, repeats: int) -> dict:
    """Times passes of fn(k) for k in range(frames), the functions in turn, `repeats` rounds.

    Returns:
        Per name: ``(best fps, median fps, median CPU ms per frame)`` (wall-clock rates; CPU
        time of the whole process, all threads).
    """
    wall = {name: [] for name in fns}
    cpu = {name: [] for name in fns}
    for _ in range(repeats):
        for name, fn in fns.items():
            t0, c0 = time.perf_counter(), time.process_time()
            for k in range(frames):
                fn(k)
            wall[name].append(time.perf_counter() - t0)
            cpu[name].append(time.process_time() - c0)
    return {
        name: (frames / min(wall[name]), frames / float(np.median(wall[name])), 1e3 * float(np.median(cpu[name])) / frames)
        for name in fns
    }


def scene_frames(num: int):
    """The default scenario's world and the first `num` frames of its simulated lift.

    Returns:
        ``(world, set_frame, truth)`` with ``set_frame(data, k)`` posing frame k.
    """

    sc = Scenario(duration_s=max((num - 1) / Scenario().fps, TASKS[Scenario().task].min_duration_s))
    truth = simulate(sc).truth
    world = build_world(sc)

    def pose(data, k):
        set_frame(world, data, truth.box_pos[k], truth.box_quat[k], truth.hand_qpos[k])

    return world, pose, truth


def main(argv=None) -> dict:
    """Measures and prints renderer speeds; returns them as a dict."""

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=150, help="frames per timed pass (default 150)")
    parser.add_argument("--repeats", type=int, default=5, help="timed rounds (default 5)")
    args = parser.parse_args(argv)
    if args.frames < 1:
        parser.error(f"--frames must be >= 1, got {args.frames}")
    if args.repeats < 1:
        parser.error(f"--repeats must be >= 1, got {args.repeats}")

    camera = load_camera()

    world, pose, truth = scene_frames(args.frames)
    model = world.model
    data = mujoco.MjData(model)
    ours = DepthRenderer(model, camera, world_labels(world))
    skinned = DepthRenderer(model, camera, world_labels(world), skin=hand_skin(world))
    centre, push = pulp_presses(truth)
    sensors = {name: sensor_preset(name, 0.01) for name in SENSORS}
    rng = np.random.default_rng(0)

    peer_model, peer_data, peer = _peer(world, camera)

    def posed(k):
        pose(data, k)
        return data

    def render_only(k):
        d = posed(k)
        ours.render(d.xpos, d.xmat)

    def render_and_sense(name):
        def run(k):
            d = posed(k)
            sensors[name].measure(ours.render(d.xpos, d.xmat)[0], camera.K, rng)

        return run

    def skin_only(k):
        d = posed(k)
        skinned.render(d.xpos, d.xmat, centre[k], push[k])

    def skin_and_sense(k):
        d = posed(k)
        sensors["ds325"].measure(skinned.render(d.xpos, d.xmat, centre[k], push[k])[0], camera.K, rng)

    def mujoco_depth(k):
        d = posed(k)
        peer_data.qpos[:] = d.qpos
        peer_data.mocap_pos[:] = d.mocap_pos
        peer_data.mocap_quat[:] = d.mocap_quat
        mujoco.mj_kinematics(peer_model, peer_data)
        mujoco.mj_camlight(peer_model, peer_data)
        peer.update_scene(peer_data, camera="depth_camera")
        peer.render()

    timed = _rates(
        {"depth_labels": render_only,
         **{f"depth_labels_sensor_{name}": render_and_sense(name) for name in SENSORS},
         "skin_depth_labels": skin_only, "skin_depth_labels_sensor_ds325": skin_and_sense,
         "mujoco_depth": mujoco_depth},
        args.frames,
        args.repeats,
    )
    rates = {}
    for name, (best, median, cpu_ms) in timed.items():
        rates[f"{name}_fps"] = best
        rates[f"{name}_fps_median"] = median
        rates[f"{name}_cpu_ms"] = cpu_ms
    # agreement of the two renderers on one frame (pixels both see, within the sensor's range)
    mujoco_depth(args.frames // 2)
    theirs = peer.render()
    d = posed(args.frames // 2)
    mine, labels = ours.render(d.xpos, d.xmat)
    both = (mine > 0) & (mine <= 1.0) & (theirs <= 1.0)
    diff = np.abs(mine - theirs)[both]
    rates["agreement_median_m"] = float(np.median(diff))
    rates["agreement_within_0.1mm"] = float(np.mean(diff < 1e-4))
    _print_rates(rates, f"scene: {model.ngeom} geoms, {ours.triangles} triangles and {ours.capsules} "
                        f"ray-cast capsules per frame (with the skin: {skinned.triangles} + {len(skinned.skin.faces)} "
                        f"triangles, {skinned.capsules} capsules); {camera.width}x{camera.height}; {args.frames} frames "
                        f"per pass, {args.repeats} rounds")
    peer.close()
    return rates


def _peer(world, camera) -> tuple:
    """MuJoCo's own depth renderer of the same world and camera: ``(model, data, renderer)``."""
    spec = mujoco.MjSpec.from_string(_model_xml(world))
    add_mujoco_camera(spec, camera, "depth_camera")
    peer_model = spec.compile()
    peer = mujoco.Renderer(peer_model, camera.height, camera.width)
    peer.enable_depth_rendering()
    return peer_model, mujoco.MjData(peer_model), peer


def _print_rates(rates: dict, scene: str) -> None:
    """The rates and ratios as a table."""

    print(scene)
    print("                                   best fps  median fps  CPU ms/frame (all threads)")
    for name, text in (
        ("depth_labels", "depth + labels                 "),
        *((f"depth_labels_sensor_{n}", f"depth + labels + {n:<14s}") for n in SENSORS),
        ("skin_depth_labels", "skin: depth + labels           "),
        ("skin_depth_labels_sensor_ds325", "skin: depth + labels + ds325   "),
        ("mujoco_depth", "MuJoCo Renderer depth (peer)   "),
    ):
        print(f"{text}: {rates[name + '_fps']:8.1f}  {rates[name + '_fps_median']:10.1f}  {rates[name + '_cpu_ms']:8.2f}")
    peer_fps = rates["mujoco_depth_fps"]
    print(
        f"ratio ours / MuJoCo (best fps)   : {rates['depth_labels_fps'] / peer_fps:7.2f} "
        "(with a sensor preset: " + ", ".join(
            f"{n} {rates[f'depth_labels_sensor_{n}_fps'] / peer_fps:.2f}" for n in SENSORS) + ")"
    )
    print(f"ratio skin / primitives (best fps): {rates['skin_depth_labels_fps'] / rates['depth_labels_fps']:7.2f} "
          f"(with ds325 {rates['skin_depth_labels_sensor_ds325_fps'] / rates['depth_labels_sensor_ds325_fps']:.2f})")
    print(
        f"depth agreement with MuJoCo      : median {rates['agreement_median_m'] * 1e6:.2f} um, "
        f"{100 * rates['agreement_within_0.1mm']:.1f} % of pixels within 0.1 mm"
    )


def _model_xml(world) -> str:
    """The MJCF text of a world (for a MuJoCo spec to which the camera is added)."""

    sc = Scenario()
    return world_xml(sc.user, sc.mass, float(user_of(sc)["stiffness_nm_per_rad"]))


if __name__ == "__main__":
    main()
