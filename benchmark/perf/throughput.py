"""Throughput: episodes per core-minute for dataset generation and suite evaluation, the scaling from
1 to 2 local workers, and what a dataset the size of the TPAMI extension's would take on 64 cores.

    python -m benchmark.perf.throughput [--episodes 4] [--duration 5] [--suite smoke]

Generation: the grid ``lift`` x seeds 0..N-1 of ``--duration`` s with tracked contacts (simulate,
render, track, forces, tactile), from scratch, in this process and with 2 worker processes.
Evaluation: ``--suite`` with the reference method from an empty episode cache, 1 then 2 workers.
Every worker, and this process in the 1-worker runs, is limited to one thread of Mesa's
software rasteriser and of the native libraries (``benchmark.parallel.ONE_CORE_ENV``), so that
a worker is one core. Episodes per core-minute = episodes / (wall minutes x workers). The
extrapolation takes the
1-worker generation cost per second of manipulation, times 3.2 h (11 520 s, the TPAMI extension's
dataset), divided by 64 cores at the measured 2-worker efficiency (a cluster of 2-core-like nodes,
no other overhead). The machine is shared: state its load beside the numbers.
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time

from benchmark.paper.dataset import DatasetSpec, generate
from benchmark.parallel import ONE_CORE_ENV
from benchmark.suites import get_suite
from benchmark.suites.evaluate import evaluate

TPAMI_MANIPULATION_S = 3.2 * 3600
"""Seconds of manipulation in the TPAMI extension's dataset (3.2 h)."""


def per_core_minute(episodes: int, seconds: float, workers: int) -> float:
    """Episodes per core-minute of a run that took ``seconds`` on ``workers`` workers."""
    return episodes / (seconds / 60.0 * workers)


def extrapolate(seconds_1: float, manipulated_s: float, efficiency: float, cores: int = 64,
                target_s: float = TPAMI_MANIPULATION_S) -> dict:
    """Wall time to generate ``target_s`` of manipulation on ``cores`` cores.

    Args:
        seconds_1: Wall seconds of the 1-worker run.
        manipulated_s: Seconds of manipulation it generated.
        efficiency: Measured parallel efficiency (speed-up / workers) applied to every core.
        cores: Cores of the cluster.
        target_s: Seconds of manipulation wanted.

    Returns:
        ``core_hours`` (at 1 worker's speed) and ``wall_hours`` on ``cores`` cores.
    """
    core_s = seconds_1 / manipulated_s * target_s
    return {"core_hours": core_s / 3600, "wall_hours": core_s / (cores * efficiency) / 3600, "cores": cores}


def _generate(episodes: int, duration: float, workers: int) -> float:
    spec = DatasetSpec(tasks=("lift",), seeds=tuple(range(episodes)), duration_s=duration)
    with tempfile.TemporaryDirectory() as out:
        t0 = time.perf_counter()
        generate(spec, out, workers=workers, progress=False)
        return time.perf_counter() - t0


def _evaluate(suite_name: str, workers: int) -> float:
    with tempfile.TemporaryDirectory() as cache:
        t0 = time.perf_counter()
        evaluate(get_suite(suite_name), cache=cache, progress=False, workers=workers)
        return time.perf_counter() - t0


def main(argv=None) -> dict:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--episodes", type=int, default=4, help="generation episodes per measurement")
    p.add_argument("--duration", type=float, default=5.0, help="generation episode length in seconds")
    p.add_argument("--suite", default="smoke", help="suite evaluated")
    args = p.parse_args(argv)

    # One worker is one core: the in-process run too (before anything renders), like the pool's workers.
    os.environ.update(ONE_CORE_ENV)

    suite = get_suite(args.suite)
    load = os.getloadavg()
    g1, g2 = _generate(args.episodes, args.duration, 1), _generate(args.episodes, args.duration, 2)
    e1, e2 = _evaluate(args.suite, 1), _evaluate(args.suite, 2)
    n = len(suite.scenarios)
    eff = (g1 / g2) / 2
    x = extrapolate(g1, args.episodes * args.duration, eff)
    res = {"load_before": load, "load_after": os.getloadavg(),
           "generate": {"episodes": args.episodes, "seconds_1": g1, "seconds_2": g2, "speedup": g1 / g2,
                        "per_core_minute_1": per_core_minute(args.episodes, g1, 1),
                        "per_core_minute_2": per_core_minute(args.episodes, g2, 2)},
           "evaluate": {"suite": args.suite, "episodes": n, "seconds_1": e1, "seconds_2": e2, "speedup": e1 / e2,
                        "per_core_minute_1": per_core_minute(n, e1, 1), "per_core_minute_2": per_core_minute(n, e2, 2)},
           "tpami_64_cores": x}
    print(f"load average before {load[0]:.2f}, after {res['load_after'][0]:.2f} ({os.cpu_count()} cores)")
    for name, r in (("generate", res["generate"]), ("evaluate", res["evaluate"])):
        print(f"{name:9s}: 1 worker {r['seconds_1']:6.1f} s ({r['per_core_minute_1']:.2f} episodes/core-min), "
              f"2 workers {r['seconds_2']:6.1f} s ({r['per_core_minute_2']:.2f} episodes/core-min), "
              f"speed-up {r['speedup']:.2f}x")
    print(f"3.2 h of manipulation (TPAMI): {x['core_hours']:.1f} core-hours; {x['wall_hours']:.2f} h on 64 cores "
          f"at the measured 2-worker efficiency ({eff:.2f})")
    return res


if __name__ == "__main__":
    main()
