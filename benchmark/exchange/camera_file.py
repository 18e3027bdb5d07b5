"""The camera-input file: one episode's inputs for a method in any language, and no truth.

FORMAT_DOC is the specification (also in docs/formats.md).
"""

from __future__ import annotations

import pathlib

import numpy as np

from benchmark.archive import read_archive, write_archive
from benchmark.errors import BenchmarkError
from benchmark.fingerprint import world_fingerprint
from fsv import FsvError
from fsv.grip import GripCalibration
from fsv.method import CameraInput
from fsv.track.tracker import TrackInit

FORMAT = "fsv-bench-camera"
VERSION = 2
READS = (1, 2)
"""The versions :func:`load_camera_input` reads: version 1 is version 2 with the depth stream only."""
FORMAT_DOC = """\
A camera-input file is a sealed NumPy ``.npz`` archive (:mod:`benchmark.archive`): arrays named
``<section>/<field>`` and a ``meta.json`` entry (uint8 array of UTF-8 JSON). Units SI; world frame
with the table top at z = 0 and z up; rotations are 3x3 matrices (world_R_object).

    camera/depth_counts       (T, H, W) uint16   depth along the optical axis = counts * quantum; 0 = none
    camera/depth_quantum_m    ()        float64  metres per count
    camera/depth_fps          ()        float64  frame k is taken at t_k = k / fps
    camera/calib_K            (3, 3)    float64  OpenCV intrinsics [[fx, 0, cx], [0, fy, cy], [0, 0, 1]]
    camera/calib_T_world_cam  (4, 4)    float64  camera pose in the world (OpenCV camera frame: x right, y down, z forward)
    camera/calib_size         (2,)      int64    width, height
    colour/rgb                (T, H, W, 3) uint8 the colour stream, if recorded (``--streams depth,colour`` or a
                                        method that reads it): sRGB-encoded images, row 0 at the top, R, G, B
    colour/fps                ()        float64  its frame rate
    colour/t_s                (T,)      float64  each frame's timestamp (the middle of its exposure), [s]
    colour/exposure_s         ()        float64  its exposure time, [s]
    colour/calib_K            (3, 3)    float64  the colour camera's own intrinsics (OpenCV, zero distortion)
    colour/calib_T_world_cam  (4, 4)    float64  the colour camera's pose in the world
    colour/calib_size         (2,)      int64    its width, height
    init/box_pos              (3,)      float64  first-frame box centre (coarse), [m]
    init/box_rot              (3, 3)    float64  first-frame world_R_box (coarse)
    init/palm_pos             (3,)      float64  first-frame palm origin (coarse), [m]
    init/palm_rot             (3, 3)    float64  first-frame world_R_palm (coarse)
    init/joints               (n,)      float64  first-frame hinge angles in hand joint order, [rad]
    init/gravity              (3,)      float64  gravity in the world, [m/s^2]
    object/size_m             (3,)      float64  box edge lengths along its x, y, z axes, [m]
    object/inertia            (3, 3)    float64  inertia about the centre of mass, box frame, [kg m^2]
    hand/*                              the known hand (fsv.HandModel fields: segment tree, joint axes
                                        and ranges, capsules, fingertip pads)
    grip/baseline_n           ()        float64  the user's grip calibration (fsv.grip.GripCalibration),
    grip/gain                 ()        float64  measured in a recording of their own with force sensors;
    grip/samples              ()        int64    absent if the user has none

``meta.json``: ``{"format": "fsv-bench-camera", "version": 2, "episode": NAME, "suite": {"name",
"version"}, "world": the world's fingerprint, "frames": T, "streams": ["depth"] or ["depth", "colour"], "object": {"mass_kg", "friction", "table_friction"}, "hand":
{"segment_names", "joint_names", "finger_names"}, "rng_seed": [ints], "array_sha256": {...},
"meta_sha256": ...}``. ``rng_seed`` is the entropy of the generator the benchmark hands an in-process
method (``numpy.random.default_rng(numpy.random.SeedSequence(rng_seed))``); a method that uses it
reproduces its in-process estimates from files. Nothing in the file is truth beyond the coarse,
perturbed first-frame initialisation. Version 1 (still read) had no ``colour`` section and no
``streams`` entry. The camera streams are described once, for every file, in docs/camera.md.
"""


class CameraFileError(BenchmarkError, ValueError):
    """A camera-input file is missing, damaged or of another format."""


def save_camera_input(inputs, path, *, episode: str, suite, rng_seed: list, knowledge: dict | None = None) -> pathlib.Path:
    """Writes a method's camera inputs (an ``fsv.method.CameraInput``) as a camera-input file.

    Args:
        inputs: The camera inputs.
        path: Destination ``.npz``.
        episode: The episode's name in its suite.
        suite: The ``benchmark.suites.Suite`` it belongs to.
        rng_seed: Entropy of the generator an in-process method gets (see ``FORMAT_DOC``).
        knowledge: What the method was told and how precisely
            (``benchmark.method.knowledge.Knowledge.given_record``: no truth), stored in the meta.
    """
    from benchmark.camera.episode_file import (  # lazy: MuJoCo (0.25 s) off `fsv-bench export`'s start-up
        model_sections,
        quantise_depth,
    )

    counts, q = quantise_depth(inputs.depth.depth_m)
    c = inputs.calib
    arrays = {"camera/depth_counts": counts, "camera/depth_quantum_m": np.float64(q),
              "camera/depth_fps": np.float64(inputs.depth.fps), "camera/calib_K": c.K,
              "camera/calib_T_world_cam": c.T_world_cam,
              "camera/calib_size": np.array([c.width, c.height], dtype=np.int64)}
    i = inputs.init
    arrays.update({"init/box_pos": i.box_pos, "init/box_rot": i.box_rot, "init/palm_pos": i.palm_pos,
                   "init/palm_rot": i.palm_rot, "init/joints": i.joints, "init/gravity": inputs.gravity})
    if inputs.colour is not None:
        co = inputs.colour
        arrays.update({"colour/rgb": co.rgb, "colour/fps": np.float64(co.fps), "colour/t_s": co.t_s,
                       "colour/exposure_s": np.float64(co.exposure_s), "colour/calib_K": co.calib.K,
                       "colour/calib_T_world_cam": co.calib.T_world_cam,
                       "colour/calib_size": np.array([co.calib.width, co.calib.height], dtype=np.int64)})

    meta = {"episode": episode, "suite": {"name": suite.name, "version": suite.version}, "world": world_fingerprint(),
            "frames": inputs.num_frames, "streams": list(inputs.streams), "rng_seed": [int(v) for v in rng_seed]}
    if knowledge is not None:
        meta["knowledge"] = knowledge
    if inputs.grip is not None:
        arrays.update({"grip/baseline_n": np.float64(inputs.grip.baseline_n), "grip/gain": np.float64(inputs.grip.gain),
                       "grip/samples": np.int64(inputs.grip.samples)})
    for name, (arrs, scalars) in model_sections(inputs.object_model, inputs.hand_model).items():
        meta[name] = scalars
        arrays.update({f"{name}/{k}": v for k, v in arrs.items()})
    return write_archive(path, FORMAT, VERSION, meta, arrays, fast=frozenset({"colour/rgb"}))


def load_camera_input(path) -> tuple:
    """Reads a camera-input file.

    Returns:
        ``(inputs, meta)``: the ``fsv.method.CameraInput`` and the file's JSON.

    Raises:
        CameraFileError: If it is missing, damaged, or of another format or version.
    """
    from benchmark.camera.episode_file import (  # lazy: MuJoCo (0.25 s) off `fsv-bench export`'s start-up
        colour_from_arrays,
        depth_from_arrays,
        models_from_sections,
    )

    meta, s = read_archive(path, FORMAT, READS, kind="camera-input", error=CameraFileError)
    try:
        depth, calib, _ = depth_from_arrays(s["camera"])
        om, hm = models_from_sections(meta, s)
        i = s["init"]
        init = TrackInit(box_pos=i["box_pos"], box_rot=i["box_rot"], palm_pos=i["palm_pos"], palm_rot=i["palm_rot"],
                         joints=i["joints"])
        g = s.get("grip")
        grip = None if g is None else GripCalibration(baseline_n=float(g["baseline_n"]), gain=float(g["gain"]),
                                                      samples=int(g["samples"]))
        colour = colour_from_arrays(s["colour"])[0] if "colour" in s else None
        inputs = CameraInput(depth=depth, calib=calib, object_model=om, hand_model=hm, init=init, gravity=i["gravity"],
                             grip=grip, colour=colour)
    except (KeyError, TypeError, FsvError, BenchmarkError) as e:
        raise CameraFileError(f"{path} has missing or inconsistent camera-input data: {e}") from e
    return inputs, meta


def rng_generator(meta: dict) -> np.random.Generator:
    """The generator an in-process method would get for this file's episode."""
    return np.random.default_rng(np.random.SeedSequence(meta["rng_seed"]))
