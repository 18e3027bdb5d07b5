"""The main command's whole-process wall time, with and without the colour stream.

    python -m benchmark.perf.command [--runs 5] [--streams depth depth,colour] [--trees DIR ...]

Runs ``fsv-bench --task lift --noise 0.01 --streams S --quiet --no-gif`` (the console script's
module, :mod:`benchmark.commands.entry`, in a fresh interpreter each time) ``--runs`` times per
variant, the variants interleaved round by round so that the load of a shared machine falls on all
of them alike, and prints each variant's times, median and the ratio of its median to the first
variant's. A variant is a value of ``--streams`` on the code of a tree (``--trees``: source folders
put first on ``PYTHONPATH``, e.g. a checkout of the code before a change; default this one). The
load average (``os.getloadavg``, 1 min) is read before every run and reported per variant.
The first round is a warm-up that is not counted (numba's cache, the page cache).
"""

from __future__ import annotations

import argparse
import os
import pathlib
import statistics
import subprocess
import sys
import tempfile
import time

HERE = pathlib.Path(__file__).resolve().parents[2]
COMMAND = ("--task", "lift", "--noise", "0.01", "--quiet", "--no-gif", "--force")


def run_once(tree: pathlib.Path, streams: str, out: pathlib.Path) -> float:
    """Wall seconds of one whole ``fsv-bench`` process on the code of ``tree``; raises if it fails
    (exit 1, a failed gate, counts as done: the time is the command's)."""
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(tree), os.environ.get("PYTHONPATH", "")]).rstrip(os.pathsep)}
    argv = [sys.executable, "-m", "benchmark.commands.entry", *COMMAND, "--streams", streams, "--out", str(out)]
    t0 = time.perf_counter()
    done = subprocess.run(argv, env=env, cwd=tree, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    took = time.perf_counter() - t0
    if done.returncode not in (0, 1):
        raise RuntimeError(f"{' '.join(argv)} exited {done.returncode}: {done.stderr.decode()[-2000:]}")
    return took


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m benchmark.perf.command", description=__doc__.strip().splitlines()[0])
    p.add_argument("--runs", type=int, default=5, help="counted runs per variant (default 5)")
    p.add_argument("--streams", nargs="+", default=["depth", "depth,colour"], help="values of --streams")
    p.add_argument("--trees", nargs="+", type=pathlib.Path, default=[HERE], help="source trees (default: this one)")
    args = p.parse_args(argv)
    variants = [(tree.resolve(), s) for tree in args.trees for s in args.streams]
    times = {v: [] for v in variants}
    loads = {v: [] for v in variants}
    with tempfile.TemporaryDirectory(prefix="fsv-perf-command-") as tmp:
        for round_ in range(args.runs + 1):
            for i, (tree, streams) in enumerate(variants):
                load = os.getloadavg()[0]
                took = run_once(tree, streams, pathlib.Path(tmp) / f"run{i}")
                if round_ > 0:
                    times[(tree, streams)].append(took)
                    loads[(tree, streams)].append(load)
                print(f"{'warm-up' if round_ == 0 else f'round {round_}'}: {tree.name} --streams {streams}: "
                      f"{took:.2f} s (load {load:.2f})", file=sys.stderr, flush=True)
    base = statistics.median(times[variants[0]])
    print(f"fsv-bench {' '.join(COMMAND[:4])} --streams S, whole process, {args.runs} runs each, interleaved\n")
    print("| tree | --streams | median [s] | runs [s] | vs first | load (1 min) |\n|---|---|---|---|---|---|")
    for v in variants:
        med = statistics.median(times[v])
        print(f"| {v[0].name} | {v[1]} | {med:.2f} | {', '.join(f'{t:.2f}' for t in times[v])} | "
              f"{100 * (med / base - 1):+.0f} % | {min(loads[v]):.2f}-{max(loads[v]):.2f} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
