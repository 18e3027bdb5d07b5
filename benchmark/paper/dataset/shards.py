"""One episode's frames and labels in one HDF5 file: a shard of a frames dataset (``fsv-bench generate --frames``).

Why HDF5 (h5py) rather than npz: a shard is read in windows of a few frames (the training
``Dataset``, :mod:`benchmark.paper.dataset.windows`), and HDF5 compresses each chunk on its own, so a
window decompresses only its frames (one chunk per image), where an npz member is decompressed whole.
HDF5 is also self-describing (groups, attributes, units) and read by every language; and with
h5py's defaults (no timestamps) the same episode gives the same bytes, so a local pool and a Ray
cluster write identical files.

Layout of ``episodes/<episode>.h5`` (T frames, K fingers thumb first, 21 keypoints in OpenPose
order; world frame unless named; object frame: the box's edges, origin at its centre of mass;
camera frames: OpenCV, docs/camera.md)::

    /                  attrs: format, version, episode, status, scenario (JSON), split, fps,
                       finger_names (JSON), streams (JSON), gravity, object_model (JSON),
                       content_sha256 (the digest of everything else in the file)
    /labels/t                         (T,) float64 [s]
    /labels/contact_active            (T, K) bool: finger k touches the box
    /labels/contact_sliding           (T, K) bool
    /labels/contact_force_{world,object}   (T, K, 3) float64 [N]: finger k's force on the box
    /labels/contact_point_{world,object}   (T, K, 3) float64 [m]: its centre of pressure
    /labels/contact_normal_{world,object}  (T, K, 3) float64: unit normal into the box
    /labels/box_pos (T, 3) [m], box_quat (T, 4) (w, x, y, z), box_rot (T, 3, 3) world_R_object,
           box_vel (T, 3) [m/s], box_omega (T, 3) [rad/s], box_acc (T, 3) [m/s^2],
           box_alpha (T, 3) [rad/s^2]
    /labels/hand_qpos (T, n) [rad], keypoints_world (T, 21, 3) [m], fingertip_pos (T, K, 3) [m],
           env_force (T, 3) [N], env_torque (T, 3) [N m] (the table on the box)
    /<stream>/frames    depth: (T, H, W) uint16 [mm] (the sensor's 1 mm steps, lossless; float32 [m]
                        if a sensor's depth is not on the grid; attr ``encoding``); colour: (T, H, W, 3)
                        uint8 sRGB ("raw") or (T,) JPEG bytes ("jpeg", lossy)
    /<stream>/labels    (T, H, W) uint8 label image: 0 none, 1 table, 2 box, 9 palm, 10 + k finger k
    /<stream>/K (3, 3), T_world_cam (4, 4), t_s (T,) [s]; attrs width, height, exposure_s (colour)
    /<stream>/keypoints_uv (T, 21, 2) [px], keypoints_z (T, 21) [m], keypoint_visibility (T, 21) uint8,
             cam_R_m2c (T, 3, 3), cam_t_m2c (T, 3) [mm] (BOP), contact_point_cam (T, K, 3) [m],
             contact_normal_cam (T, K, 3), contact_force_cam (T, K, 3) [N]
    /privileged         attrs person (JSON: ``benchmark.world.people.person_record``) and grasp
                        (JSON: ``benchmark.world.grasp_plan.grasp_spec``): who squeezes and how;
                        no method is handed them, a network trained on them cheats

Images are chunked one frame per chunk, gzip level 4 with the byte shuffle; the label arrays gzip too.
"""

from __future__ import annotations

import hashlib
import io
import json
import os
from dataclasses import asdict

import numpy as np

from benchmark.errors import DatasetError, DatasetFileError
from benchmark.world.scenario import episode_name

SHARD_FORMAT = "fsv-bench-frames-shard"
SHARD_VERSION = 1
COLOUR_ENCODINGS = ("raw", "jpeg")
"""How the colour frames are stored: "raw" (uint8, gzip: lossless) or "jpeg" (per frame, Pillow,
quality :data:`JPEG_QUALITY`, 4:2:0 chroma: lossy, about 14x smaller; for training data only)."""
JPEG_QUALITY = 90
"""JPEG quality of ``--colour-encoding jpeg`` (a choice: libjpeg's usual "high quality" setting)."""
DEPTH_STEP_M = 0.001
"""The depth is stored in steps of this many metres when every value lies on that grid (the sensor
presets quantise to 1 mm)."""
GZIP_LEVEL = 4
"""gzip level of every array (a choice: level 9 gains ~3 % on depth for twice the time)."""
_STREAM_LABELS = ("keypoints_uv", "keypoints_z", "keypoint_visibility", "cam_R_m2c", "cam_t_m2c", "contact_point_cam",
                  "contact_normal_cam", "contact_force_cam")


def check_colour_encoding(name: str) -> str:
    """``name`` if it is one of :data:`COLOUR_ENCODINGS`; DatasetError naming it otherwise."""
    if name not in COLOUR_ENCODINGS:
        raise DatasetError(f"colour encoding {name!r}: accepted: {', '.join(COLOUR_ENCODINGS)}")
    return name


def label_arrays(episode) -> dict:
    """The world- and object-frame labels of an episode: ``{name: array}`` (see the module docstring)."""
    from benchmark.camera.annotations import (  # lazy: MuJoCo (0.25 s) off `fsv-bench generate`'s start-up
        _quat_rot,
        _rotate,
    )

    tr = episode.truth
    R = _quat_rot(tr.box_quat)  # (T, 3, 3) world_R_object, fixed-order arithmetic
    M = R[:, None]
    point_obj = np.asarray(tr.contact_point, np.float64)
    p = _rotate(M, point_obj)
    point_world = np.empty(p.shape)
    for i in range(3):
        point_world[..., i] = p[..., i] + np.asarray(tr.box_pos, np.float64)[:, None, i]
    out = {
        "t": np.asarray(tr.t, np.float64),
        "contact_active": np.asarray(tr.contact_active, bool), "contact_sliding": np.asarray(tr.contact_sliding, bool),
        "contact_force_object": np.asarray(tr.contact_force, np.float64),
        "contact_force_world": _rotate(M, np.asarray(tr.contact_force, np.float64)),
        "contact_point_object": point_obj, "contact_point_world": point_world,
        "contact_normal_object": np.asarray(tr.contact_normal, np.float64),
        "contact_normal_world": _rotate(M, np.asarray(tr.contact_normal, np.float64)),
        "box_pos": tr.box_pos, "box_quat": tr.box_quat, "box_rot": R, "box_vel": tr.box_vel, "box_omega": tr.box_omega,
        "box_acc": tr.box_acc, "box_alpha": tr.box_alpha, "hand_qpos": tr.hand_qpos, "fingertip_pos": tr.fingertip_pos,
        "env_force": tr.env_force, "env_torque": tr.env_torque,
    }
    if episode.annotations is not None:
        out["keypoints_world"] = episode.annotations.keypoints_world
    if tr.held is not None:
        out["held"] = np.asarray(tr.held, bool)
    return {k: np.asarray(v) for k, v in out.items()}


def _depth_encoding(depth_m: np.ndarray) -> tuple:
    """``(stored array, encoding)``: uint16 millimetres when that is lossless, else float32 metres."""
    d = np.asarray(depth_m, np.float32)
    if np.all(np.isfinite(d)) and d.min(initial=0.0) >= 0 and d.max(initial=0.0) < 65.0:
        mm = np.round(d.astype(np.float64) / DEPTH_STEP_M).astype(np.uint16)
        if np.array_equal(decode_depth(mm, "uint16-mm"), d):
            return mm, "uint16-mm"
    return d, "float32-m"


def decode_depth(stored: np.ndarray, encoding: str) -> np.ndarray:
    """Depth in metres, float32, from a shard's stored depth (``encoding``: the dataset's attr)."""
    if encoding == "uint16-mm":
        return (stored.astype(np.float64) * DEPTH_STEP_M).astype(np.float32)
    return np.asarray(stored, np.float32)


def _encode_jpeg(rgb: np.ndarray) -> np.ndarray:
    from PIL import Image  # lazy: PIL (10 ms) off `fsv-bench generate`'s start-up

    buf = io.BytesIO()
    Image.fromarray(rgb).save(buf, "JPEG", quality=JPEG_QUALITY)
    return np.frombuffer(buf.getvalue(), np.uint8)


def decode_colour(ds, start: int = 0, stop: int | None = None) -> np.ndarray:
    """Frames ``[start, stop)`` of a shard's ``colour/frames`` dataset as (n, H, W, 3) uint8."""
    stop = ds.shape[0] if stop is None else stop
    if ds.attrs["encoding"] == "raw":
        return ds[start:stop]
    from PIL import Image  # lazy: PIL (10 ms) off `fsv-bench generate`'s start-up

    return np.stack([np.asarray(Image.open(io.BytesIO(ds[k].tobytes())).convert("RGB")) for k in range(start, stop)])


def _images(group, name: str, data: np.ndarray, written: dict, **attrs):
    """A dataset of frames, one chunk a frame; ``written[its name] = data`` (:func:`content_sha256`)."""
    ds = group.create_dataset(name, data=data, chunks=(1,) + data.shape[1:], compression="gzip",
                              compression_opts=GZIP_LEVEL, shuffle=data.dtype.itemsize > 1)
    ds.attrs.update(attrs)
    written[ds.name] = data
    return ds


def _array(group, name: str, data: np.ndarray):
    data = np.asarray(data)
    if data.size == 0 or data.ndim == 0:
        return group.create_dataset(name, data=data)
    return group.create_dataset(name, data=data, compression="gzip", compression_opts=GZIP_LEVEL, shuffle=True)


def write_shard(episode, *, streams: tuple = ("depth",), colour_encoding: str = "raw", split: str | None = None,
                privileged: dict | None = None) -> bytes:
    """The bytes of one rendered episode's shard (the module docstring's layout).

    Args:
        episode: A rendered :class:`benchmark.world.episode.Episode` with every stream of ``streams``.
        streams: Stream names to store ("depth" always, "colour").
        colour_encoding: One of :data:`COLOUR_ENCODINGS`.
        split: The episode's split (``benchmark.suites.splits.split_of``), recorded.
        privileged: ``{"person": dict, "grasp": dict}`` stored under ``/privileged``.
    """
    import h5py  # lazy: h5py (0.1 s) off `fsv-bench generate`'s start-up

    check_colour_encoding(colour_encoding)
    missing = [s for s in streams if s not in episode.streams]
    if missing:
        raise DatasetError(f"episode {episode_name(episode.scenario)} has no {missing[0]} stream to store")
    buf, written = io.BytesIO(), {}
    with h5py.File(buf, "w") as f:
        _root_attrs(f, episode, streams, split)
        g = f.create_group("labels")
        for name, arr in label_arrays(episode).items():
            _array(g, name, arr)
        for stream in streams:
            _stream(f, episode, stream, colour_encoding, written)
        p = f.create_group("privileged")
        for key, value in (privileged or {}).items():
            p.attrs[key] = json.dumps(value, sort_keys=True, default=_json_default)
        f.attrs["content_sha256"] = content_sha256(f, written)
    return buf.getvalue()


def failed_shard(scenario, error: str, split: str | None = None) -> bytes:
    """A shard holding only the root attributes and ``status = error`` (a world failure: the
    episode is neither lost nor retried forever)."""
    import h5py  # lazy: h5py (0.1 s) off `fsv-bench generate`'s start-up

    buf = io.BytesIO()
    with h5py.File(buf, "w") as f:
        f.attrs.update(format=SHARD_FORMAT, version=SHARD_VERSION, episode=episode_name(scenario), status=error,
                       scenario=json.dumps(_scenario_dict(scenario), sort_keys=True), split=str(split),
                       streams="[]", finger_names="[]", fps=float(scenario.fps))
        f.attrs["content_sha256"] = content_sha256(f)
    return buf.getvalue()


def _scenario_dict(sc) -> dict:
    return asdict(sc)


def _json_default(v):
    if isinstance(v, np.ndarray):
        return v.tolist()
    if isinstance(v, np.generic):
        return v.item()
    if hasattr(v, "record"):
        return v.record()
    raise TypeError(f"not JSON: {type(v).__name__}")


def _root_attrs(f, episode, streams, split) -> None:
    tr, om = episode.truth, episode.object_model
    f.attrs.update(
        format=SHARD_FORMAT, version=SHARD_VERSION, episode=episode_name(episode.scenario), status="ok",
        scenario=json.dumps(_scenario_dict(episode.scenario), sort_keys=True), split=str(split),
        fps=float(episode.scenario.fps), finger_names=json.dumps([str(n) for n in tr.finger_names]),
        streams=json.dumps(list(streams)), gravity=np.asarray(tr.gravity, np.float64),
        object_model=json.dumps(dict(size_m=np.asarray(om.size_m).tolist(), mass_kg=float(om.mass_kg),
                                     inertia=np.asarray(om.inertia).tolist(), friction=float(om.friction)),
                                sort_keys=True),
    )


def _stream(f, episode, stream: str, colour_encoding: str, written: dict) -> None:
    g = f.create_group(stream)
    if stream == "depth":
        calib, t_s = episode.calib, np.arange(episode.depth.num_frames) / episode.depth.fps
        stored, encoding = _depth_encoding(episode.depth.depth_m)
        _images(g, "frames", stored, written, encoding=encoding, units="mm" if encoding == "uint16-mm" else "m")
        _images(g, "labels", np.asarray(episode.labels, np.uint8), written)
    else:
        video = episode.colour
        calib, t_s = video.calib, np.asarray(video.t_s, np.float64)
        g.attrs["exposure_s"] = float(video.exposure_s)
        if colour_encoding == "raw":
            _images(g, "frames", np.asarray(video.rgb, np.uint8), written, encoding="raw")
        else:
            import h5py  # lazy: h5py (0.1 s) off `fsv-bench generate`'s start-up

            ds = g.create_dataset("frames", shape=(len(video.rgb),), dtype=h5py.vlen_dtype(np.uint8))
            for k in range(len(video.rgb)):
                ds[k] = _encode_jpeg(video.rgb[k])
            ds.attrs.update(encoding="jpeg", quality=JPEG_QUALITY, height=video.rgb.shape[1], width=video.rgb.shape[2])
        _images(g, "labels", np.asarray(episode.colour_labels, np.uint8), written)
    g.attrs.update(width=int(calib.width), height=int(calib.height))
    _array(g, "K", calib.K)
    _array(g, "T_world_cam", calib.T_world_cam)
    _array(g, "t_s", t_s)
    if episode.annotations is not None and stream in episode.annotations.streams:
        labels = episode.annotations.streams[stream]
        for name in _STREAM_LABELS:
            _array(g, name, getattr(labels, name))


def content_sha256(f, written: dict | None = None) -> str:
    """SHA-256 of a shard's content: every dataset (name, dtype, shape, values; JPEG frames
    element by element) and every attribute but ``content_sha256``, in sorted order.

    ``written`` maps datasets' names to the arrays just written into them (:func:`write_shard`): their
    values are hashed from memory, the same bytes as read back, without decompressing the frames
    again (about a quarter of the time to write a shard with colour); the rest is read from ``f``."""
    h, written = hashlib.sha256(), written or {}

    def attrs(name, obj):
        items = {k: (v.tolist() if isinstance(v, np.ndarray) else v.item() if isinstance(v, np.generic) else v)
                 for k, v in obj.attrs.items() if k != "content_sha256"}
        h.update(json.dumps([name, items], sort_keys=True, default=str).encode())

    names = []
    f.visit(names.append)
    attrs("/", f)
    for name in sorted(names):
        obj = f[name]
        attrs(name, obj)
        if hasattr(obj, "dtype"):
            h.update(json.dumps([name, str(obj.dtype), list(obj.shape)]).encode())
            if obj.dtype.kind == "O":
                for k in range(obj.shape[0]):
                    v = obj[k].tobytes()
                    h.update(len(v).to_bytes(8, "little") + v)
            elif (kept := written.get(obj.name)) is not None and (kept.dtype, kept.shape) == (obj.dtype, obj.shape):
                h.update(np.ascontiguousarray(kept))  # C order: the frames' bytes one after another
            else:
                for k in range(obj.shape[0] if obj.ndim else 1):  # a chunk's worth at a time for images
                    h.update(np.ascontiguousarray(obj[k] if obj.ndim else obj[()]).tobytes())
    return h.hexdigest()


def open_shard(path, data: bytes | None = None):
    """An h5py File of a shard (read-only), from its path or its bytes; DatasetFileError naming it if unreadable."""
    import h5py  # lazy: h5py (0.1 s) off `fsv-bench generate`'s start-up

    try:
        return h5py.File(io.BytesIO(data) if data is not None else path, "r")
    except (OSError, ValueError) as e:
        raise DatasetFileError(f"{path} is not a readable shard: {e}") from e


def verify_shard(path, data: bytes | None = None, sha256: str | None = None, content: bool = True) -> dict:
    """Checks a shard: readable, of this format, named after its episode, its content matching its
    digest (unless ``content`` is False: the writer of bytes a worker has just made skips the
    decompression), and its bytes matching ``sha256`` (the index's) if given. Returns its root
    attributes with ``sha256`` and ``bytes``.

    Raises:
        DatasetFileError: naming the file and what is wrong.
    """

    if data is None:
        try:
            with open(path, "rb") as fh:
                data = fh.read()
        except OSError as e:
            raise DatasetFileError(f"cannot read {path}: {e}") from e
    if sha256 is not None and hashlib.sha256(data).hexdigest() != sha256:
        raise DatasetFileError(f"{path} is corrupt: its bytes do not match the SHA-256 in the index")
    try:
        with open_shard(path, data) as f:
            meta = {k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in f.attrs.items()}
            if meta.get("format") != SHARD_FORMAT or meta.get("version") != SHARD_VERSION:
                raise DatasetFileError(f"{path} is a {meta.get('format')!r} file of version {meta.get('version')!r}; "
                                       f"this fsv-bench reads {SHARD_FORMAT!r} version {SHARD_VERSION}")
            if content and meta.get("content_sha256") != content_sha256(f):
                raise DatasetFileError(f"{path} is corrupt: its content does not match its digest")
    except DatasetFileError:
        raise
    except (OSError, ValueError, KeyError, RuntimeError) as e:  # h5py's errors on damaged chunks
        raise DatasetFileError(f"{path} is corrupt: {e}") from e
    stem = os.path.basename(os.fspath(path))[: -len(".h5")]
    if meta.get("episode") != stem:
        raise DatasetFileError(f"{path} holds episode {meta.get('episode')!r}, not {stem!r}: a renamed or copied file")
    meta["sha256"] = hashlib.sha256(data).hexdigest()
    meta["bytes"] = len(data)
    return meta


def read_shard(path) -> dict:
    """A whole shard as ``{"/"-joined name: array}`` (depth in metres, colour decoded), with
    ``"attrs"``: the root attributes (tests, inspection; the training reader is windowed)."""
    out = {}
    with open_shard(path) as f:
        out["attrs"] = dict(f.attrs)

        def take(name, obj):
            if not hasattr(obj, "dtype"):
                return
            if name == "depth/frames":
                out[name] = decode_depth(obj[()], obj.attrs["encoding"])
            elif name == "colour/frames":
                out[name] = decode_colour(obj)
            else:
                out[name] = obj[()]

        f.visititems(take)
        out["privileged"] = {k: json.loads(v) for k, v in f["privileged"].attrs.items()} if "privileged" in f else {}
    return out
