"""The episode file: an episode's truth, models and rendered depth (quantised) in one archive."""

from __future__ import annotations

import dataclasses
import pathlib
from dataclasses import fields, replace

import numpy as np

from benchmark.archive import read_archive, write_archive
from benchmark.camera.labelling import Annotations
from benchmark.camera.sensor import dequantise
from benchmark.camera.sensor_kernels import quantise_on_grid
from benchmark.errors import BenchmarkError, EpisodeFileError
from benchmark.world.episode import Episode
from benchmark.world.scenario import Scenario
from benchmark.world.truth import Truth
from fsv import Calibration, ColourVideo, DepthVideo, FsvError, HandModel, ObjectModel

# --- Rendered part of an episode in the episode file (depth, calibration, labels) -------------

DEPTH_QUANTA_M = (0.001, 0.0001, 0.01)
"""Depth is stored as uint16 multiples of the first of these quanta that represents it: 1 mm when
the depth already lies on the 1 mm grid (the default sensor's quantisation: stored exactly),
otherwise 0.1 mm (up to 6.5 m), otherwise 1 cm."""


def depth_arrays(episode: Episode) -> dict[str, np.ndarray]:
    """The rendered part of an episode as named arrays for the (compressed) episode file.

    Returns:
        {} before rendering; otherwise ``depth_counts`` (T, H, W) uint16 and ``depth_quantum_m``
        (depth = counts * quantum, 0 = no measurement), ``depth_fps``, ``calib_K`` (3, 3),
        ``calib_T_world_cam`` (4, 4), ``calib_size`` (width, height) and, if rendered with
        labels, ``labels`` (T, H, W) uint8.
    """
    if episode.depth is None:
        return {}
    counts, q = quantise_depth(episode.depth.depth_m)
    out = {
        "depth_counts": counts,
        "depth_quantum_m": np.float64(q),
        "depth_fps": np.float64(episode.depth.fps),
        "calib_K": episode.calib.K,
        "calib_T_world_cam": episode.calib.T_world_cam,
        "calib_size": np.array([episode.calib.width, episode.calib.height], dtype=np.int64),
    }
    if episode.labels is not None:
        out["labels"] = np.asarray(episode.labels, dtype=np.uint8)
    return out


def quantise_depth(depth: np.ndarray) -> tuple:
    """Depth as uint16 counts of the first quantum of :data:`DEPTH_QUANTA_M` that represents it.

    Args:
        depth: Depth images, any shape, [m]; 0 = no measurement.

    Returns:
        ``(counts, quantum_m)``: depth = counts * quantum_m (exactly for depth on the 1 mm grid).

    Raises:
        EpisodeFileError: If the depth does not fit uint16 even at the coarsest quantum.
    """
    if depth.dtype == np.float32:  # the renderer's depth: one pass where it lies on the first grid
        depth = np.ascontiguousarray(depth)
        counts = np.empty(depth.shape, dtype=np.uint16)
        if quantise_on_grid(depth, DEPTH_QUANTA_M[0], counts):
            return counts, DEPTH_QUANTA_M[0]
    top = float(depth.max(initial=0.0))
    for i, q in enumerate(DEPTH_QUANTA_M):
        counts = np.rint(depth.astype(np.float64) / q)
        if counts.max(initial=0) > np.iinfo(np.uint16).max:
            continue
        if i > 0 or np.array_equal(dequantise(counts, q), depth):
            break
    else:
        raise EpisodeFileError(f"depth up to {top:.2f} m does not fit uint16 at a quantum of {DEPTH_QUANTA_M[-1]} m")
    return counts.astype(np.uint16), q


def depth_from_arrays(arrays) -> tuple[DepthVideo | None, Calibration | None, np.ndarray | None]:
    """Inverse of :func:`depth_arrays`: ``(depth, calib, labels)``, all None if not rendered.

    Depth comes back within half a quantum of what was stored (exactly for 1 mm data).
    """
    if "depth_counts" not in arrays:
        return None, None, None
    depth = DepthVideo(
        depth_m=dequantise(arrays["depth_counts"], float(arrays["depth_quantum_m"])), fps=float(arrays["depth_fps"])
    )
    width, height = (int(v) for v in arrays["calib_size"])
    calib = Calibration(K=arrays["calib_K"], T_world_cam=arrays["calib_T_world_cam"], width=width, height=height)
    labels = np.asarray(arrays["labels"], dtype=np.uint8) if "labels" in arrays else None
    return depth, calib, labels


def colour_arrays(episode: Episode) -> dict[str, np.ndarray]:
    """The colour stream of an episode as named arrays: {} when it has none; otherwise ``rgb``
    (T, H, W, 3) uint8 (stored as it is: lossless), ``fps``, ``t_s`` (T,), ``exposure_s``, the
    colour camera's ``calib_K``, ``calib_T_world_cam``, ``calib_size`` and its ``labels`` (T, H, W) uint8."""
    c = episode.colour
    if c is None:
        return {}
    out = {"rgb": c.rgb, "fps": np.float64(c.fps), "t_s": c.t_s, "exposure_s": np.float64(c.exposure_s),
           "calib_K": c.calib.K, "calib_T_world_cam": c.calib.T_world_cam,
           "calib_size": np.array([c.calib.width, c.calib.height], dtype=np.int64)}
    if episode.colour_labels is not None:
        out["labels"] = np.asarray(episode.colour_labels, dtype=np.uint8)
    return out


def colour_from_arrays(arrays) -> tuple:
    """Inverse of :func:`colour_arrays`: ``(ColourVideo, labels or None)``."""
    width, height = (int(v) for v in arrays["calib_size"])
    calib = Calibration(K=arrays["calib_K"], T_world_cam=arrays["calib_T_world_cam"], width=width, height=height)
    colour = ColourVideo(rgb=arrays["rgb"], fps=float(arrays["fps"]), calib=calib, t_s=arrays["t_s"],
                         exposure_s=float(arrays["exposure_s"]))
    labels = np.asarray(arrays["labels"], dtype=np.uint8) if "labels" in arrays else None
    return colour, labels


# --- the episode file -------------------------------------------------------------------------

FORMAT = "fsv-bench-episode"
VERSION = 3
READS = (2, 3)
"""The versions :func:`load_episode` reads: version 2 is version 3 without the colour and annotation sections."""
FORMAT_DOC = """\
An episode file is a NumPy ``.npz`` archive (zip; every entry deflate-compressed but the colour
images ``colour/rgb``, stored as they are; in a file with colour the depth counts and the colour
labels are deflated at level 1) holding only plain arrays (no pickles). Entry ``meta.json`` is a
uint8 array of UTF-8 JSON:

    {"format": "fsv-bench-episode", "version": 3, "scenario": {Scenario fields},
     "sections": [names of the sections present], "<section>": {scalars of that section},
     "array_sha256": {"<section>/<field>": SHA-256 of that array}, "meta_sha256": SHA-256}

Array entries are named ``<section>/<field>``. Sections of version 3:

    truth/*    every array field of benchmark.world.truth.Truth (scalars ``mass`` in the JSON)
    object/*   fsv.ObjectModel arrays (size_m, inertia); mass_kg and frictions in the JSON
    hand/*     fsv.HandModel arrays; segment, joint and finger names in the JSON
    render/*   after rendering only: the arrays of :func:`depth_arrays` (uint16 depth counts and
               their quantum, fps, calibration, labels)
    colour/*   when the colour stream was rendered: the arrays of :func:`colour_arrays` (uint8
               sRGB images stored losslessly, fps, timestamps, exposure, the colour camera's
               calibration and label images); the colour sensor's preset name in the JSON
    annotations/*  after rendering: the per-frame labels of
               :class:`benchmark.camera.annotations.Annotations` (keypoints, BOP box poses,
               contacts in each stream's camera frame)

Version 2 (read too) has no ``colour`` or ``annotations`` section.

``array_sha256`` holds :func:`fsv.digest.array_sha256` of every array entry (over its name, dtype,
shape and bytes) and ``meta_sha256`` is :func:`fsv.digest.tree_sha256` of the JSON without
``meta_sha256``: a reader recomputes both and refuses the file if one differs, or if an array is
missing or not listed. A reader must refuse another format or a version it does not read (version 1 had no digests).
Writers replace the file atomically and use fixed zip timestamps, so the same episode always gives
the same bytes.
"""


def _truth_arrays(truth: Truth) -> tuple[dict, dict]:
    arrays, meta = {}, {}
    for name, value in truth.as_dict().items():
        if value is None:
            continue
        if np.ndim(value) == 0:
            meta[name] = float(value)
        else:
            arrays[name] = np.asarray(value)
    return arrays, meta


def _truth_from(arrays: dict, meta: dict) -> Truth:
    kw = dict(arrays)
    kw["finger_names"] = np.asarray(kw["finger_names"]).astype(str)
    kw.update(meta)
    return Truth(**kw)


_OBJECT_ARRAYS = ("size_m", "inertia")
_HAND_NAMES = ("segment_names", "joint_names", "finger_names")


def model_sections(om: ObjectModel, hm: HandModel) -> dict:
    """The ``object`` and ``hand`` sections of a file: section name -> (arrays, json scalars)."""
    return {
        "object": ({k: np.asarray(getattr(om, k)) for k in _OBJECT_ARRAYS},
                   {"mass_kg": om.mass_kg, "friction": om.friction, "table_friction": om.table_friction}),
        "hand": ({f.name: np.asarray(getattr(hm, f.name)) for f in fields(hm) if f.name not in _HAND_NAMES},
                 {k: list(getattr(hm, k)) for k in _HAND_NAMES}),
    }


def models_from_sections(meta: dict, arrays: dict) -> tuple:
    """Inverse of :func:`model_sections`: ``(ObjectModel, HandModel)`` (raises FsvError/KeyError/TypeError)."""
    o = meta["object"]
    om = ObjectModel(mass_kg=o["mass_kg"], friction=o["friction"], table_friction=o["table_friction"],
                     **arrays["object"])
    return om, HandModel(**arrays["hand"], **meta["hand"])


def _sections(ep: Episode) -> dict:
    """Section name -> (arrays, json scalars) of an episode."""
    out = {"truth": _truth_arrays(ep.truth), **model_sections(ep.object_model, ep.hand_model)}
    rendered = depth_arrays(ep)
    if rendered:
        out["render"] = (rendered, {})
    colour = colour_arrays(ep)
    if colour:
        out["colour"] = (colour, {})
    if ep.annotations is not None:
        out["annotations"] = (ep.annotations.arrays(), {})
    return out


def save_episode(episode: Episode, path, identity: dict | None = None) -> pathlib.Path:
    """Writes an episode file (format: see ``FORMAT_DOC``), replacing ``path`` atomically.

    Args:
        episode: The episode to write.
        path: Destination; ``.npz`` is appended if missing.
        identity: What the file is for (e.g. the cache's suite, version and world fingerprint),
            stored as ``meta["identity"]`` and checked by :func:`load_episode` (``expect``).

    Returns:
        The path written.
    """
    path = pathlib.Path(path)
    if path.suffix != ".npz":
        path = path.with_name(path.name + ".npz")
    sections = _sections(episode)
    meta = {"scenario": dataclasses.asdict(episode.scenario), "sections": list(sections)}
    if identity is not None:
        meta["identity"] = identity
    arrays = {}
    for name, (arrs, scalars) in sections.items():
        meta[name] = scalars
        for k, v in arrs.items():
            arrays[f"{name}/{k}"] = v
    # the colour images stored (deflate would save 41 % of them for seconds of a core); the depth's
    # counts and the colour's labels deflated at the fast level: a 4 s depth episode's file is 2 %
    # larger (7.1 against 7.0 MB) and written in 0.16 s of deflate instead of 0.47 s
    fast = frozenset({"render/depth_counts"} | ({"colour/labels"} if episode.colour is not None else set()))
    return write_archive(path, FORMAT, VERSION, meta, arrays, fast=fast, stored=frozenset({"colour/rgb"}))


def load_episode(path, *, scenario: Scenario | None = None, identity: dict | None = None) -> Episode:
    """Reads an episode file written by :func:`save_episode` and checks its digests.

    Args:
        path: The file.
        scenario: The scenario the file must hold, if known (a renamed or copied file holds another).
        identity: The ``identity`` the file must carry, if any (see :func:`save_episode`).

    Raises:
        EpisodeFileError: If the file is missing, truncated or corrupt (the message names the file
            and, if it can, the damaged array), of another format, or of another version, or holds
            another scenario or identity than expected.
    """
    path = pathlib.Path(path)
    meta, arrays = read_archive(path, FORMAT, READS, kind="episode", error=EpisodeFileError)
    if scenario is not None and meta.get("scenario") != dataclasses.asdict(scenario):
        raise EpisodeFileError(f"{path} holds the episode of scenario {meta.get('scenario')}, not of "
                               f"{dataclasses.asdict(scenario)} (a renamed or copied file)")
    if identity is not None and meta.get("identity") != identity:
        raise EpisodeFileError(f"{path} was written for {meta.get('identity')}, not for {identity} (a renamed or "
                               "copied file)")
    try:
        scenario = Scenario(**meta["scenario"])
        truth = _truth_from(arrays["truth"], meta["truth"])
        om, hm = models_from_sections(meta, arrays)
        ep = Episode(scenario=scenario, truth=truth, object_model=om, hand_model=hm)
        if "render" in meta["sections"]:
            depth, calib, labels = depth_from_arrays(arrays["render"])
            ep = replace(ep, depth=depth, calib=calib, labels=labels)
        if "colour" in meta["sections"]:
            colour, colour_labels = colour_from_arrays(arrays["colour"])
            ep = ep.with_colour(colour, colour_labels)
        if "annotations" in meta["sections"]:
            ep = ep.with_annotations(Annotations.from_arrays(arrays["annotations"]))
    except (KeyError, TypeError, BenchmarkError, FsvError) as e:
        raise EpisodeFileError(f"{path} has missing or inconsistent episode data: {e}") from e
    return ep
