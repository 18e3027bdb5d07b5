"""The grip-calibration file: each user's grip line, as the method adapter hands it to a method.

The file is JSON: ``{"format": "fsv-bench-grip-calibration", "version": 1, "recording": {the
dataset's generate spec} (a list of them when several recordings made it), "users": {"<index>": {"baseline_n", "gain", "samples"}}, "provenance"}``.
It is made by ``fsv-bench calibrate`` (:mod:`benchmark.paper.calibration`).
"""

from __future__ import annotations

import functools
import importlib.resources
import json
import os

from benchmark.atomic import write_text
from benchmark.errors import BenchmarkError
from fsv.errors import FsvError
from fsv.grip import GripCalibration
from fsv.provenance import provenance

FORMAT = "fsv-bench-grip-calibration"
VERSION = 1
SHIPPED = "calibration/grip_calibration.json"
"""The benchmark's users' calibration, in ``sim_assets``: a result of ``fsv-bench reproduce``, in a
sub-folder so that it is part of neither the world's nor the results' fingerprint
(:mod:`benchmark.fingerprint`), like the shipped model."""


class CalibrationError(BenchmarkError):
    """A grip-calibration file is missing, damaged or of another format."""


def write_calibration(path, calibrations: dict, recording) -> None:
    """Writes ``{user: GripCalibration}`` as a grip-calibration file (atomically), with provenance."""
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


def calibrated_users() -> str:
    """The people of the shipped calibration, in short ranges (e.g. "0-4, 100-147, 500-547")."""
    users = sorted(dict(_shipped()))
    runs, start = [], None
    for i, u in enumerate(users):
        if start is None:
            start = u
        if i + 1 == len(users) or users[i + 1] != u + 1:
            runs.append(str(start) if start == u else f"{start}-{u}")
            start = None
    return ", ".join(runs) or "none"
