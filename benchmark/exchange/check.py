"""``fsv-bench check``: is an estimates file one that ``fsv-bench score`` will accept, and if not, why.

    fsv-bench check FILE [--inputs CAMERA_FILE]

Reads the file as ``fsv-bench score`` does: its container, format and version, the shapes of its
arrays, and their physics (:func:`benchmark.exchange.estimates_file.check_physics`). With
``--inputs`` (the episode's camera-input file from ``fsv-bench export``) also the frames, the
fingers and the identity (episode, suite, world) against that episode. Exit 0 and one line when it
is good; exit 2 and one line naming the array, the frame or the entry when it is not.

    fsv-bench check DIR

Given a folder, checks a frames dataset of ``fsv-bench generate --frames``
(:func:`benchmark.paper.dataset.frames.check_frames`): the index's digest, every shard's bytes
and content digests, and that the card and the Croissant file are there.
"""

from __future__ import annotations

import argparse
import pathlib

import numpy as np

from benchmark.exchange.camera_file import load_camera_input
from benchmark.exchange.estimates_file import EstimatesFileError, check_identity, load_estimate, read_estimates
from benchmark.fingerprint import world_fingerprint

INTERRUPTED = "nothing was written"
"""What Ctrl-C leaves, as the interrupted command says it (`fsv-bench <sub-command>: interrupted; ...`)."""


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("file", type=pathlib.Path, help="an estimates file (.npz), or a frames dataset's folder")
    p.add_argument("--inputs", type=pathlib.Path, default=None,
                   help="the episode's camera-input file (fsv-bench export): frames, fingers and identity checked too")


def check(path: pathlib.Path, inputs: pathlib.Path | None = None) -> str:
    """Checks an estimates file; returns a one-line description (raises EstimatesFileError, CameraFileError)."""

    meta, arrays = read_estimates(path)
    if inputs is not None:
        camera, cmeta = load_camera_input(inputs)
        suite = argparse.Namespace(**cmeta["suite"])
        check_identity(path, meta, episode=cmeta["episode"], suite=suite, world=world_fingerprint(),
                       knowledge=cmeta.get("knowledge", {}).get("knowledge"))
        T, fps, names = camera.num_frames, camera.depth.fps, tuple(camera.hand_model.finger_names)
    else:
        pos = arrays.get("box", {}).get("pos")
        if pos is None:
            raise EstimatesFileError(f"{path}: required array box/pos is missing")
        T, fps, names = len(pos), 30.0, tuple(meta.get("finger_names") or ())
    estimate = load_estimate(path, t=np.arange(T) / fps, finger_names=names)
    groups = [g for g, s in (("nominal", estimate.nominal), ("forces", estimate.forces)) if s is not None]
    return (f"{path}: ok: episode {meta.get('episode')!r}, {T} frames, {len(names)} fingers, forces: "
            f"{', '.join(groups) or 'none'}"
            + (f"; matches {inputs} (streams: {', '.join(camera.streams)})" if inputs is not None else ""))


def run(args: argparse.Namespace) -> str:
    if args.file.is_dir():
        from benchmark.paper.dataset.frames import check_frames  # lazy: pandas (0.3 s) off `fsv-bench check`'s start-up

        line = check_frames(args.file)
        print(line)
        return line
    line = check(args.file, args.inputs)
    print(line)
    return line
