"""manifest.parquet: a flipped byte is refused, or lies where no reader looks and changes nothing read."""

import json

import pandas as pd
import pyarrow as pa
import pytest

from benchmark.errors import DatasetFileError
from benchmark.paper.dataset.files import MANIFEST_COLUMNS, _write_sealed, read_manifest
from benchmark.paper.dataset.spec import FORMAT, VERSION


def write_manifest_of(out, n: int = 3) -> pd.DataFrame:
    rows = [dict(episode=f"lift-u{i}-g0-m0-s{i}", file=f"episodes/lift-u{i}-g0-m0-s{i}.parquet", sha256="ab" * 32,
                 task="lift", user=i, grasp=0, mass=0, seed=i, status="ok", frames=46, rows=40, dropped_contacts=1,
                 dropped_gap=2, dropped_solver=0, seconds=1.5, kinematics="tracker", contacts="tracker")
            for i in range(n)]
    table = pa.Table.from_pandas(pd.DataFrame(rows, columns=list(MANIFEST_COLUMNS)), preserve_index=False)
    meta = {b"fsv": json.dumps(dict(format=FORMAT + "-manifest", version=VERSION)).encode()}
    _write_sealed(table.replace_schema_metadata({**(table.schema.metadata or {}), **meta}),
                  str(out / "manifest.parquet"))
    return read_manifest(out)


def test_every_sampled_flip_is_refused_or_reads_back_the_same_manifest(tmp_path):
    good = write_manifest_of(tmp_path)
    path = tmp_path / "manifest.parquet"
    data = path.read_bytes()
    outcomes = {"refused": 0, "same": 0}
    for i in range(0, len(data), 13):
        flipped = bytearray(data)
        flipped[i] ^= 0x10
        path.write_bytes(bytes(flipped))
        try:
            got = read_manifest(tmp_path)
        except DatasetFileError:
            outcomes["refused"] += 1
            continue
        assert got.equals(good) and list(got.dtypes) == list(good.dtypes), f"byte {i}: a different manifest read"
        outcomes["same"] += 1
    assert outcomes["refused"] > 0 and outcomes["same"] > 0  # both kinds of bytes exist


@pytest.mark.parametrize("covered, offset", [(b"lift-u0", 5), (b"tracker", 2), (b"ARROW:schema", 400)])
def test_a_flip_in_a_covered_region_is_refused(tmp_path, covered, offset):
    """Covered: the data pages (an episode's name, a source) and the Arrow schema with the metadata
    that pyarrow reads (its base64 blob); not covered: e.g. the footer's plain copy of that metadata."""
    write_manifest_of(tmp_path)
    path = tmp_path / "manifest.parquet"
    data = bytearray(path.read_bytes())
    at = data.find(covered) + offset
    assert at >= offset
    data[at] ^= 0x01
    path.write_bytes(bytes(data))
    with pytest.raises(DatasetFileError, match="manifest.parquet is (corrupt|truncated)"):
        read_manifest(tmp_path)
