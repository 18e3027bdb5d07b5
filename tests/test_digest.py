"""Digests of arrays and nested data: equal content, equal digest; any change, another digest."""

import numpy as np
import pytest

from fsv import InputError
from fsv.digest import array_sha256, tree_sha256


def test_array_digest_covers_name_dtype_shape_and_bytes():
    a = np.arange(6, dtype=np.float64)
    d = array_sha256(a, "x")
    assert len(d) == 64 and d == array_sha256(a.copy(), "x")
    assert d == array_sha256(a[::-1][::-1].copy(), "x") == array_sha256(np.asfortranarray(a), "x")
    assert d == array_sha256(a.astype(">f8"), "x")  # byte order is canonical
    assert d != array_sha256(a, "y")
    assert d != array_sha256(a.reshape(2, 3), "x")
    assert d != array_sha256(a.astype(np.float32), "x")
    b = a.copy()
    b.view(np.uint8)[17] ^= 1  # one bit
    assert d != array_sha256(b, "x")
    assert array_sha256(np.array(["thumb", "index"]), "n") != array_sha256(np.array(["thumb", "indey"]), "n")
    with pytest.raises(InputError, match="Python objects"):
        array_sha256(np.array([{}, 1], dtype=object))


def test_tree_digest_is_canonical_and_sees_every_change():
    tree = {"b": [1, 2.5, None, True, "s"], "a": {"w": np.eye(2), "v": np.zeros(3, np.int64)}, "nan": float("nan")}
    d = tree_sha256(tree)
    reordered = {"nan": float("nan"), "a": {"v": np.zeros(3, np.int64), "w": np.eye(2)}, "b": (1, 2.5, None, True, "s")}
    assert tree_sha256(reordered) == d  # key order and tuple/list do not matter
    changed = [
        {**tree, "b": [1, 2.5, None, 1, "s"]},  # True is not 1
        {**tree, "b": [1, 2.5000000000000004, None, True, "s"]},
        {**tree, "a": {"w": np.eye(2), "v": np.zeros(3, np.int32)}},
        {**tree, "a": {"w": np.eye(2).ravel(), "v": np.zeros(3, np.int64)}},
        {**tree, "a": {"v": np.eye(2), "w": np.zeros(3, np.int64)}},  # arrays swapped between keys
        {**tree, "extra": None},
    ]
    w = np.eye(2)
    w[1, 0] = 1e-300
    changed.append({**tree, "a": {"w": w, "v": np.zeros(3, np.int64)}})
    assert len({tree_sha256(t) for t in changed} | {d}) == len(changed) + 1
    with pytest.raises(InputError, match=r"\.a\.s of type set"):
        tree_sha256({"a": {"s": {1}}})
