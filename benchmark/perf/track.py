"""Speed of the tracker on one core, side by side with an earlier version of it in the same run.

    python -m benchmark.perf.track [--task lift] [--duration S] [--seed N] [--baseline REV] [--rounds R]

Simulates and renders one episode, then tracks it (box, hand, contacts) in fresh worker processes
pinned to one CPU core: this checkout's ``fsv`` and, with ``--baseline``, the ``fsv`` package of a
git revision (extracted with ``git archive`` once per content and kept, with its compiled kernels,
in the user's cache: :func:`baseline_fsv`), alternately for ``--rounds`` rounds so that a change
of the machine's load hits both alike. Each worker tracks the episode twice and times the second
pass (the first compiles or loads the numba kernels). It prints per version the frames per second
(wall clock and process CPU time, median over rounds), the stages' milliseconds per frame, the
new/old speed ratio, and the median box position error of each (the two must track alike), and
then, in this process, the rest of the method per frame (kinematics, nominal forces) and the
renderer with the sensor model as a peer.
Target (issue on real time): >= 30 tracked frames per second on one core.
"""

from __future__ import annotations

import argparse
import json
import os
import pathlib
import pickle
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np

from benchmark.camera.render import render
from benchmark.method.init import tracker_init
from benchmark.world.scenario import Scenario
from benchmark.world.simulate import simulate
from fsv.forces import nominal_forces
from fsv.kinematics import AlgebraicConfig, differentiate_poses
from fsv.track.tracker import track

TARGET_FPS = 30.0
ROOT = pathlib.Path(__file__).resolve().parents[2]

_WORKER = r"""
import json, os, pickle, sys, time
import numpy as np
os.sched_setaffinity(0, {int(sys.argv[3])})
from fsv.track.tracker import track
with open(sys.argv[1], "rb") as fh:
    depth, calib, obj, hand, init, seed = pickle.load(fh)
run = lambda: track(depth, calib, obj, hand, init, rng=np.random.default_rng(seed))
run()  # compiles or loads the kernels
w0, c0 = time.perf_counter(), time.process_time()
tr = run()
wall, cpu = time.perf_counter() - w0, time.process_time() - c0
np.save(sys.argv[2], tr.box.pos)
print(json.dumps(dict(wall=wall, cpu=cpu, stages=tr.timing_s)))
"""


def _timed(fn):
    w0, c0 = time.perf_counter(), time.process_time()
    out = fn()
    return out, time.perf_counter() - w0, time.process_time() - c0


def extract_fsv(rev: str, dest: pathlib.Path) -> pathlib.Path:
    """The ``fsv`` package of git revision ``rev`` of this checkout, extracted into ``dest``."""
    archive = subprocess.run(["git", "-C", str(ROOT), "archive", rev, "fsv"], capture_output=True, check=False)
    if archive.returncode != 0:
        raise SystemExit(f"python -m benchmark.perf.track: error: --baseline {rev!r}: "
                         f"{archive.stderr.decode().strip() or 'not a revision of this checkout'}")
    dest.mkdir(parents=True, exist_ok=True)
    subprocess.run(["tar", "-x", "-C", str(dest)], input=archive.stdout, check=True)
    return dest


def baseline_fsv(rev: str) -> pathlib.Path:
    """The folder holding the ``fsv`` package of git revision ``rev``, extracted once per content into
    ``$XDG_CACHE_HOME/fsv-bench/perf-baselines/<the tree's git hash>`` (``~/.cache`` by default) and
    kept: numba's compiled kernels, cached beside the sources, are then made once per baseline, not
    at every run (about 10 s of a core for the tracker's). Extracted into a temporary folder and
    renamed into place, so that runs side by side never see half a package."""
    tree = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--verify", "--quiet", f"{rev}^{{tree}}:fsv"],
                          capture_output=True, text=True, check=False)
    if tree.returncode != 0:
        raise SystemExit(f"python -m benchmark.perf.track: error: --baseline {rev!r}: not a revision of this "
                         "checkout with an fsv package; accepted: a commit, branch or tag, e.g. HEAD~1")
    base = pathlib.Path(os.environ.get("XDG_CACHE_HOME") or pathlib.Path.home() / ".cache") / "fsv-bench" / "perf-baselines"
    folder = base / tree.stdout.strip()
    if (folder / "fsv").is_dir():
        return folder
    base.mkdir(parents=True, exist_ok=True)
    tmp = pathlib.Path(tempfile.mkdtemp(prefix=".extracting-", dir=base))
    extract_fsv(rev, tmp)
    try:
        tmp.rename(folder)
    except OSError:  # another run put it there first
        shutil.rmtree(tmp, ignore_errors=True)
    return folder


def run_worker(job: pathlib.Path, fsv_parent: pathlib.Path, core: int, out: pathlib.Path) -> dict:
    """Tracks the pickled job in a fresh process whose ``fsv`` is the one under ``fsv_parent``."""
    env = dict(os.environ, PYTHONPATH=str(fsv_parent), OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1",
               NUMBA_NUM_THREADS="1")
    res = subprocess.run([sys.executable, "-c", _WORKER, str(job), str(out), str(core)], env=env,
                         capture_output=True, text=True, cwd=str(fsv_parent))
    if res.returncode != 0:
        raise SystemExit(f"tracking worker failed:\n{res.stderr[-2000:]}")
    return json.loads(res.stdout.strip().splitlines()[-1])


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m benchmark.perf.track", description=__doc__.splitlines()[0])
    p.add_argument("--task", default="lift")
    p.add_argument("--duration", type=float, default=4.0)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--baseline", default=None, help="git revision whose fsv tracker runs beside this one")
    p.add_argument("--rounds", type=int, default=2)
    args = p.parse_args(argv)
    if args.rounds < 1:
        p.error(f"--rounds must be >= 1, got {args.rounds}")

    with tempfile.TemporaryDirectory(prefix="fsv-perf-track-") as tmp:
        tmp = pathlib.Path(tmp)
        versions = {"this checkout": ROOT}
        if args.baseline:
            versions[f"baseline {args.baseline}"] = baseline_fsv(args.baseline)
        sc = Scenario(task=args.task, noise_m=0.01, seed=args.seed, duration_s=args.duration)
        ep, render_wall, render_cpu = _timed(lambda: render(simulate(sc)))
        T = len(ep.truth.t)
        init = tracker_init(ep.truth, sc, ep.hand_model)
        seed = int(sc.rng("tracker").integers(2**63))
        job = tmp / "job.pkl"
        with open(job, "wb") as fh:
            pickle.dump((ep.depth, ep.calib, ep.object_model, ep.hand_model, init, seed), fh)
        core = sorted(os.sched_getaffinity(0))[0]
        runs = {name: [] for name in versions}
        for r in range(args.rounds):
            for v, (name, parent) in enumerate(versions.items()):
                out = tmp / f"box-pos-round{r}-version{v}.npy"
                res = run_worker(job, parent, core, out)
                res["box_err_mm"] = float(np.median(np.linalg.norm(np.load(out) - ep.truth.box_pos, axis=1)) * 1e3)
                runs[name].append(res)
        print(f"{args.task}, {T} frames of {ep.depth.depth_m.shape[2]}x{ep.depth.depth_m.shape[1]} depth, seed {args.seed}; "
              f"tracker on CPU core {core}, {args.rounds} round(s), load average {os.getloadavg()[0]:.2f}")
        print(f"{'version':<28}{'frames/s wall':>15}{'frames/s cpu':>14}{'box ms/f':>10}{'hand ms/f':>11}{'box err mm':>12}")
        fps = {}
        for name, rs in runs.items():
            fps[name] = statistics.median(T / r["wall"] for r in rs)
            cpu = statistics.median(T / r["cpu"] for r in rs)
            box = statistics.median(1e3 * r["stages"]["box"] / T for r in rs)
            hand = statistics.median(1e3 * r["stages"]["hand"] / T for r in rs)
            err = statistics.median(r["box_err_mm"] for r in rs)
            print(f"{name:<28}{fps[name]:15.1f}{cpu:14.1f}{box:10.2f}{hand:11.2f}{err:12.2f}")
        new = fps["this checkout"]
        if args.baseline:
            print(f"speed ratio this / baseline: {new / fps[f'baseline {args.baseline}']:.2f}x")
        print(f"target >= {TARGET_FPS:g} frames/s on one core: {'met' if new >= TARGET_FPS else 'NOT met'} ({new:.1f})")
        # The rest of the method, in this process, per frame; the renderer as a peer.
        tracking = track(ep.depth, ep.calib, ep.object_model, ep.hand_model, init, rng=np.random.default_rng(seed))
        kin, k_wall, _ = _timed(lambda: differentiate_poses(tracking.box, AlgebraicConfig()))
        _, f_wall, _ = _timed(lambda: nominal_forces(kin, tracking.contacts, ep.object_model, gravity=ep.truth.gravity))
        print(f"kinematics {1e3 * k_wall / T:.2f} ms/frame, nominal forces {1e3 * f_wall / T:.2f} ms/frame; "
              f"simulate + render with the sensor model (peer) {1e3 * render_wall / T:.1f} ms/frame")
    return 0


if __name__ == "__main__":
    sys.exit(main())
