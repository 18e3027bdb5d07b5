"""The main command's whole-process wall time, with and without the colour stream.

    python -m benchmark.perf.command [--runs 5] [--streams depth depth,colour] [--trees DIR ...]

Runs ``fsv-bench --task lift --noise 0.01 --streams S --quiet --no-gif`` (the console script's
module, :mod:`benchmark.commands.entry`, in a fresh interpreter each time) ``--runs`` times per
variant, the variants interleaved round by round so that the load of a shared machine falls on all
of them alike, and prints each variant's times, median and the ratio of its median to the first
variant's. A variant is a value of ``--streams`` on the code of a tree (``--trees``: source folders
put first on ``PYTHONPATH``, e.g. a checkout of the code before a change; default this one). The
load average (``os.getloadavg``, 1 min) is read before every run and reported per variant.
The first round is a warm-up that is not counted (numba's cache, the page cache). Beside the
wall time, the CPU time (user + system, the command and its children): on a machine that others
load, the wall time of work done beside the main chain approaches the CPU time's share. And the
CPU time of the command's main thread (the imports and every stage; the render worker, the
pictures and the episode file run beside it): on an idle two-core machine the wall time is that,
plus what the main thread waits for, so it is the measure of the critical path that a loaded
machine inflates least.
"""

from __future__ import annotations

import argparse
import os
import pathlib
import resource
import statistics
import subprocess
import sys
import tempfile
import time

from fsv.errors import InputError
from fsv.types import check_streams

HERE = pathlib.Path(__file__).resolve().parents[2]
COMMAND = ("--task", "lift", "--noise", "0.01", "--quiet", "--no-gif", "--force")
PROBE = """
import os, sys, time
from benchmark import interrupt
from benchmark.commands import entry

def _exit_now(code=interrupt.EXIT_INTERRUPTED, _exit=interrupt.exit_now):
    os.write(2, f"main-thread-cpu {time.thread_time():.4f}\\n".encode())
    _exit(code)

interrupt.exit_now = _exit_now
sys.argv[0] = "fsv-bench"
sys.exit(entry.main())
"""
"""The console script's ``main`` (:mod:`benchmark.commands.entry`), which ends the main command with
``interrupt.exit_now`` once its output is complete, with the main thread's CPU time written to stderr
just before."""


def run_once(tree: pathlib.Path, streams: str, out: pathlib.Path) -> tuple:
    """``(wall, cpu, main)`` seconds of one whole ``fsv-bench`` process on the code of ``tree`` (cpu:
    user + system time of it and its children, which a loaded machine does not inflate as it does
    the wall time; main: its main thread's, :data:`PROBE`); raises if it fails (exit 1, a failed
    gate, counts as done: the time is the command's)."""
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(tree), os.environ.get("PYTHONPATH", "")]).rstrip(os.pathsep)}
    argv = [sys.executable, "-c", PROBE, *COMMAND, "--streams", streams, "--out", str(out)]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    done = subprocess.run(argv, env=env, cwd=tree, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    took = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if done.returncode not in (0, 1):
        raise RuntimeError(f"{' '.join(argv)} exited {done.returncode}: {done.stderr.decode()[-2000:]}")
    main = [float(line.split()[1]) for line in done.stderr.decode().splitlines() if line.startswith("main-thread-cpu ")]
    return took, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime), main[-1] if main else float("nan")


def bad_input(args: argparse.Namespace) -> str | None:
    """What is wrong with the arguments, in one line naming the value and what is accepted, or None."""
    if args.runs < 1:
        return f"--runs {args.runs}: accepted: 1 or more"
    for tree in args.trees:
        if not (tree / "benchmark" / "commands" / "entry.py").is_file():
            return (f"--trees {str(tree)!r}: not a source tree of fsv-bench (no benchmark/commands/entry.py there); "
                    "accepted: folders such as a checkout of another commit (`git worktree add DIR COMMIT`)")
    for streams in args.streams:
        try:
            check_streams(streams)
        except InputError as e:
            return f"--streams {streams!r}: {e}"
    return None


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m benchmark.perf.command", description=__doc__.strip().splitlines()[0])
    p.add_argument("--runs", type=int, default=5, help="counted runs per variant (default 5)")
    p.add_argument("--streams", nargs="+", default=["depth", "depth,colour"], help="values of --streams")
    p.add_argument("--trees", nargs="+", type=pathlib.Path, default=[HERE], help="source trees (default: this one)")
    args = p.parse_args(argv)
    bad = bad_input(args)
    if bad is not None:
        print(f"python -m benchmark.perf.command: {bad}", file=sys.stderr)
        return 2
    variants = [(tree.resolve(), s) for tree in args.trees for s in args.streams]
    times = {v: [] for v in variants}
    cpus = {v: [] for v in variants}
    mains = {v: [] for v in variants}
    loads = {v: [] for v in variants}
    with tempfile.TemporaryDirectory(prefix="fsv-perf-command-") as tmp:
        for round_ in range(args.runs + 1):
            for i, (tree, streams) in enumerate(variants):
                load = os.getloadavg()[0]
                took, cpu, main = run_once(tree, streams, pathlib.Path(tmp) / f"run{i}")
                if round_ > 0:
                    times[(tree, streams)].append(took)
                    cpus[(tree, streams)].append(cpu)
                    mains[(tree, streams)].append(main)
                    loads[(tree, streams)].append(load)
                print(f"{'warm-up' if round_ == 0 else f'round {round_}'}: {tree.name} --streams {streams}: "
                      f"{took:.2f} s, cpu {cpu:.2f} s, main thread {main:.2f} s (load {load:.2f})", file=sys.stderr,
                      flush=True)
    base = statistics.median(times[variants[0]])
    print(f"fsv-bench {' '.join(COMMAND[:4])} --streams S, whole process, {args.runs} runs each, interleaved\n")
    cpu_base = statistics.median(cpus[variants[0]])
    main_base = statistics.median(mains[variants[0]])
    print("| tree | --streams | wall, median [s] | runs [s] | vs first | cpu, median [s] | vs first | "
          "main thread cpu, median [s] | vs first | load (1 min) |\n|---|---|---|---|---|---|---|---|---|---|")
    for v in variants:
        med, cpu, main = statistics.median(times[v]), statistics.median(cpus[v]), statistics.median(mains[v])
        print(f"| {v[0].name} | {v[1]} | {med:.2f} | {', '.join(f'{t:.2f}' for t in times[v])} | "
              f"{100 * (med / base - 1):+.0f} % | {cpu:.2f} | {100 * (cpu / cpu_base - 1):+.0f} % | "
              f"{main:.2f} | {100 * (main / main_base - 1):+.0f} % | {min(loads[v]):.2f}-{max(loads[v]):.2f} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
