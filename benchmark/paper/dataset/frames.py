"""Frames datasets: every frame of the rendered streams with its labels, for any network (``fsv-bench generate --frames``).

Each episode of the grid (:class:`benchmark.paper.dataset.spec.DatasetSpec`) is simulated and
rendered with the streams asked for, and written as one HDF5 shard (:mod:`benchmark.paper.dataset.shards`).
Layout of a frames dataset folder::

    dataset.json              format, spec (grid, streams, colour encoding), the world's fingerprint
                              and the provenance of the run (a resumed run must match them)
    episodes/<episode>.h5     one shard per episode, written atomically by this process only
    episodes/<episode>.seconds.json   how long it took to build (wall and CPU seconds)
    index.parquet             one row per shard (:data:`INDEX_COLUMNS`), sealed with its content digest
    README.md                 the dataset card (Hugging Face form, YAML header: licences, size, configs)
    croissant.json            Croissant 1.0 metadata with its responsible-AI fields

It is training data: a grid holding a ``dev`` or ``test`` person, grasp or view
(:mod:`benchmark.suites.splits`) is refused before any work. Resuming, the local pool or Ray and
concurrent runs behave as for the feature datasets (:func:`benchmark.paper.dataset.generate`): a
resumed run re-verifies every shard (its bytes against the index, its content against its own
digest) and rebuilds a bad one.
"""

from __future__ import annotations

import glob
import io
import json
import os
import sys
import time
from dataclasses import asdict, dataclass

import numpy as np
import pandas as pd
import pyarrow as pa

from benchmark.atomic import claim_folder, remove_stale_temporaries, write_bytes, write_text
from benchmark.errors import BenchmarkError, DatasetError, DatasetFileError
from benchmark.fingerprint import world_fingerprint
from benchmark.paper.dataset.card import write_card
from benchmark.paper.dataset.claims import Claims
from benchmark.paper.dataset.files import _write_sealed
from benchmark.paper.dataset.shards import check_colour_encoding, failed_shard, verify_shard, write_shard
from benchmark.paper.dataset.spec import DatasetSpec
from benchmark.parallel import RayUnavailable, check_ray_address, run_jobs
from benchmark.sealed_table import read_sealed
from benchmark.world.people import person_record
from benchmark.world.scenario import Scenario, episode_name
from fsv.provenance import provenance
from fsv.types import check_streams

FRAMES_FORMAT = "fsv-bench-frames"
FRAMES_VERSION = 1
INDEX_COLUMNS = ("episode", "file", "split", "task", "user", "grasp", "view", "mass", "seed", "frames", "bytes",
                 "sha256", "status", "streams")
"""Columns of ``index.parquet``: the scenario's fields, the split (``cohort`` or ``train``), the
frame count, the shard's size in bytes and the SHA-256 of its bytes, its status ("ok" or
"failed: ...") and its streams (comma-separated)."""
SHARD_SUFFIX = ".h5"
TIMING_SUFFIX = ".seconds.json"


@dataclass(frozen=True)
class FramesSpec:
    """What a frames dataset holds: the grid of scenarios, the streams and the colour's encoding.

    Attributes:
        grid: The episodes (its sample rules and sources are not used: every frame is kept).
        streams: Stream names ("depth" always; "colour").
        colour_encoding: ``benchmark.paper.dataset.shards.COLOUR_ENCODINGS``: "raw" (lossless) or "jpeg".
    """

    grid: DatasetSpec
    streams: tuple = ("depth",)
    colour_encoding: str = "raw"

    def __post_init__(self):
        try:
            object.__setattr__(self, "streams", check_streams(self.streams))
        except ValueError as e:
            raise DatasetError(str(e)) from None
        check_colour_encoding(self.colour_encoding)

    def as_dict(self) -> dict:
        g = self.grid
        grid = dict(tasks=list(g.tasks), users=list(g.users), grasps=list(g.grasps), masses=list(g.masses),
                    seeds=list(g.seeds), views=list(g.views), design=g.design, duration_s=g.duration_s, fps=g.fps,
                    noise_m=g.noise_m)
        return dict(grid=grid, streams=list(self.streams),
                    colour_encoding=self.colour_encoding if "colour" in self.streams else None)


def check_training_people(spec: DatasetSpec) -> None:
    """Refuses a grid holding a ``dev`` or ``test`` person, grasp or view (they choose and score,
    never train): DatasetError naming the first, before any work."""
    from benchmark.suites.splits import SPLITS  # lazy: scipy.stats (0.4 s) off `fsv-bench generate`'s start-up

    for sc in spec.scenarios():
        for kind in ("user", "grasp", "view"):
            index = getattr(sc, kind)
            for name in ("dev", "test"):
                if SPLITS[name].holds(index):
                    raise DatasetError(
                        f"{kind} {index} is in the {name} split, which never trains a model; a frames dataset is "
                        f"training data: accepted: the named cohort (users 0-4, grasps 0-3, view 0), indices 5-99 "
                        f"and the training split (`--split train`, 1000 and above)")


def render_episode(scenario: Scenario, streams: tuple):
    """Simulates and renders one scenario with ``streams`` (the default episode source)."""
    from benchmark.camera.render import render  # lazy: MuJoCo (0.25 s) off `fsv-bench generate`'s start-up
    from benchmark.world.simulate import simulate  # lazy: MuJoCo (0.25 s) off `fsv-bench generate`'s start-up

    return render(simulate(scenario), streams=streams)


def build_shard(scenario: Scenario, spec: FramesSpec, make=render_episode) -> bytes:
    """One scenario's shard bytes (:func:`benchmark.paper.dataset.shards.write_shard`), with its
    person and grasp descriptors as privileged; a world failure gives a failed shard."""
    from benchmark.suites.splits import split_of  # lazy: scipy.stats (0.4 s) off `fsv-bench generate`'s start-up
    from benchmark.world.grasp_plan import grasp_spec  # lazy: MuJoCo (0.25 s) off `fsv-bench generate`'s start-up

    split = split_of(scenario)
    try:
        episode = make(scenario, spec.streams)
        privileged = dict(person=person_record(scenario.user), grasp=grasp_spec(scenario))
        return write_shard(episode, streams=spec.streams, colour_encoding=spec.colour_encoding, split=split,
                           privileged=privileged)
    except BenchmarkError as e:
        return failed_shard(scenario, f"failed: {type(e).__name__}: {e}", split)


def _run_one(job) -> tuple:
    """``(episode name, shard bytes, {"seconds": wall, "cpu_seconds": this process's CPU time})`` of a
    ``(scenario, spec, make)`` job, in a worker."""
    scenario, spec, make = job
    t0, c0 = time.perf_counter(), time.process_time()
    data = build_shard(scenario, spec, make)
    return episode_name(scenario), data, {"seconds": time.perf_counter() - t0, "cpu_seconds": time.process_time() - c0}


def made_by_generate_frames(out) -> bool:
    """Whether ``out`` is a real folder holding a frames dataset's ``dataset.json``."""
    path = os.path.join(os.fspath(out), "dataset.json")
    if os.path.islink(os.fspath(out)) or not os.path.isfile(path):
        return False
    try:
        with open(path) as fh:
            return json.load(fh).get("format") == FRAMES_FORMAT
    except (OSError, ValueError, AttributeError):
        return False


def _prepare(spec: FramesSpec, out: str) -> str:
    claim_folder(out, adopt=made_by_generate_frames(out))
    episodes = os.path.join(out, "episodes")
    os.makedirs(episodes, exist_ok=True)
    for folder in (out, episodes):
        remove_stale_temporaries(folder, owner=out)
    header = dict(format=FRAMES_FORMAT, version=FRAMES_VERSION, spec=spec.as_dict(), world=world_fingerprint())
    path = os.path.join(out, "dataset.json")
    if os.path.exists(path):
        try:
            with open(path) as fh:
                old = json.load(fh)
        except (OSError, ValueError) as e:
            raise DatasetFileError(f"{path} is not a readable dataset header: {e}") from e
        for key, what in (("format", "another kind of dataset"), ("version", "another version"),
                          ("spec", f"another spec ({old.get('spec')}); use a new folder or the same arguments"),
                          ("world", "another world (the simulation, the sensor or their assets changed)")):
            if old.get(key) != header[key]:
                raise DatasetError(f"{out!r} holds {what}: use a new folder")
        now = provenance()
        if now != old.get("provenance") and now not in old.get("resumed_with", []):
            old["resumed_with"] = old.get("resumed_with", []) + [now]
            write_text(path, json.dumps(old, indent=1))
    else:
        write_text(path, json.dumps(dict(header, provenance=provenance()), indent=1))
    return episodes


def _listed(out: str) -> dict:
    """``{file: sha256}`` of the index, if there is a readable one."""
    path = os.path.join(out, "index.parquet")
    if not os.path.exists(path):
        return {}
    try:
        index = read_index(out)
    except DatasetFileError as e:
        print(f"generate: {e}; it is rebuilt from the shards", file=sys.stderr)
        return {}
    return dict(zip(index["file"], index["sha256"]))


def _check_existing(spec: FramesSpec, out: str) -> dict:
    """Verifies every shard already there; a bad one is reported and removed (then rebuilt).
    Returns ``{relative path: root attributes}`` of the good ones."""

    listed = _listed(out)
    expected = {episode_name(sc): sc for sc in spec.grid.scenarios()}
    good = {}
    for path in sorted(glob.glob(os.path.join(out, "episodes", "*" + SHARD_SUFFIX))):
        rel = os.path.relpath(path, out)
        try:
            meta = verify_shard(path, sha256=listed.get(rel))
            sc = expected.get(meta["episode"])
            if sc is not None and json.loads(meta["scenario"]) != asdict(sc):
                raise DatasetFileError(f"{path} holds episode {meta['episode']} of another scenario")
            if meta["status"] == "ok" and json.loads(meta["streams"]) != list(spec.streams):
                raise DatasetFileError(f"{path} holds the streams {meta['streams']}, not {list(spec.streams)}")
        except DatasetFileError as e:
            print(f"generate: {e}; {'rebuilding' if os.path.basename(path)[:-3] in expected else 'removing'} it",
                  file=sys.stderr)
            os.unlink(path)
            continue
        good[rel] = meta
    return good


def generate_frames(spec: FramesSpec, out, *, workers: int | None = None, ray_address: str | None = None,
                    progress: bool = True, make=render_episode) -> pd.DataFrame:
    """Generates (or completes) the frames dataset ``spec`` in ``out``.

    Args:
        spec: The grid, the streams and the colour encoding.
        out: Dataset folder; created if missing. An existing one must hold the same spec and world.
        workers: Local worker processes (default: all cores); 1 builds in this process.
        ray_address: A Ray cluster's address; the episodes then run as Ray tasks.
        progress: A tqdm bar on stderr.
        make: ``(Scenario, streams) -> rendered Episode`` (default :func:`render_episode`).

    Returns:
        The index (one row per shard), also in ``out/index.parquet``; ``out/README.md`` and
        ``out/croissant.json`` are written from it.
    """

    out = os.fspath(out)
    if workers is not None and (isinstance(workers, bool) or int(workers) != workers or workers < 1):
        raise DatasetError(f"workers must be a positive integer, got {workers!r}")
    if ray_address is not None:
        check_ray_address(ray_address)
    check_training_people(spec.grid)
    _prepare(spec, out)
    written = _check_existing(spec, out)
    rel = lambda sc: os.path.join("episodes", episode_name(sc) + SHARD_SUFFIX)
    todo = [sc for sc in spec.grid.scenarios() if rel(sc) not in written]
    total = spec.grid.size()
    from tqdm.auto import tqdm  # lazy: tqdm (30 ms) off `fsv-bench generate`'s start-up

    bar = tqdm(total=total, initial=total - len(todo), unit="episode", desc="generate --frames", disable=not progress,
               file=sys.stderr)
    claims = Claims(out)

    def done(result) -> None:
        name, data, timing = result
        path = os.path.join(out, "episodes", name + SHARD_SUFFIX)
        write_bytes(path, data)
        written[os.path.relpath(path, out)] = verify_shard(path, data, content=False)  # the worker sealed it
        write_text(os.path.join(out, "episodes", name + TIMING_SUFFIX), json.dumps(timing))
        claims.release(name)
        bar.update(1)

    try:
        while todo:
            mine = [sc for sc in todo if claims.take(episode_name(sc))]
            local = 1 if len(mine) <= 1 else min(int(workers or os.cpu_count() or 1), len(mine))
            try:
                for _, result in run_jobs(_run_one, [(sc, spec, make) for sc in mine], workers=local,
                                          ray_address=ray_address):
                    done(result)
            except RayUnavailable as e:
                raise DatasetError(str(e)) from e
            todo = [sc for sc in todo if sc not in mine]
            todo = claims.wait_for_others(todo, bar)
    finally:
        claims.release_all()
        bar.close()
    if claims.waited:
        written = _check_existing(spec, out)
    index = write_index(out, written)

    write_card(out, spec, index)
    return index


def _index_row(rel: str, meta: dict) -> dict:
    sc = json.loads(meta["scenario"])
    return dict(episode=meta["episode"], file=rel, split=str(meta.get("split")), task=sc["task"], user=sc["user"],
                grasp=sc["grasp"], view=sc.get("view", 0), mass=sc["mass"], seed=sc["seed"],
                frames=_frames(meta, sc), bytes=int(meta["bytes"]), sha256=meta["sha256"], status=meta["status"],
                streams=",".join(json.loads(meta["streams"])))


def _frames(meta: dict, sc: dict) -> int:
    from benchmark.world.simulate import duration_of  # lazy: MuJoCo (0.25 s) off `fsv-bench generate`'s start-up

    if meta["status"] != "ok":
        return 0
    return int(np.floor(duration_of(Scenario(**sc)) * sc["fps"] + 1e-9)) + 1


def write_index(out, shards: dict) -> pd.DataFrame:
    """Writes ``out/index.parquet`` (sealed: :mod:`benchmark.sealed_table`) from ``{relative path:
    verified root attributes}`` and returns it."""

    rows = [_index_row(rel, meta) for rel, meta in sorted(shards.items())]
    index = pd.DataFrame(rows, columns=list(INDEX_COLUMNS))
    for col in ("user", "grasp", "view", "mass", "seed", "frames", "bytes"):
        index[col] = index[col].astype(np.int64)
    table = pa.Table.from_pandas(index, preserve_index=False)
    meta = {b"fsv": json.dumps(dict(format=FRAMES_FORMAT + "-index", version=FRAMES_VERSION)).encode()}
    _write_sealed(table.replace_schema_metadata({**(table.schema.metadata or {}), **meta}),
                  os.path.join(os.fspath(out), "index.parquet"))
    return index


def read_index(out) -> pd.DataFrame:
    """``out/index.parquet``, its content digest checked (DatasetFileError naming it otherwise)."""

    path = os.path.join(os.fspath(out), "index.parquet")
    try:
        with open(path, "rb") as fh:
            data = fh.read()
    except OSError as e:
        raise DatasetError(f"{os.fspath(out)!r} is not a frames dataset (no index.parquet): {e}") from e
    _, meta = read_sealed(data, path)
    if meta.get("format") != FRAMES_FORMAT + "-index" or meta.get("version") != FRAMES_VERSION:
        raise DatasetFileError(f"{path} is not a frames index of version {FRAMES_VERSION}")
    return pd.read_parquet(io.BytesIO(data))


def check_frames(out) -> str:
    """Verifies a frames dataset folder (``fsv-bench check DIR``): the index's digest, every shard's
    bytes against it and its content against its own digest, and that every shard is listed.
    Returns one line; raises DatasetFileError naming the first bad file."""
    out = os.fspath(out)
    index = read_index(out)
    on_disk = {os.path.relpath(p, out) for p in glob.glob(os.path.join(out, "episodes", "*" + SHARD_SUFFIX))}
    missing = sorted(set(index["file"]) - on_disk)
    if missing:
        raise DatasetFileError(f"{os.path.join(out, missing[0])} is listed in the index but missing")
    extra = sorted(on_disk - set(index["file"]))
    if extra:
        raise DatasetFileError(f"{os.path.join(out, extra[0])} is not listed in the index")
    for row in index.itertuples():
        verify_shard(os.path.join(out, row.file), sha256=row.sha256)
    for name in ("README.md", "croissant.json"):
        if not os.path.isfile(os.path.join(out, name)):
            raise DatasetFileError(f"{os.path.join(out, name)} is missing")
    ok = int((index["status"] == "ok").sum())
    return (f"{out}: ok: frames dataset, {len(index)} shards ({ok} ok), {int(index['frames'].sum())} frames, "
            f"{index['bytes'].sum() / 1e6:.1f} MB, every digest matches")
