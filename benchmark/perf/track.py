"""Speed of the tracker, and of every other stage of the method, per frame.

    python -m benchmark.perf.track [--task lift] [--duration S] [--seed N]

Simulates and renders one episode, then runs the method's stages on it the way ``fsv.run_pipeline``
does: tracking (box, hand, contacts), kinematics (the algebraic differentiator) and the nominal
forces, and reports frames per second and milliseconds per frame of each, in wall-clock time and
in process CPU time (the machine is shared by several jobs, so CPU time is the steadier number).
As a peer in the same process, the renderer's own speed on the same episode is printed: tracking a
frame should not cost much more than drawing it.
Target (issue 6): >= 10 tracked frames per second on 2 cores (goal 30, real time).
"""

from __future__ import annotations

import argparse
import sys
import time

TARGET_FPS = 10.0


def _timed(fn):
    w0, c0 = time.perf_counter(), time.process_time()
    out = fn()
    return out, time.perf_counter() - w0, time.process_time() - c0


def main(argv=None) -> int:
    from benchmark.camera.render import render
    from benchmark.world.scenario import Scenario
    from benchmark.world.simulate import simulate
    from benchmark.method.init import tracker_init
    from fsv.forces import nominal_forces
    from fsv.kinematics import AlgebraicConfig, differentiate_poses
    from fsv.track.tracker import track

    p = argparse.ArgumentParser(prog="python -m benchmark.perf.track", description=__doc__.splitlines()[0])
    p.add_argument("--task", default="lift")
    p.add_argument("--duration", type=float, default=4.0)
    p.add_argument("--seed", type=int, default=0)
    args = p.parse_args(argv)
    sc = Scenario(task=args.task, noise_m=0.01, seed=args.seed, duration_s=args.duration)
    ep = simulate(sc)
    ep, render_wall, render_cpu = _timed(lambda: render(ep))
    T = len(ep.truth.t)
    init = tracker_init(ep.truth, sc, ep.hand_model)
    tracking, wall, cpu = _timed(lambda: track(ep.depth, ep.calib, ep.object_model, ep.hand_model, init,
                                               rng=sc.rng("tracker")))
    kin, k_wall, k_cpu = _timed(lambda: differentiate_poses(tracking.box, AlgebraicConfig()))
    _, f_wall, f_cpu = _timed(lambda: nominal_forces(kin, tracking.contacts, ep.object_model, gravity=ep.truth.gravity))
    rows = [("render (peer)", render_wall, render_cpu)]
    rows += [(f"track: {k}", v, None) for k, v in tracking.timing_s.items()]
    rows += [("track (total)", wall, cpu), ("kinematics", k_wall, k_cpu), ("forces (nominal)", f_wall, f_cpu)]
    print(f"{args.task}, {T} frames of {ep.depth.depth_m.shape[2]}x{ep.depth.depth_m.shape[1]} depth, seed {args.seed}")
    print(f"{'stage':<22}{'ms/frame wall':>15}{'ms/frame cpu':>15}{'frames/s wall':>15}")
    for name, w, c in rows:
        cpu_ms = f"{1e3 * c / T:15.2f}" if c is not None else f"{'-':>15}"
        print(f"{name:<22}{1e3 * w / T:15.2f}{cpu_ms}{T / w:15.1f}")
    fps_cpu = T / cpu
    print(f"tracker: {T / wall:.1f} frames/s wall, {fps_cpu:.1f} frames/s of CPU time "
          f"(target >= {TARGET_FPS:g}); tracking costs {wall / render_wall:.1f}x the renderer's time")
    return 0


if __name__ == "__main__":
    sys.exit(main())
