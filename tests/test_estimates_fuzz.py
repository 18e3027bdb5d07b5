"""A fuzz test of the estimates file: mutated valid files are either refused in one line naming the file
(``EstimatesFileError``: exit 2) or scored with every episode counted."""

import json

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from tiny_suite import TINY

from benchmark.exchange import EstimatesFileError, load_estimate
from benchmark.exchange.estimates_file import ARRAYS, FORMAT, META_KEYS
from benchmark.scores.aggregate import aggregate_all
from benchmark.scores.episode import score_episode
from benchmark.scores.metrics import METRICS
from benchmark.suites.evaluate import cached_episode

CASES = 150
"""Hypothesis examples (derandomized: the same cases every run; about 10 s here)."""


@pytest.fixture(scope="module")
def episode(tiny_episode_folder):
    return cached_episode(TINY, TINY.scenarios[0], tiny_episode_folder)[0]


def truth_arrays(episode) -> dict:
    """A valid estimates file's arrays: the truth itself, every optional group present."""
    tr = episode.truth
    T, K = tr.contact_active.shape
    active = np.asarray(tr.contact_active, bool)
    normal = np.where(active[..., None], tr.contact_normal, [0.0, 0.0, 1.0])
    forces = {"force": np.where(active[..., None], tr.contact_force, 0.0), "env_wrench": np.zeros((T, 6)),
              "status": np.zeros(T, np.int8)}
    return {"box/pos": tr.box_pos, "box/rot": tr.box_rot, "contacts/active": active,
            "contacts/sliding": np.zeros((T, K), bool),
            "contacts/point": np.where(active[..., None], tr.contact_point, 0.0), "contacts/normal": normal,
            "kinematics/vel": tr.box_vel, "kinematics/acc": tr.box_acc, "kinematics/omega": tr.box_omega,
            "kinematics/alpha": tr.box_alpha, "kinematics/valid": np.ones(T, bool),
            "kinematics/pos": tr.box_pos, "kinematics/rot": tr.box_rot, "contacts/slide_dir": np.zeros((T, K, 3)),
            "hand/fingertips": tr.fingertip_pos,
            **{f"{g}/{k}": v for g in ("nominal", "forces") for k, v in forces.items()}}


DTYPES = ("float16", "float32", "int8", "int16", "int64", "uint8", "bool", "complex128", "<U4", "object")
VALUES = (np.nan, np.inf, -np.inf, 1e300, -1e300, 0.0, 1.0, -1.0, 1e6, 300, 0.5, 7, 8)
META_VALUES = (True, False, 1, 1.0, "x", "", [], {}, None, ["thumb"], {"tracker": 3}, "a" * 2000, "line\nbreak",
               {"name": "tiny", "version": True})

mutation = st.one_of(
    st.tuples(st.just("dtype"), st.sampled_from(sorted(ARRAYS)), st.sampled_from(DTYPES)),
    st.tuples(st.just("shape"), st.sampled_from(sorted(ARRAYS)), st.sampled_from(("drop", "extra", "flat", "T"))),
    st.tuples(st.just("value"), st.sampled_from(sorted(ARRAYS)), st.sampled_from(VALUES), st.integers(0, 10_000),
              st.booleans()),
    st.tuples(st.just("delete"), st.sampled_from(sorted(ARRAYS) + ["meta.json"])),
    st.tuples(st.just("extra"), st.sampled_from(("extra/x", "box/secret", "contacts/slide_dir", "nominal"))),
    st.tuples(st.just("meta"), st.sampled_from(META_KEYS[1:] + ("notes",)), st.sampled_from(META_VALUES)),
    st.tuples(st.just("meta-delete"), st.sampled_from(META_KEYS)),
)


def mutate(arrays: dict, meta: dict, m: tuple) -> None:
    kind, name = m[0], m[1]
    if kind == "dtype" and name in arrays:
        a = arrays[name]
        arrays[name] = a.astype(str).astype(object) if m[2] == "object" else a.astype(m[2])
    elif kind == "shape" and name in arrays:
        a = arrays[name]
        arrays[name] = {"drop": a[:-1], "extra": a[..., None], "flat": a.reshape(-1), "T": a.T}[m[2]]
    elif kind == "value" and name in arrays:
        a = np.array(arrays[name])
        flat = a.reshape(-1)
        if flat.size:
            value = m[2]
            if a.dtype == bool or np.issubdtype(a.dtype, np.integer):
                a = a.astype(np.float64) if m[4] else a.astype(np.int64)
                flat = a.reshape(-1)
                value = value if m[4] or np.isfinite(value) and abs(value) < 2 ** 62 else 300
            flat[m[3] % flat.size] = value
        arrays[name] = a
    elif kind == "delete":
        arrays.pop(name, None)
        if name == "meta.json":
            arrays["meta.json"] = None  # written without it
    elif kind == "extra":
        arrays[name] = np.zeros((3,))
    elif kind == "meta":
        meta[name] = m[2]
    elif kind == "meta-delete":
        meta.pop(name, None)


@settings(max_examples=CASES, deadline=None, derandomize=True, database=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
@given(mutations=st.lists(mutation, min_size=1, max_size=3))
def test_a_mutated_file_is_refused_in_one_line_or_every_episode_counts(episode, tmp_path, mutations):
    arrays = truth_arrays(episode)
    names = tuple(str(n) for n in episode.hand_model.finger_names)
    meta = {"format": FORMAT, "version": 1, "episode": "lift-u0-g0-m0-s21", "finger_names": list(names),
            "method": "the truth", "stages": {"tracker": "truth"}}
    for m in mutations:
        mutate(arrays, meta, m)
    path = tmp_path / "e.npz"
    entries = dict(arrays)
    if "meta.json" in entries:  # a mutation deleted it
        del entries["meta.json"]
    else:
        entries["meta.json"] = np.frombuffer(json.dumps(meta).encode(), np.uint8)
    np.savez(path, **entries, allow_pickle=True)
    try:
        estimate = load_estimate(path, t=episode.truth.t, finger_names=names)
    except EstimatesFileError as e:  # exit 2 with this one line
        text = str(e)
        assert "\n" not in text and str(path) in text and "pickle" not in text.lower(), text
        return
    row = score_episode(episode, estimate)
    aggregates = aggregate_all([row], METRICS)
    for metric, by in aggregates.items():
        for statistic, a in by.items():
            assert a["n"] == 1, (metric, statistic, a)
            assert a["value"] is not None or metric == "contact_err_mm_mean", (metric, a)
