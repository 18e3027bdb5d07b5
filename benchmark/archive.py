"""Sealed ``.npz`` archives: the one container of the episode, camera-input and estimates files.

An archive is a NumPy ``.npz`` (zip, deflate-compressed) of plain arrays (no pickles) named
``<section>/<field>``, plus an entry ``meta.json``: a uint8 array of UTF-8 JSON with ``format``,
``version``, ``array_sha256`` (:func:`fsv.digest.array_sha256` of every array over its name, dtype,
shape and bytes) and ``meta_sha256`` (:func:`fsv.digest.tree_sha256` of the JSON without itself).
Writers replace the file atomically with fixed zip timestamps (the same content gives the same
bytes); readers check the format, the version and every digest. Files written by other programs
may leave the digests out (``digests_required=False``): then only the format and version are checked.

The same archive may be an HDF5 file (a path ending in ``.h5``): a dataset per array at
``<section>/<field>`` and a uint8 dataset ``meta.json``, with the same digests; C, C++, Julia,
MATLAB, R and JavaScript read it with their own HDF5 libraries (Python: ``h5py``).
"""

from __future__ import annotations

import json
import pathlib
import zipfile

import numpy as np

from benchmark.atomic import atomic_path
from fsv.digest import array_sha256, tree_sha256
from fsv.errors import one_line

HDF5_SUFFIX = ".h5"
"""An archive whose path ends so is an HDF5 file, any other an ``.npz``."""


def _h5py():
    try:
        import h5py
    except ImportError as e:  # pragma: no cover - h5py is installed with fsv-bench
        raise ImportError("HDF5 files need h5py: pip install h5py") from e
    return h5py


class _HDF5Entries:
    """An HDF5 archive seen as ``np.load`` sees an ``.npz``: ``files`` and ``[name]`` -> array."""

    def __init__(self, path):
        self._file = _h5py().File(path, "r")
        names = []
        self._file.visititems(lambda name, obj: names.append(name) if hasattr(obj, "shape") else None)
        self.files = names

    def __getitem__(self, name):
        return np.asarray(self._file[name][()])

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self._file.close()


def _container(path: pathlib.Path):
    return _HDF5Entries(path) if path.suffix == HDF5_SUFFIX else np.load(path, allow_pickle=False)


def write_archive(path, fmt: str, version: int, meta: dict, arrays: dict) -> pathlib.Path:
    """Writes a sealed archive, replacing ``path`` atomically.

    Args:
        path: Destination (``.npz``).
        fmt: The ``format`` name.
        version: The format's version.
        meta: JSON-able entries of ``meta.json`` besides format, version and digests.
        arrays: ``{"<section>/<field>": array}``.

    Returns:
        The path written.
    """
    path = pathlib.Path(path)
    meta = {"format": fmt, "version": version, **meta}
    meta["array_sha256"] = {name: array_sha256(value, name) for name, value in arrays.items()}
    meta["meta_sha256"] = tree_sha256(meta)
    entries = dict(arrays)
    entries["meta.json"] = np.frombuffer(json.dumps(meta, sort_keys=True).encode(), dtype=np.uint8)
    if path.suffix == HDF5_SUFFIX:
        h5py = _h5py()
        with atomic_path(path) as tmp, h5py.File(tmp, "w", track_order=True) as f:
            for name, value in entries.items():
                value = np.asanyarray(value)
                big = value.size > 4096
                f.create_dataset(name, data=value, track_times=False, compression="gzip" if big else None,
                                 compression_opts=4 if big else None)
        return path
    with atomic_path(path) as tmp, zipfile.ZipFile(tmp, "w", compression=zipfile.ZIP_DEFLATED) as z:
        for name, value in entries.items():
            info = zipfile.ZipInfo(name + ".npy", date_time=(1980, 1, 1, 0, 0, 0))  # fixed: same bytes
            info.compress_type = zipfile.ZIP_DEFLATED
            with z.open(info, "w", force_zip64=True) as out:
                np.lib.format.write_array(out, np.asanyarray(value), allow_pickle=False)
    return path


def read_archive(path, fmt: str, version: int, *, kind: str, error: type, digests_required: bool = True) -> tuple:
    """Reads and checks a sealed archive.

    Args:
        path: The file.
        fmt: The expected ``format``.
        version: The expected version.
        kind: What the file is, for messages ("episode", "estimates", ...).
        error: The exception class raised.
        digests_required: Refuse a file without digests.

    Returns:
        ``(meta, sections)``: the JSON, and ``{section: {field: array}}``.

    Raises:
        error: If the file is missing, truncated or corrupt (naming the damaged entry), of another
            format or version, or if an array is missing or not listed.
    """
    path = pathlib.Path(path)
    if not path.is_file():
        raise error(f"no {kind} file at {path}")
    entry = "meta.json"
    try:
        with _container(path) as z:
            if "meta.json" not in z.files:
                raise error(f"{path} is not an fsv-bench {kind} file (no meta.json entry)")
            meta = json.loads(bytes(z["meta.json"]).decode())
            if not isinstance(meta, dict) or meta.get("format") != fmt:
                got = meta.get("format") if isinstance(meta, dict) else None
                raise error(f"{path} is not an fsv-bench {kind} file (format {got!r}, expected {fmt!r})")
            if meta.get("version") != version:
                raise error(f"{path} is {kind} format version {meta.get('version')!r}; this fsv-bench reads "
                            f"version {version}")
            digests = meta.get("array_sha256")
            if "meta_sha256" in meta or digests_required:
                if meta.get("meta_sha256") != tree_sha256({k: v for k, v in meta.items() if k != "meta_sha256"}):
                    raise error(f"{path} is corrupt: entry 'meta.json' does not match its SHA-256")
            if digests is None and not digests_required:
                digests = {k: None for k in z.files if k != "meta.json"}
            if not isinstance(digests, dict):
                raise error(f"{path} has missing or inconsistent {kind} data: no array digests")
            stored = [k for k in z.files if k != "meta.json"]
            for name in digests:
                if name not in stored:
                    raise error(f"{path} has missing or inconsistent {kind} data: array {name!r} listed in "
                                "meta.json is missing")
            sections = {}
            for entry in stored:
                if entry not in digests:
                    raise error(f"{path} has missing or inconsistent {kind} data: array {entry!r} is not listed "
                                "in meta.json")
                value = z[entry]
                if digests[entry] is not None and array_sha256(value, entry) != digests[entry]:
                    raise error(f"{path} is corrupt: array {entry!r} does not match its SHA-256")
                section, _, name = entry.partition("/")
                sections.setdefault(section, {})[name] = value
    except error:
        raise
    except Exception as e:  # zip, zlib, CRC, .npy header or JSON errors: whatever damaged bytes raise
        raise error(f"{path} is truncated or corrupt (entry {entry!r}): {one_line(e)}") from e
    return meta, sections
