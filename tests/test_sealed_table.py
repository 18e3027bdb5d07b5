"""Sealed Parquet tables: the digest of the content travels in the file and is checked on reading."""

import json

import numpy as np
import pandas as pd
import pyarrow as pa
import pytest

from benchmark.errors import DatasetFileError
from benchmark.sealed_table import KEY, file_sha256, read_sealed, seal, table_sha256, to_bytes


def table(**meta):
    t = pa.table(dict(name=["a", "bc", ""], n=np.arange(3), x=[0.5, np.nan, -1.0], ok=[True, False, True]))
    return t.replace_schema_metadata({KEY: json.dumps(dict(episode="e1", **meta)).encode()})


def test_a_sealed_table_reads_back_with_its_metadata():
    data = to_bytes(seal(table(rows=3)))
    back, meta = read_sealed(data, "f.parquet")
    assert meta["episode"] == "e1" and meta["rows"] == 3 and len(meta["sha256"]) == 64
    assert back.column("name").to_pylist() == ["a", "bc", ""]
    assert file_sha256(data) == file_sha256(bytes(data)) != file_sha256(data + b"\0")


def test_the_digest_sees_values_names_types_nulls_and_metadata():
    base = table()
    d = table_sha256(base)
    assert d == table_sha256(seal(base))  # the seal itself is not digested
    variants = [
        base.set_column(2, "x", pa.array([0.5, np.nan, -1.0 + 1e-16])),
        base.set_column(1, "n", pa.array([0, 1, 2], pa.int32())),
        base.rename_columns(["name", "n", "y", "ok"]),
        base.set_column(0, "name", pa.array(["a", "bc", None])),  # null is not ""
        base.set_column(0, "name", pa.array(["ab", "c", ""])),  # same bytes, other split
        base.replace_schema_metadata({KEY: json.dumps(dict(episode="e2")).encode()}),
        base.replace_schema_metadata({KEY: json.dumps(dict(episode="e1")).encode(), b"other": b"1"}),
        base.slice(0, 2),
    ]
    assert len({table_sha256(v) for v in variants} | {d}) == len(variants) + 1
    empty = pa.Table.from_pandas(pd.DataFrame(columns=["a", "b"]), preserve_index=False)
    assert table_sha256(empty) != table_sha256(empty.rename_columns(["a", "c"]))  # null-typed columns


def test_content_changed_under_an_old_seal_is_refused():
    sealed = seal(table())
    changed = sealed.set_column(3, "ok", pa.array([True, True, True]))  # keeps the old seal
    with pytest.raises(DatasetFileError, match=r"^x\.parquet is corrupt: its content does not match"):
        read_sealed(to_bytes(changed), "x.parquet")


def test_unsealed_and_foreign_bytes_are_refused():
    with pytest.raises(DatasetFileError, match=r"^old\.parquet carries no SHA-256"):
        read_sealed(to_bytes(table()), "old.parquet")
    with pytest.raises(DatasetFileError, match=r"^junk\.parquet is truncated or corrupt"):
        read_sealed(b"PAR1 not really", "junk.parquet")
    data = to_bytes(seal(table()))
    with pytest.raises(DatasetFileError, match=r"^half\.parquet is truncated or corrupt"):
        read_sealed(data[: len(data) // 2], "half.parquet")
