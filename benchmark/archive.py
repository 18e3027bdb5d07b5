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
        import h5py  # lazy: h5py (0.1 s), only for .h5 archives
    except ImportError as e:  # pragma: no cover - h5py is installed with fsv-bench
        raise ImportError("HDF5 files need h5py: pip install h5py") from e
    return h5py


MAX_COMPRESSION_RATIO = 1100
"""The most an entry may expand when read, uncompressed bytes over stored bytes (zip or HDF5
chunks). Deflate, the format's compression, cannot exceed about 1032:1 (an all-zero array); a
larger ratio is a decompression bomb or another codec."""

MAX_META_BYTES = 1 << 20
"""The largest ``meta.json`` entry, [bytes]: fsv-bench's own are a few KiB."""

MAX_ENTRY_BYTES = 1 << 32
"""The largest array of an archive whose format gives no tighter bound, [bytes] (4 GiB: about a
hundred times a 10 s depth recording at 30 fps and 320 x 240, 46 MB). Estimates files bound each array by its shape
(the episode's frames, :data:`benchmark.exchange.estimates_file.MAX_FRAMES`)."""

_HDF5_FILTERS = {1: "gzip", 2: "shuffle", 3: "fletcher32"}
"""HDF5 filters a dataset may use (h5py's ids): fsv-bench writes gzip; shuffle and the checksum are
common in other writers. Any other (a plugin, szip, scale-offset) is refused."""


class _Refused(Exception):
    """An entry that is not in the format: the message names it (``read_archive`` adds the file)."""


def _entry_name(member: str) -> str:
    if not member.endswith(".npy"):
        raise _Refused(f"entry {member!r} is not in the format (every entry is <section>/<field>.npy)")
    return member[:-4]


def _check_dtype(name: str, dtype: np.dtype) -> None:
    """Numbers, booleans and fixed-width text (an episode's names) only: never objects (variable-length
    strings included), bytes, complex numbers or records."""
    if dtype.hasobject or dtype.kind not in "biufU" or dtype.fields is not None or dtype.subdtype is not None:
        what = {"S": "byte strings", "O": "objects or variable-length strings", "c": "complex numbers"}.get(
            dtype.kind, f"dtype {dtype.str}")
        raise _Refused(f"array {name!r} holds {what}; an archive holds numbers, booleans and fixed-width text only")


class _ZipEntries:
    """An ``.npz`` read entry by entry: every ``.npy`` header is parsed and checked before its data."""

    def __init__(self, path):
        self._zip = zipfile.ZipFile(path)
        try:
            self._index(self._zip.infolist())
        except BaseException:
            self._zip.close()
            raise
        self.files = list(self._infos)

    def _index(self, infos):
        self._infos = {}
        for info in infos:
            if _entry_name(info.filename) in self._infos:
                raise _Refused(f"entry {info.filename!r} is stored twice")
            if info.compress_type not in (zipfile.ZIP_STORED, zipfile.ZIP_DEFLATED):
                raise _Refused(f"entry {info.filename!r} uses compression method {info.compress_type}; the format "
                               "stores or deflates")
            if info.file_size > MAX_COMPRESSION_RATIO * max(info.compress_size, 1):
                raise _Refused(f"entry {info.filename!r} expands {info.file_size / max(info.compress_size, 1):.0f} "
                               f"times (above {MAX_COMPRESSION_RATIO}, deflate's limit)")
            self._infos[_entry_name(info.filename)] = info

    def header(self, name: str) -> tuple:
        """``(dtype, shape)`` of an entry, from its ``.npy`` header alone."""
        with self._zip.open(self._infos[name]) as fp:
            return self._read_header(name, fp)[:2]

    def _read_header(self, name, fp):
        fmt = np.lib.format
        major, _ = fmt.read_magic(fp)
        read = fmt.read_array_header_1_0 if major == 1 else fmt.read_array_header_2_0
        shape, fortran, dtype = read(fp, max_header_size=10000)
        return dtype, tuple(int(n) for n in shape), fortran

    def read(self, name: str, limit: int) -> np.ndarray:
        """The array of an entry, refused when its header says it holds more than ``limit`` bytes or
        the entry is larger than its header says."""
        info = self._infos[name]
        with self._zip.open(info) as fp:
            dtype, shape, fortran = self._read_header(name, fp)
            _check_dtype(name, dtype)
            nbytes = int(np.prod(shape, dtype=object)) * dtype.itemsize
            if nbytes > limit:
                raise _Refused(f"array {name!r} holds {nbytes} bytes, above the {limit} bytes its format allows")
            if fp.tell() + nbytes != info.file_size:
                raise _Refused(f"entry {info.filename!r} is {info.file_size} bytes, not the {fp.tell() + nbytes} "
                               "bytes its .npy header gives")
            data = bytearray(nbytes)  # filled in place: one copy of the array in memory, writable
            view, got = memoryview(data), 0
            while got < nbytes:
                n = fp.readinto(view[got:])
                if not n:
                    raise ValueError(f"entry {info.filename!r} is truncated")
                got += n
            fp.read(1)  # at the end: the CRC is checked
        array = np.frombuffer(data, dtype)
        return np.ascontiguousarray(array.reshape(shape[::-1]).T) if fortran else array.reshape(shape)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self._zip.close()


class _HDF5Entries:
    """An HDF5 archive read as :class:`_ZipEntries` reads an ``.npz``: datasets only, each checked
    before its data is read; links (soft or external), external raw storage, virtual datasets,
    unknown filters and named types are refused."""

    def __init__(self, path):
        h5py = _h5py()
        self._h5py = h5py
        self._file = h5py.File(path, "r")
        self._datasets = {}
        try:
            self._walk(self._file, "")
        except BaseException:
            self._file.close()
            raise
        self.files = list(self._datasets)

    def _walk(self, group, prefix):
        h5py = self._h5py
        for key in group.keys():
            name = prefix + key
            link = group.get(key, getlink=True)
            if not isinstance(link, h5py.HardLink):
                kind = "an external link" if isinstance(link, h5py.ExternalLink) else "a soft link"
                raise _Refused(f"entry {name!r} is {kind}; the format holds datasets only")
            obj = group[key]
            if isinstance(obj, h5py.Group):
                if name.count("/") > 2:
                    raise _Refused(f"entry {name!r} is nested deeper than <section>/<field>")
                self._walk(obj, name + "/")
            elif isinstance(obj, h5py.Dataset):
                self._check_dataset(name, obj)
                self._datasets[name] = obj
            else:
                raise _Refused(f"entry {name!r} is not a dataset")

    def _check_dataset(self, name, d):
        if d.is_virtual:
            raise _Refused(f"dataset {name!r} is virtual (its data lives in other files); the format stores it")
        if d.external:
            raise _Refused(f"dataset {name!r} has external raw storage (its data lives in another file); "
                           "the format stores it in the file")
        plist = d.id.get_create_plist()
        for i in range(plist.get_nfilters()):
            code = plist.get_filter(i)[0]
            if code not in _HDF5_FILTERS:
                raise _Refused(f"dataset {name!r} uses HDF5 filter {code}; accepted: "
                               f"{', '.join(_HDF5_FILTERS.values())}")
        _check_dtype(name, d.dtype)
        stored = d.id.get_storage_size()
        if d.nbytes > MAX_COMPRESSION_RATIO * max(stored, 1) and d.nbytes > 4096:
            raise _Refused(f"dataset {name!r} expands {d.nbytes / max(stored, 1):.0f} times (above "
                           f"{MAX_COMPRESSION_RATIO}, deflate's limit)")

    def header(self, name: str) -> tuple:
        d = self._datasets[name]
        return d.dtype, tuple(int(n) for n in d.shape)

    def read(self, name: str, limit: int) -> np.ndarray:
        d = self._datasets[name]
        if d.nbytes > limit:
            raise _Refused(f"array {name!r} holds {d.nbytes} bytes, above the {limit} bytes its format allows")
        return np.asarray(d[()])

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self._file.close()


def _container(path: pathlib.Path):
    return _HDF5Entries(path) if path.suffix == HDF5_SUFFIX else _ZipEntries(path)


FAST_DEFLATE_LEVEL = 1
"""Deflate's level for the entries a writer names ``fast`` (large noisy images, e.g. a colour
video: level 6, the default, takes four times as long for 4 % less; measured on a 2 s colour stream,
56 MB: 33.2 MB in 0.63 s at level 1, 32.1 MB in 2.5 s at level 6)."""


def write_archive(path, fmt: str, version: int, meta: dict, arrays: dict, fast: frozenset = frozenset(),
                  stored: frozenset = frozenset()) -> pathlib.Path:
    """Writes a sealed archive, replacing ``path`` atomically.

    Args:
        path: Destination (``.npz``).
        fmt: The ``format`` name.
        version: The format's version.
        meta: JSON-able entries of ``meta.json`` besides format, version and digests.
        arrays: ``{"<section>/<field>": array}``.
        fast: Entries deflated at :data:`FAST_DEFLATE_LEVEL` instead of the default level (the
            same format: any reader inflates them alike).
        stored: Entries stored without compression (zip's method 0, which every reader of the
            format reads): for large images dominated by noise, where deflate saves little for its
            time (a 10 s colour video: 41 % of 277 MB for 3.4 s of a core at level 1).

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
            info.compress_type = zipfile.ZIP_STORED if name in stored else zipfile.ZIP_DEFLATED
            if name in fast:  # the attribute is compress_level from Python 3.13, _compresslevel before
                setattr(info, "compress_level" if hasattr(info, "compress_level") else "_compresslevel",
                        FAST_DEFLATE_LEVEL)
            with z.open(info, "w", force_zip64=True) as out:
                _write_npy(out, np.asanyarray(value))
    return path


def _write_npy(out, array: np.ndarray) -> None:
    """``np.lib.format.write_array(out, array, allow_pickle=False)``, the same bytes, but a C-ordered
    array's data is handed to ``out`` as it lies in memory (numpy copies it 16 MiB at a time into
    new bytes objects: 0.3 s for a 10 s colour video)."""
    if not array.flags.c_contiguous or array.dtype.hasobject or array.size == 0:
        np.lib.format.write_array(out, array, allow_pickle=False)
        return
    np.lib.format.write_array_header_1_0(out, np.lib.format.header_data_from_array_1_0(array))
    out.write(memoryview(array.reshape(-1)).cast("B"))


def read_archive(path, fmt: str, version: int | tuple, *, kind: str, error: type, digests_required: bool = True,
                 check_entry=None, arrays: bool = True) -> tuple:
    """Reads and checks a sealed archive, never reading more than the format allows.

    Every entry's name, dtype and shape are checked (``.npy`` header or HDF5 dataset) before its data
    is read: an entry not listed in ``meta.json`` (or, without digests, refused by ``check_entry``),
    above :data:`MAX_ENTRY_BYTES`, expanding more than :data:`MAX_COMPRESSION_RATIO`, holding
    strings or objects, or (HDF5) a link, external storage or a virtual dataset is refused before any
    array is read.

    Args:
        path: The file.
        fmt: The expected ``format``.
        version: The expected version, or a tuple of the versions this reader reads.
        kind: What the file is, for messages ("episode", "estimates", ...).
        error: The exception class raised.
        digests_required: Refuse a file without digests.
        check_entry: ``(name, dtype, shape, meta) -> message or None``: a format's own rule on each
            entry, given its header before its data is read (a message refuses it).
        arrays: False reads ``meta.json`` and checks every entry's header without reading the arrays
            (then ``sections`` is empty).

    Returns:
        ``(meta, sections)``: the JSON, and ``{section: {field: array}}``.

    Raises:
        error: If the file is missing, not an archive, truncated or corrupt (naming the damaged
            entry), of another format or version, or if an entry is missing, not listed, or refused.
    """
    path = pathlib.Path(path)
    if not path.is_file():
        raise error(f"no {kind} file at {path}")
    entry = "meta.json"
    container = "an HDF5 file" if path.suffix == HDF5_SUFFIX else "a zip archive of .npy arrays (.npz)"
    try:
        try:
            z = _container(path)
        except (zipfile.BadZipFile, OSError) as e:
            raise error(f"{path} is truncated or corrupt, or not an fsv-bench {kind} file: not {container} "
                        f"({one_line(e)})") from e
        with z:
            if "meta.json" not in z.files:
                raise error(f"{path} is not an fsv-bench {kind} file (no meta.json entry)")
            dtype, shape = z.header("meta.json")
            if dtype != np.uint8 or len(shape) != 1:
                raise error(f"{path}: entry 'meta.json' is {dtype.str} of shape {shape}; expected a 1-d uint8 array "
                            "of UTF-8 JSON")
            meta = json.loads(bytes(z.read("meta.json", MAX_META_BYTES)).decode())
            if not isinstance(meta, dict) or meta.get("format") != fmt:
                got = meta.get("format") if isinstance(meta, dict) else None
                raise error(f"{path} is not an fsv-bench {kind} file (format {str(got)[:60]!r}, expected {fmt!r})")
            held = meta.get("version")
            readable = (version,) if isinstance(version, int) else tuple(version)
            if type(held) is not int or held not in readable:
                raise error(f"{path} is {kind} format version {repr(held)[:60]}; this fsv-bench reads version "
                            f"{' or '.join(str(v) for v in readable)} (an integer)")
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
                    raise error(f"{path} has missing or inconsistent {kind} data: array {str(name)[:60]!r} listed in "
                                "meta.json is missing")
            for entry in stored:
                if entry not in digests:
                    raise error(f"{path} has missing or inconsistent {kind} data: array {entry!r} is not listed "
                                "in meta.json")
                if check_entry is not None:
                    dtype, shape = z.header(entry)
                    refused = check_entry(entry, dtype, shape, meta)
                    if refused:
                        raise error(f"{path}: {refused}")
            sections = {}
            for entry in stored if arrays else ():
                value = z.read(entry, MAX_ENTRY_BYTES)
                if digests[entry] is not None and array_sha256(value, entry) != digests[entry]:
                    raise error(f"{path} is corrupt: array {entry!r} does not match its SHA-256")
                section, _, name = entry.partition("/")
                sections.setdefault(section, {})[name] = value
    except error:
        raise
    except _Refused as e:
        raise error(f"{path}: {e}") from e
    except Exception as e:  # zip, zlib, CRC, .npy header or JSON errors: whatever damaged bytes raise
        raise error(f"{path} is truncated or corrupt (entry {entry!r}): {one_line(e)}") from e
    return meta, sections
