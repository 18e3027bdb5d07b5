"""Speed of dataset generation: episodes per minute with 1 and 2 workers, and the scaling.

    python -m benchmark.perf.dataset [--episodes 12] [--duration 10]

Generates the same grid of episodes twice into temporary folders: once in this process
(1 worker) and once with a pool of 2 worker processes (which pays for spawning them and importing
MuJoCo there). Prints episodes per minute and the speed-up 1 -> 2 workers. On this 2-core machine
shared with other jobs, expect noise; the ratio is measured in one process, back to back.
"""

from __future__ import annotations

import argparse
import tempfile
import time

from benchmark.paper.dataset import DatasetSpec, generate


def measure(spec: DatasetSpec, workers: int) -> float:
    """Seconds to generate ``spec`` from scratch with ``workers`` workers."""
    with tempfile.TemporaryDirectory() as out:
        t0 = time.perf_counter()
        generate(spec, out, workers=workers, progress=False)
        return time.perf_counter() - t0


def main(argv=None) -> dict:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--episodes", type=int, default=4, help="episodes per measurement (seeds 0..N-1 of lift)")
    p.add_argument("--duration", type=float, default=5.0, help="episode length in seconds")
    p.add_argument("--task", default="lift")
    args = p.parse_args(argv)
    spec = DatasetSpec(tasks=(args.task,), seeds=tuple(range(args.episodes)), duration_s=args.duration)
    s1 = measure(spec, 1)
    s2 = measure(spec, 2)
    res = dict(episodes=args.episodes, duration_s=args.duration, seconds_1=s1, seconds_2=s2,
               per_minute_1=60 * args.episodes / s1, per_minute_2=60 * args.episodes / s2, speedup=s1 / s2)
    print(f"{args.episodes} episodes of {args.duration:g} s ({args.task}):")
    print(f"  1 worker : {s1:6.1f} s  -> {res['per_minute_1']:.1f} episodes/min")
    print(f"  2 workers: {s2:6.1f} s  -> {res['per_minute_2']:.1f} episodes/min")
    print(f"  speed-up 1 -> 2 workers: {res['speedup']:.2f}x")
    return res


if __name__ == "__main__":
    main()
