import os

import numpy as np
import pyarrow as pa
import pytest

from benchmark.dataset import DatasetSpec, _with_meta, episode_id, generate, load_dataset, _ints
from benchmark.errors import DatasetError

CALLS = []


def cheap_build(sc, spec):
    """A stand-in world for the bookkeeping tests: three rows per episode."""
    CALLS.append(episode_id(sc))
    if len(CALLS) == 3 and os.environ.get("FSV_TEST_INTERRUPT") == "1":
        raise KeyboardInterrupt
    n = 3
    t = pa.table(dict(episode=[episode_id(sc)] * n, user=[sc.user] * n, frame=np.arange(n), p1=np.full(n, sc.seed, float)))
    return _with_meta(t, sc, spec, ["thumb"], dict(frames=n, rows=n), status="ok")


def test_resume_after_interrupt_neither_duplicates_nor_loses(tmp_path, monkeypatch):
    spec = DatasetSpec(tasks=("lift",), users=(0, 1), seeds=(0, 1, 2))
    CALLS.clear()
    monkeypatch.setenv("FSV_TEST_INTERRUPT", "1")
    (tmp_path / "episodes").mkdir()
    (tmp_path / "episodes" / ".tmp-debris.parquet").write_bytes(b"half")  # a killed run's leftover
    with pytest.raises(KeyboardInterrupt):
        generate(spec, tmp_path, workers=1, progress=False, build=cheap_build)
    files = sorted(p.name for p in (tmp_path / "episodes").iterdir())
    assert files == ["lift_u0_g0_m0_s0.parquet", "lift_u0_g0_m0_s1.parquet"]  # debris gone, nothing half-written
    monkeypatch.setenv("FSV_TEST_INTERRUPT", "0")
    man = generate(spec, tmp_path, workers=1, progress=False, build=cheap_build)
    assert CALLS == [episode_id(sc) for sc in spec.scenarios()[:3]] + [episode_id(sc) for sc in spec.scenarios()[2:]]
    assert sorted(man["episode"]) == sorted(episode_id(sc) for sc in spec.scenarios())
    assert man["rows"].sum() == 18
    df = load_dataset(tmp_path, user=1)
    assert len(df) == 9 and set(df["user"]) == {1}
    again = generate(spec, tmp_path, workers=1, progress=False, build=cheap_build)  # nothing left to do
    assert len(CALLS) == 7 and len(again) == 6


def test_resume_with_another_spec_is_refused(tmp_path):
    generate(DatasetSpec(seeds=(0,)), tmp_path, workers=1, progress=False, build=cheap_build)
    with pytest.raises(DatasetError, match="another spec"):
        generate(DatasetSpec(seeds=(0, 1)), tmp_path, workers=1, progress=False, build=cheap_build)


def test_ray_without_ray_installed_says_how_to_get_it(tmp_path):
    try:
        import ray  # noqa: F401
        pytest.skip("ray is installed")
    except ImportError:
        pass
    with pytest.raises(DatasetError, match=r"fsv-bench\[ray\]"):
        generate(DatasetSpec(seeds=(0, 1)), tmp_path, ray_address="auto", progress=False, build=cheap_build)


def test_bad_spec_and_ranges():
    assert _ints("0,2,5-7") == (0, 2, 5, 6, 7)
    with pytest.raises(DatasetError, match="'a-b'"):
        _ints("a-b")
    with pytest.raises(DatasetError, match="users"):
        DatasetSpec(users=(-1,))
    with pytest.raises(DatasetError, match="kinematics source"):
        DatasetSpec(kinematics="magic")
