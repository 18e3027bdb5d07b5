"""SHA-256 digests of arrays and of nested data, independent of how they were stored.

A file format that records these digests when it writes and recomputes them when it reads
detects any change of the content, wherever the bytes of the file were damaged. The digests are
over a canonical serialisation, not over a file's bytes, so they survive re-compression and do
not depend on a container's own layout:

* :func:`array_sha256`: an array's name, dtype (little-endian), shape and C-order bytes;
* :func:`tree_sha256`: nested dicts (keys sorted), lists, tuples (as lists), strings, numbers,
  booleans, None and arrays: a compact JSON header in which every array is replaced by its
  dtype and shape, followed by the arrays' bytes in header order.
"""

from __future__ import annotations

import hashlib
import json
import math

import numpy as np

from fsv.errors import InputError


def _canonical_array(a) -> np.ndarray:
    a = np.ascontiguousarray(a)
    if a.dtype.hasobject:
        raise InputError(f"cannot digest an array of Python objects (dtype {a.dtype})")
    if a.dtype.byteorder == ">":
        a = a.astype(a.dtype.newbyteorder("<"))
    return a


def _data(a: np.ndarray) -> memoryview:
    """The bytes of a canonical (C-contiguous) array as they lie in memory: what ``a.tobytes()``
    holds, without its copy (0.3 GB for a 10 s colour video)."""
    return memoryview(a.reshape(-1)).cast("B")


def _describe(a: np.ndarray) -> list:
    return [a.dtype.str, list(a.shape)]


def array_sha256(array, name: str = "") -> str:
    """SHA-256 (hex) of an array's name, dtype, shape and bytes.

    Args:
        array: Anything :func:`numpy.asarray` turns into an array of a fixed-size dtype.
        name: The array's name in its file (a renamed array gets another digest).

    Raises:
        InputError: If the array holds Python objects.
    """
    a = _canonical_array(np.asarray(array))
    h = hashlib.sha256(json.dumps([str(name), *_describe(a)], separators=(",", ":")).encode())
    h.update(b"\0")
    h.update(_data(a))
    return h.hexdigest()


def tree_sha256(tree) -> str:
    """SHA-256 (hex) of nested JSON-like data with numpy arrays (see the module docstring).

    Raises:
        InputError: If the data holds something else (e.g. an object, a set).
    """
    arrays = []

    def canon(obj, where):
        if isinstance(obj, dict):
            return {"dict": [[str(k), canon(obj[k], f"{where}.{k}")] for k in sorted(obj, key=str)]}
        if isinstance(obj, (list, tuple)):
            return {"list": [canon(v, f"{where}[{i}]") for i, v in enumerate(obj)]}
        if isinstance(obj, np.ndarray):
            a = _canonical_array(obj)
            arrays.append(a)
            return {"array": _describe(a)}
        if isinstance(obj, np.generic):
            obj = obj.item()
        if obj is None or isinstance(obj, (bool, int, str)):
            return obj
        if isinstance(obj, float):
            return obj if math.isfinite(obj) else {"float": repr(obj)}
        raise InputError(f"cannot digest {where or 'the value'} of type {type(obj).__name__}")

    header = json.dumps(canon(tree, ""), separators=(",", ":"), allow_nan=False)
    h = hashlib.sha256(header.encode())
    for a in arrays:
        h.update(b"\0")
        h.update(_data(a))
    return h.hexdigest()
