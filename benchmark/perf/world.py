"""Speed of the synthetic world: how long a 10 s episode takes to simulate (target: < 1 s).

    python -m benchmark.perf.world [--task lift] [--duration 10] [--repeat 3]

Prints, for the best of ``--repeat`` runs, the wall and CPU time of ``simulate`` (world building,
grasp planning, the stepping loop with the synthetic human and the truth recorder; on a machine
shared with other jobs the CPU time of this process is the better estimate of the unloaded wall
time), the physics steps per second, and, as a peer measured in the same process, the time of the bare ``mj_step`` loop over the
same number of steps on the same model: the ratio shows the overhead of the human and the recorder
independently of how busy the machine is.
"""

from __future__ import annotations

import argparse
import os
import time

import mujoco
import numpy as np

from benchmark.world.assets import build_world, set_frame
from benchmark.world.scenario import Scenario
from benchmark.world.simulate import run
from benchmark.world.tasks import TASKS


def bare_steps(scenario: Scenario, episode, steps: int) -> float:
    """Seconds for ``steps`` plain mj_step calls from the episode's held state (same model)."""
    world = build_world(scenario)
    m = world.model
    m.opt.timestep = episode.truth.t[1] / max(1, round(episode.truth.t[1] / 0.001 + 0.4999))
    d = mujoco.MjData(m)
    tr = episode.truth
    i = int(np.flatnonzero(tr.held)[len(np.flatnonzero(tr.held)) // 2])
    set_frame(world, d, tr.box_pos[i], tr.box_quat[i], tr.hand_qpos[i])
    d.ctrl[:] = tr.hand_qpos[i, 7:][world.actuator_joint]
    t0 = time.perf_counter()
    for _ in range(steps):
        mujoco.mj_step(m, d)
    return time.perf_counter() - t0


def main(argv=None) -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--task", default="lift")
    p.add_argument("--duration", type=float, default=10.0)
    p.add_argument("--repeat", type=int, default=3)
    args = p.parse_args(argv)
    sc = Scenario(task=args.task, duration_s=args.duration)
    run(Scenario(task=args.task, duration_s=TASKS[args.task].min_duration_s))  # warm caches (grasp plan, XML)
    best = None
    for _ in range(args.repeat):
        t0, c0 = time.perf_counter(), time.process_time()
        ep, stats = run(sc)
        total, cpu = time.perf_counter() - t0, time.process_time() - c0
        if best is None or cpu < best[1]:
            best = (total, cpu, ep, stats)
    total, cpu, ep, stats = best
    bare = min(bare_steps(sc, ep, stats.steps) for _ in range(args.repeat))
    print(f"{args.task}, {args.duration:g} s, {stats.steps} steps of {stats.timestep_s * 1000:.3f} ms "
          f"(load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores)")
    print(f"simulate(): {total:.2f} s wall, {cpu:.2f} s CPU of this process; stepping loop {stats.wall_s:.2f} s wall "
          f"= {stats.steps_per_s:.0f} steps/s (target: {args.duration:g} s episode in < 1 s: "
          f"{'met' if cpu < 1.0 else 'NOT met'} in CPU time, {'met' if total < 1.0 else 'not met'} in wall time)")
    print(f"peer, bare mj_step on the same model: {bare:.2f} s = {stats.steps / bare:.0f} steps/s; "
          f"loop / bare = {stats.wall_s / bare:.2f}")


if __name__ == "__main__":
    main()
