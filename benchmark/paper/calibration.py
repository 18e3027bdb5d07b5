"""``fsv-bench calibrate``: each user's grip, measured once in a calibration recording.

    fsv-bench calibrate --data DIR --out grip_calibration.json

A calibration recording is a dataset made by ``fsv-bench generate`` for that purpose, with seeds no
suite and no training grid uses: the shipped one (``sim_assets/calibration/grip_calibration.json``) is eight
ten-second lifts per user (grasps 0-3, the 0.30 and 0.60 kg box, seed 900), rendered and tracked
like any dataset, with the tactile sensors' readings. For every user in it, the amount of internal
force of its samples (the decomposition of eq. 9 with the sensors' readings: the networks' training
targets) is fitted as a straight line of the load (:func:`fsv.grip.fit_grip`). The benchmark hands
a user's line to every method as ``CameraInput.grip`` (:func:`user_grip`), the way a lab would
measure a new participant once with force sensors before recording them with the camera alone;
training with ``fsv-bench train --grip FILE`` gives every sample its user's line.

The file is JSON: ``{"format": "fsv-bench-grip-calibration", "version": 1, "recording": {the
dataset's generate spec}, "users": {"<index>": {"baseline_n", "gain", "samples"}}, "provenance"}``.
"""

from __future__ import annotations

import argparse
import functools
import importlib.resources
import json
import os

from benchmark.atomic import write_text
from benchmark.errors import BenchmarkError
from fsv.grip import GripCalibration, fit_grip

FORMAT = "fsv-bench-grip-calibration"
VERSION = 1
SHIPPED = "calibration/grip_calibration.json"
"""The benchmark's users' calibration, in ``sim_assets``: a result of ``fsv-bench reproduce``, in a
sub-folder so that it is part of neither the world's nor the results' fingerprint
(:mod:`benchmark.fingerprint`), like the shipped model."""


class CalibrationError(BenchmarkError):
    """A grip-calibration file is missing, damaged or of another format."""


def grip_calibrations(df) -> dict[int, GripCalibration]:
    """Every user's grip line, fitted to a dataset table's samples of that user.

    Args:
        df: A dataset table (:func:`benchmark.paper.dataset.load_dataset`).

    Returns:
        ``{user index: GripCalibration}``.
    """
    from benchmark.paper.dataset import finger_names_of

    names = finger_names_of(df)
    out = {}
    for user, rows in df.groupby("user", sort=True):
        out[int(user)] = fit_grip(rows["p1"].to_numpy(float), rows[[f"f_int_{n}" for n in names]].to_numpy(float),
                                  rows[[f"active_{n}" for n in names]].to_numpy(bool))
    return out


def write_calibration(path, calibrations: dict, recording: dict) -> None:
    """Writes ``{user: GripCalibration}`` as a grip-calibration file (atomically), with provenance."""
    from fsv.provenance import provenance

    doc = {"format": FORMAT, "version": VERSION, "recording": recording,
           "users": {str(u): {"baseline_n": c.baseline_n, "gain": c.gain, "samples": c.samples}
                     for u, c in sorted(calibrations.items())},
           "provenance": provenance()}
    write_text(path, json.dumps(doc, indent=1, allow_nan=False) + "\n")


def read_calibration(path=None) -> dict[int, GripCalibration]:
    """The ``{user: GripCalibration}`` of a grip-calibration file (default: the shipped one).

    Raises:
        CalibrationError: If the file is missing, not JSON, or not a grip-calibration file of this version.
    """
    if path is None:
        return dict(_shipped())
    return _read(os.fspath(path), None)


@functools.lru_cache(maxsize=1)
def _shipped() -> tuple:
    text = importlib.resources.files("sim_assets").joinpath(SHIPPED).read_text()
    return tuple(_read(f"sim_assets/{SHIPPED}", text).items())


def _read(path: str, text) -> dict[int, GripCalibration]:
    from fsv.errors import FsvError

    try:
        if text is None:
            with open(path) as fh:
                text = fh.read()
        doc = json.loads(text)
    except (OSError, ValueError) as e:
        raise CalibrationError(f"{path} is not a readable grip-calibration file: {e}") from e
    if not isinstance(doc, dict) or doc.get("format") != FORMAT or doc.get("version") != VERSION:
        raise CalibrationError(f"{path} is not an {FORMAT} file of version {VERSION}")
    try:
        return {int(u): GripCalibration(baseline_n=c["baseline_n"], gain=c["gain"], samples=c["samples"])
                for u, c in doc["users"].items()}
    except (KeyError, TypeError, ValueError, AttributeError, FsvError) as e:
        raise CalibrationError(f"{path} has inconsistent grip-calibration data: {e}") from e


def user_grip(user: int) -> GripCalibration | None:
    """The shipped calibration of a benchmark user, or None if it has none."""
    return dict(_shipped()).get(int(user))


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--data", required=True, help="the calibration recording: a dataset folder made by `fsv-bench generate`")
    p.add_argument("--out", required=True, help="grip-calibration file to write (.json)")


def run(args: argparse.Namespace) -> dict:
    from benchmark.paper.dataset import MAX_EXCESS_N, load_dataset

    df = load_dataset(args.data, max_excess_n=MAX_EXCESS_N)
    with open(os.path.join(args.data, "dataset.json")) as fh:
        recording = json.load(fh)["spec"]
    calibrations = grip_calibrations(df)
    write_calibration(args.out, calibrations, recording)
    for u, c in sorted(calibrations.items()):
        print(f"user {u}: {c.baseline_n:.2f} N + {c.gain:.3f} N per N of load ({c.samples} samples)")
    print(f"saved {args.out}")
    return calibrations
