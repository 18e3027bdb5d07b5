"""``fsv-bench calibrate``: each user's grip, measured once in a calibration recording.

    fsv-bench calibrate --data DIR --out grip_calibration.json

A calibration recording is a dataset made by ``fsv-bench generate`` for that purpose, with seeds no
suite and no training grid uses: the shipped one (``sim_assets/calibration/grip_calibration.json``) is eight
ten-second lifts per user (grasps 0-3, the 0.30 and 0.60 kg box, seed 900), rendered and tracked
like any dataset, with the tactile sensors' readings. For every user in it, the amount of internal
force of its samples (the decomposition of eq. 9 with the sensors' readings: the networks' training
targets) is fitted as a straight line of the load (:func:`fsv.grip.fit_grip`). The benchmark hands
a user's line to every method as ``CameraInput.grip`` (:func:`benchmark.method.grip_file.user_grip`), the way a lab would
measure a new participant once with force sensors before recording them with the camera alone;
training with ``fsv-bench train --grip FILE`` gives every sample its user's line.

The file's format, its reader and writer are :mod:`benchmark.method.grip_file`.
"""

from __future__ import annotations

import argparse

from benchmark.atomic import OUT_AS_IT_WAS, check_file_out
from benchmark.errors import DatasetError
from benchmark.method.grip_file import write_calibration
from benchmark.scores.samples import MAX_EXCESS_N
from fsv.grip import GripCalibration, fit_grip

INTERRUPTED = OUT_AS_IT_WAS
"""What Ctrl-C leaves, as the interrupted command says it (`fsv-bench <sub-command>: interrupted; ...`)."""


def grip_calibrations(df) -> dict[int, GripCalibration]:
    """Every user's grip line, fitted to a dataset table's samples of that user.

    Args:
        df: A dataset table (:func:`benchmark.paper.dataset.load_dataset`).

    Returns:
        ``{user index: GripCalibration}``.
    """
    from benchmark.paper.dataset import finger_names_of  # lazy: pandas (0.3 s) off `fsv-bench calibrate`'s start-up

    names = finger_names_of(df)
    out = {}
    for user, rows in df.groupby("user", sort=True):
        out[int(user)] = fit_grip(rows["p1"].to_numpy(float), rows[[f"f_int_{n}" for n in names]].to_numpy(float),
                                  rows[[f"active_{n}" for n in names]].to_numpy(bool))
    return out


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--data", required=True, action="append",
                   help="a calibration recording: a dataset folder made by `fsv-bench generate` (repeat for several; "
                        "no person in two)")
    p.add_argument("--out", required=True, help="grip-calibration file to write (.json); an existing file needs --force")
    p.add_argument("--force", action="store_true", help="replace --out if it exists (without it an existing file is refused)")


def run(args: argparse.Namespace) -> dict:
    from benchmark.paper.dataset import load_dataset  # lazy: pandas (0.3 s) off `fsv-bench calibrate`'s start-up
    from benchmark.paper.dataset.files import read_header  # lazy: pandas (0.3 s) off `fsv-bench calibrate`'s start-up

    check_file_out(args.out, force=args.force)
    recordings = [read_header(d)["spec"] for d in args.data]  # every header checked before any work
    calibrations = {}
    for folder in args.data:
        found = grip_calibrations(load_dataset(folder, max_excess_n=MAX_EXCESS_N))
        twice = sorted(set(found) & set(calibrations))
        if twice:
            raise DatasetError(f"--data {folder}: user {twice[0]} is also in an earlier recording; accepted: "
                               f"recordings of different people")
        calibrations.update(found)
    write_calibration(args.out, calibrations, recordings[0] if len(recordings) == 1 else recordings)
    for u, c in sorted(calibrations.items()):
        print(f"user {u}: {c.baseline_n:.2f} N + {c.gain:.3f} N per N of load ({c.samples} samples)")
    print(f"saved {args.out}")
    return calibrations
