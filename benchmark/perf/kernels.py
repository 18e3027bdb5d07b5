"""Headline figures side by side under several OpenBLAS kernels, with their spread.

    python -m benchmark.perf.kernels [--kernels Haswell,Sandybridge,Nehalem,Prescott] [--suite smoke] [--out DIR]

Runs the main command (``fsv-bench --task lift --noise 0.01``) and ``fsv-bench eval --suite S``
once per kernel, each in its own process with ``OPENBLAS_CORETYPE`` set (OpenBLAS reads it when it
loads), and prints every headline figure per kernel, the spread (largest minus smallest) and, for
the suite's aggregates, the width of their 95 % confidence interval. The kernels must be ones the
CPU can run (an AVX2 machine runs all four defaults).
"""

from __future__ import annotations

import argparse
import json
import os
import pathlib
import subprocess
import sys
import tempfile

from benchmark.suites import get_suite

KERNELS = ("Haswell", "Sandybridge", "Nehalem", "Prescott")

MAIN_FIGURES = {
    "tracking.box_pos_err_mm": "box position error, median [mm]",
    "tracking.contact_err_mm_mean": "contact error mean [mm]",
    "tracking.contact_err_mm_std": "contact error std [mm]",
    "tracking.contact_recall": "contact recall",
    "tracking.contact_precision": "contact precision",
    "kinematics.algebraic.acc_std": "acc. error std, algebraic [m/s^2]",
    "forces.net_force_err_n_rms": "net force error RMS [N]",
    "forces.solver_failures": "least-violation frames",
    "learning.rel_err_pct_mean": "learned forces, rel. error [%]",
}


def _get(d: dict, dotted: str):
    for k in dotted.split("."):
        d = d[k]
    return d


def _run(kernel: str, argv: list) -> None:
    env = dict(os.environ, OPENBLAS_CORETYPE=kernel)
    subprocess.run([sys.executable, "-m", "benchmark.commands.cli", *argv], env=env, check=True, stdout=subprocess.DEVNULL)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m benchmark.perf.kernels", description=__doc__.strip().splitlines()[0])
    p.add_argument("--kernels", default=",".join(KERNELS), help="comma-separated OPENBLAS_CORETYPE values")
    p.add_argument("--suite", default="smoke", help="suite whose aggregates are compared (default smoke)")
    p.add_argument("--out", default=None, help="keep the runs here (default: a temporary folder)")
    args = p.parse_args(argv)
    kernels = [k.strip() for k in args.kernels.split(",") if k.strip()]

    get_suite(args.suite)
    out = pathlib.Path(args.out or tempfile.mkdtemp(prefix="fsv-kernels-"))
    main_runs, suite_runs = {}, {}
    for k in kernels:
        _run(k, ["--task", "lift", "--noise", "0.01", "--no-gif", "--quiet", "--out", str(out / f"main-{k}")])
        main_runs[k] = json.loads((out / f"main-{k}" / "summary.json").read_text())
        _run(k, ["eval", "--suite", args.suite, "--quiet", "--out", str(out / f"{args.suite}-{k}")])
        suite_runs[k] = json.loads((out / f"{args.suite}-{k}" / "scores.json").read_text())
        print(f"{k}: {main_runs[k]['provenance']['blas']}", file=sys.stderr)
    head = f"| figure | {' | '.join(kernels)} | spread |"
    print(f"## fsv-bench --task lift --noise 0.01\n\n{head}\n|---|{'---|' * (len(kernels) + 1)}")
    for key, label in MAIN_FIGURES.items():
        v = [float(_get(main_runs[k], key)) for k in kernels]
        print(f"| {label} | {' | '.join(f'{x:.6g}' for x in v)} | {max(v) - min(v):.2g} |")
    print(f"\n## {args.suite}: medians over the suite's episodes\n\n| metric | {' | '.join(kernels)} | spread | 95 % CI width |")
    print(f"|---|{'---|' * (len(kernels) + 2)}")
    first = suite_runs[kernels[0]]
    for m in first["metrics"]:
        vals = [suite_runs[k]["aggregate"][m]["median"]["value"] for k in kernels]
        if any(v is None for v in vals):
            continue
        a = first["aggregate"][m]["median"]
        print(f"| {m} | {' | '.join(f'{x:.6g}' for x in vals)} | {max(vals) - min(vals):.2g} | "
              f"{a['ci_high'] - a['ci_low']:.3g} |")
    print(f"\nruns kept in {out}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
