"""Speed of the colour camera against the depth rasteriser, in one process.

Run: ``python -m benchmark.perf.colour [--frames N] [--repeats R]``. It simulates a lift of the
default scenario (hand drawn as the person's skin, pulps pressed) and times, per frame, in turn
within each of ``--repeats`` rounds (so a change of the machine's load hits all alike), on one core:

- the depth rasteriser with the ``ds325`` sensor model at 320 x 240 (what ``render()`` does per
  frame: :class:`benchmark.camera.depth.DepthRenderer` + :class:`benchmark.camera.sensor.SensorModel`);
- the colour camera at 640 x 480, ``ds325`` preset: motion-adaptive blur (sub-renders every
  ``blur_step_px``), shading, textures, noise, white balance, sRGB (what
  :func:`benchmark.camera.colour.render_colour` does per frame);
- the same with sub-renders every 2 px, with a fixed 3 sub-renders, and without blur (zero exposure);
- one colour render (radiance, depth, labels) without the sensor.

It prints the best and median frames per second and the mean sub-renders per frame, and the
ratios against the depth rasteriser.
"""

from __future__ import annotations

import argparse
import dataclasses

import mujoco
import numpy as np

from benchmark.camera.appearance import appearance_of
from benchmark.camera.camera import load_camera
from benchmark.camera.colour import ColourRenderer, interpolated_state
from benchmark.camera.colour_sensor import colour_camera, colour_preset
from benchmark.camera.depth import DepthRenderer, hand_skin, pulp_presses
from benchmark.camera.scene import world_labels
from benchmark.camera.sensor import sensor_preset
from benchmark.perf.render import _rates, scene_frames
from benchmark.world.assets import set_frame
from benchmark.world.scenario import Scenario


def main(argv=None) -> dict:
    """Measures and prints the speeds; returns them as a dict (fps per way, best and median)."""

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=150, help="frames per timed pass (default 150)")
    parser.add_argument("--repeats", type=int, default=3, help="timed rounds (default 3)")
    args = parser.parse_args(argv)
    if args.frames < 1:
        parser.error(f"--frames must be >= 1, got {args.frames}")
    if args.repeats < 1:
        parser.error(f"--repeats must be >= 1, got {args.repeats}")

    world, pose, truth = scene_frames(args.frames)
    model = world.model
    fps = Scenario().fps
    data = mujoco.MjData(model)
    skin = hand_skin(world)
    labels = world_labels(world)
    centre, push = pulp_presses(truth)
    depth_cam = load_camera()
    depth = DepthRenderer(model, depth_cam, labels, skin=skin)
    depth_sensor = sensor_preset("ds325", 0.01)
    appearance = appearance_of(Scenario())
    base = colour_preset("ds325")
    sensors = {
        "colour": base,
        "colour_step2": dataclasses.replace(base, blur_step_px=2.0),
        "colour_fixed3": dataclasses.replace(base, blur_step_px=1e-9, max_samples=3),
        "colour_noblur": dataclasses.replace(base, exposure_s=0.0),
    }
    camera = colour_camera(depth_cam, base)
    colour = ColourRenderer(model, camera, labels, appearance, skin=skin)
    rng = np.random.default_rng(0)
    T = len(truth.t)
    samples = {name: [] for name in sensors}

    def set_state(d, k, s):
        box_pos, box_quat, hand_qpos = interpolated_state(truth, k, s, fps)
        set_frame(world, d, box_pos, box_quat, hand_qpos)

    def depth_frame(k):
        pose(data, k)
        depth_sensor.measure(depth.render(data.xpos, data.xmat, centre[k], push[k])[0], depth_cam.K, rng)

    def colour_frame(name):
        sensor = sensors[name]

        def run(k):
            k = k % T
            radiance, _, _, S = colour.render_exposure(set_state, data, k, sensor, centre[k], push[k])
            sensor.measure(radiance, rng, appearance.lighting)
            samples[name].append(S)

        return run

    def colour_render(k):
        pose(data, k % T)
        colour.render(data.xpos, data.xmat, centre[k % T], push[k % T])

    fns = {"depth_ds325_320x240": depth_frame, **{name: colour_frame(name) for name in sensors},
           "colour_render_only": colour_render}
    for fn in fns.values():  # compile and warm up
        fn(0)
    for name in samples:
        samples[name].clear()
    timed = _rates(fns, args.frames, args.repeats)
    rates = {}
    for name, (best, median, cpu_ms) in timed.items():
        rates[f"{name}_fps"] = best
        rates[f"{name}_fps_median"] = median
        rates[f"{name}_cpu_ms"] = cpu_ms
    for name in sensors:
        rates[f"{name}_mean_samples"] = float(np.mean(samples[name]))
    print(f"{args.frames} frames of a {truth.t[-1]:.1f} s lift (skin, pulps pressed), {args.repeats} rounds; colour "
          f"{camera.width}x{camera.height}, depth {depth_cam.width}x{depth_cam.height}, one core")
    print("                                  best fps  median fps  CPU ms/frame  sub-renders/frame  ratio to depth (best)")
    depth_fps = rates["depth_ds325_320x240_fps"]
    for name in fns:
        sub = f"{rates[name + '_mean_samples']:8.2f}" if name in sensors else "        "
        print(f"{name:<32s}: {rates[name + '_fps']:8.1f}  {rates[name + '_fps_median']:10.1f}  "
              f"{rates[name + '_cpu_ms']:12.2f}  {sub}           {rates[name + '_fps'] / depth_fps:6.3f}")
    return rates


if __name__ == "__main__":
    main()
