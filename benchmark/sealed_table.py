"""Parquet tables that carry the SHA-256 of their own content ("sealed" tables).

A dataset's tables (:mod:`benchmark.paper.dataset`) hold their description as JSON under the schema
metadata key ``fsv``. :func:`seal` adds ``"sha256"`` to that JSON: the digest of every column (name,
Arrow type, nulls and values, :func:`table_sha256`) and of all the schema metadata (the ``fsv``
JSON without the digest itself). :func:`read_sealed` parses a file's bytes, recomputes the digest
and refuses the file if it differs, naming it.

What it detects. Any change of what a reader gets from the file: values, column names or types,
the metadata. Damaged bytes that change none of that (e.g. the leading magic number, column
statistics, page headers' optional fields) are not seen; a dataset's manifest therefore also
records the SHA-256 of each file's bytes (:func:`file_sha256`), which sees every flipped byte.
"""

from __future__ import annotations

import hashlib
import json

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

from benchmark.errors import DatasetFileError
from fsv.digest import tree_sha256
from fsv.errors import InputError, one_line

KEY = b"fsv"


def file_sha256(data: bytes) -> str:
    """SHA-256 (hex) of a file's bytes."""
    return hashlib.sha256(data).hexdigest()


def _column(column: pa.ChunkedArray):
    arr = column.combine_chunks()
    nulls = arr.is_null().to_numpy(zero_copy_only=False) if arr.null_count else None
    t = pa.types
    if t.is_string(arr.type) or t.is_large_string(arr.type) or t.is_binary(arr.type) or t.is_large_binary(arr.type):
        values = arr.cast(pa.large_binary()).to_pylist()
        lengths = [-1 if v is None else len(v) for v in values]
        return [nulls, np.asarray(lengths, np.int64), np.frombuffer(b"".join(v or b"" for v in values), np.uint8)]
    if t.is_integer(arr.type) or t.is_floating(arr.type) or t.is_boolean(arr.type):
        filled = arr.fill_null(False if t.is_boolean(arr.type) else 0) if arr.null_count else arr
        return [nulls, filled.to_numpy(zero_copy_only=False)]
    if t.is_null(arr.type):  # e.g. a column of an empty DataFrame
        return [len(arr)]
    raise InputError(f"cannot digest a column of type {arr.type}")


def metadata(table: pa.Table) -> dict:
    """The ``fsv`` JSON of a table's schema metadata ({} if it has none)."""
    raw = (table.schema.metadata or {}).get(KEY)
    return {} if raw is None else json.loads(raw)


def table_sha256(table: pa.Table) -> str:
    """SHA-256 of a table's columns and schema metadata, without the ``sha256`` of its ``fsv`` JSON.

    Raises:
        InputError: If a column has a type that is not digested (strings, binaries, integers,
            floats, booleans and nulls are).
        ValueError: If the ``fsv`` metadata is not JSON.
    """
    meta = {}
    for key, value in (table.schema.metadata or {}).items():
        if key == KEY:
            fsv = json.loads(value)
            value = {k: v for k, v in fsv.items() if k != "sha256"} if isinstance(fsv, dict) else fsv
        else:
            value = value.decode("latin-1")
        meta[key.decode("latin-1")] = value
    columns = [[name, str(col.type), _column(col)] for name, col in zip(table.column_names, table.columns)]
    return tree_sha256({"metadata": meta, "rows": table.num_rows, "columns": columns})


def seal(table: pa.Table) -> pa.Table:
    """The table with ``"sha256"`` (:func:`table_sha256`) added to its ``fsv`` metadata."""
    meta = metadata(table)
    meta["sha256"] = table_sha256(table)
    schema_meta = dict(table.schema.metadata or {})
    schema_meta[KEY] = json.dumps(meta).encode()
    return table.replace_schema_metadata(schema_meta)


def to_bytes(table: pa.Table) -> bytes:
    """The table as Parquet file bytes."""
    sink = pa.BufferOutputStream()
    pq.write_table(table, sink)
    return sink.getvalue().to_pybytes()


def read_sealed(data: bytes, name: str) -> tuple[pa.Table, dict]:
    """Parses Parquet bytes and checks the table's seal.

    Args:
        data: The file's bytes.
        name: The file's name, for the error messages.

    Returns:
        ``(table, fsv metadata)``.

    Raises:
        DatasetFileError: If the bytes are not a Parquet table, it has no ``fsv`` metadata or no
            seal, or its content does not match the seal; the message names the file.
    """
    try:
        table = pq.read_table(pa.BufferReader(data))
        meta = metadata(table)
        digest = table_sha256(table)
    except Exception as e:  # Arrow, Thrift, JSON or Unicode errors: whatever damaged bytes raise
        raise DatasetFileError(f"{name} is truncated or corrupt: {one_line(e)}") from e
    if "sha256" not in meta:
        raise DatasetFileError(f"{name} carries no SHA-256 of its content (written by an fsv-bench without "
                               "dataset digests): generate it again")
    if meta["sha256"] != digest:
        raise DatasetFileError(f"{name} is corrupt: its content does not match the SHA-256 recorded in it")
    return table, meta
