"""Run a method on exported camera-input files and write its estimates files: the file protocol in Python.

    fsv-bench export --suite smoke --out runs/smoke-inputs
    python examples/estimates_from_files.py runs/smoke-inputs runs/smoke-estimates [--differentiator central]
    fsv-bench score --suite smoke --estimates runs/smoke-estimates --out runs/smoke-scores

A method in another language does the same: read each ``<episode>.npz`` listed in ``suite.json``
(format in docs/formats.md), write ``<episode>.npz`` estimates with the arrays the format lists.
"""

from __future__ import annotations

import argparse
import json
import pathlib
import sys

from benchmark.exchange import load_camera_input, rng_generator, save_estimate
from benchmark.method import MethodSpec, method_label


def write_estimates(inputs_dir, out_dir, method, label: str) -> list:
    """Runs ``method`` (an ``fsv.method.Method``) on every camera-input file; returns the files written."""

    inputs_dir, out_dir = pathlib.Path(inputs_dir), pathlib.Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    written = []
    for ep in json.loads((inputs_dir / "suite.json").read_text())["episodes"]:
        inputs, meta = load_camera_input(inputs_dir / ep["file"])
        estimate = method(inputs, rng_generator(meta))
        written.append(save_estimate(estimate, out_dir / ep["file"], episode=ep["episode"], method=label,
                                     knowledge=meta.get("knowledge", {}).get("knowledge")))
    return written


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("inputs", help="folder written by fsv-bench export")
    p.add_argument("out", help="folder for the estimates files")
    p.add_argument("--differentiator", default=None, help="algebraic, central, gaussian or module:attribute")
    args = p.parse_args(argv)
    spec = MethodSpec(differentiator=args.differentiator)
    files = write_estimates(args.inputs, args.out, spec.build(), method_label(spec))
    print(f"{len(files)} estimates files in {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
