"""Training data for the internal-force networks without tactile hardware (the paper's §3.6).

Each episode of a grid of scenarios (tasks x users x grasps x masses x seeds) is simulated; per
frame we compute the features p1, p2_k, p3, p4_k (eq. 10-13, :mod:`fsv.features`) from the object's
kinematics and the contacts, and the targets from the decomposition SOCP (eq. 9,
:func:`fsv.forces.decompose_forces`) fed with the "tactile measurements": the truth's normal force of each
finger. As in the paper, samples whose vision and tactile net forces differ by more than
``max_gap_n`` (1.5 N) are dropped. The vision net force is F_c = m (a - g) from the kinematics the
features use; the tactile net force is the resultant of the truth's finger forces (so frames where
the table still carries the box are dropped too). Frames with fewer than ``min_fingers`` fingers in
contact (no internal force is possible) or invalid kinematics are dropped as well.

Sources. By default (``contacts="tracker"``) every episode goes through the method proper, as
``fsv-bench`` does: the depth video is rendered (``benchmark.camera.render``), the tracker
(``fsv.track.track``, with the benchmark's seeded first-frame initialisation and the same random
streams as ``fsv-bench``) estimates the box poses and the contacts, and the kinematics are the
algebraic differentiator of ``benchmark.world.motion`` on the tracked poses. Two cheaper, labelled
alternatives skip rendering and tracking: ``"error-model"``, the truth's contacts moved by the
paper's measured contact-point error (mean -1.55 mm, std 6.13 mm per axis, white in time,
``benchmark.world.contact_error``) with kinematics differentiated from tracker-like poses
(``benchmark.world.pose_error``); and ``"oracle"``, the truth's contacts (an ablation). ``kinematics=
"oracle"`` takes the true kinematics (an ablation). The dataset records its sources in
``dataset.json`` and in every file, and every report labels them.

Layout of a dataset folder::

    dataset.json              spec, sources, format version and the world's fingerprint (a resumed
                              run must match them), and the
                              provenance of the run that made it (``resumed_with``: of later runs)
    episodes/<id>.parquet     one table per episode (one row per kept frame), written atomically;
                              its bytes depend only on the episode (the same from a pool or Ray)
    episodes/<id>.seconds.json  how long it took to build (for the manifest's ``seconds``)
    manifest.parquet          one row per episode (counts, timing, status, SHA-256 of the file's
                              bytes), rebuilt from the files

Integrity. Every table (episodes and manifest) carries the SHA-256 of its own content in its
metadata (:mod:`benchmark.sealed_table`), and the manifest records the SHA-256 of each episode
file's bytes. :func:`load_dataset` checks both and that each file holds the episode its name says;
so does a resumed :func:`generate`, which reports a bad file on stderr and builds it again. Both
digests are needed: the content digest lets a file be checked on its own (an interrupted run has
no manifest yet), but about one in ten random 4-byte flips in a Parquet file hits bytes that no
reader uses (e.g. column statistics) and leaves the content as it was; the bytes' digest in the
manifest sees every flip.

Columns of an episode table: ``episode, task, user, grasp, mass, seed, frame, t``; the world-frame
kinematics ``pos_*, rot_00..rot_22, vel_*, acc_*, omega_*, alpha_*``; the features ``p1, p3,
p2_<finger>, p4_<finger>``; per finger ``active_, sliding_, point_{x,y,z}_, normal_{x,y,z}_,
slide_{x,y,z}_`` (object frame), ``f_meas_`` (tactile reading, [N], 0 off contact), ``f_true_`` (the
truth's normal force, the scoring reference), ``true_active_`` and ``true_point_{x,y,z}_`` (the
truth's contact, object frame: for scoring and for measuring contact errors only, never an input),
``f_nom_`` and ``f_int_`` (nominal and internal normal components from eq. 9, [N]); ``net_gap_n``.
With the tracker, each file's metadata also holds the tracker's scores on the episode
(``benchmark.scores.tracking.score_tracking``). Read them with pandas
(``pd.read_parquet``) or :func:`load_dataset`.

Running. A local process pool over all cores by default, with a progress bar; or Ray
(``ray_address``; ``pip install 'fsv-bench[ray]'``), whose workers return tables to this process.
Either way only this process writes files: each episode goes to a temporary file that is renamed
into place, so an interrupted run (crash, Ctrl-C) leaves only complete episodes, and running the
same command again does the missing ones. A failed episode (e.g. the box was dropped) is written
as an empty table whose metadata holds the error, so it is neither lost nor retried forever.
"""

from __future__ import annotations

import argparse
import glob
import io
import json
import os
import pathlib
import sys
import time
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from dataclasses import asdict, dataclass, fields, replace
import multiprocessing

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq

from benchmark.atomic import write_bytes, write_text
from benchmark.errors import ScenarioError, BenchmarkError, DatasetError, DatasetFileError
from benchmark.parallel import check_ray_address
from benchmark.world.scenario import Scenario
from benchmark.scores.forces import true_normal_forces
from benchmark.scores.samples import (DATASET_FORCE_SETTINGS, MAX_EXCESS_N, nominal_excess_n, sample_mask,  # noqa: F401
                                      take_contacts as _take_con, take_kinematics as _take_kin)
from benchmark.sealed_table import file_sha256, read_sealed, seal, to_bytes
from fsv import Contacts, InputError, Kinematics
from fsv.features import grasp_features
from fsv.provenance import provenance

FORMAT = "fsv-bench-dataset"
VERSION = 2  # version 1 had no digests
KINEMATICS = ("algebraic", "central", "gaussian", "oracle")
CONTACTS = ("tracker", "error-model", "oracle")
_AX = "xyz"


@dataclass(frozen=True)
class DatasetSpec:
    """Which episodes a dataset holds and how its samples are made.

    Attributes:
        tasks: Task names (see ``benchmark.TASKS``).
        users, grasps, masses: Indices into ``sim_assets`` lists.
        seeds: Scenario seeds.
        duration_s: Episode length in [s]; None takes each task's default.
        fps: Frame rate in [Hz].
        noise_m: Depth noise of the scenarios [m]; it sets the tracker-like pose errors that the
            kinematics are differentiated from (``benchmark.world.pose_error``).
        kinematics: Kinematics behind the features and the decomposition: a differentiator of
            ``benchmark.world.motion`` ("algebraic", "central", "gaussian") on the observed poses, or
            "oracle" (the truth). On tracked poses "algebraic" is the reference method's
            (``fsv.method.reference.TRACKED_POSES``).
        contacts: Source of the contacts (see the module docstring): "tracker" (render and track
            each episode: the method's contacts and poses), "error-model" (the truth's with the
            paper's contact-point errors) or "oracle" (the truth).
        tactile_noise_n: Noise of the simulated tactile sensors (``benchmark.world.tactile``), [N].
        max_gap_n: Samples whose vision and tactile net forces differ by more than this are dropped, [N].
        min_fingers: Frames with fewer fingers in contact are dropped.
    """

    tasks: tuple = ("lift",)
    users: tuple = (0,)
    grasps: tuple = (0,)
    masses: tuple = (0,)
    seeds: tuple = (0,)
    duration_s: float | None = None
    fps: float = 30.0
    noise_m: float = 0.01
    kinematics: str = "algebraic"
    contacts: str = "tracker"
    tactile_noise_n: float = 0.1
    max_gap_n: float = 1.5
    min_fingers: int = 2

    def __post_init__(self):
        object.__setattr__(self, "tasks", tuple(str(t) for t in self.tasks))
        for name in ("users", "grasps", "masses", "seeds"):
            vals = tuple(getattr(self, name))
            if not vals or any(isinstance(v, bool) or int(v) != v or v < 0 for v in vals):
                raise DatasetError(f"{name} must be a non-empty list of non-negative integers, got {vals!r}")
            object.__setattr__(self, name, tuple(int(v) for v in vals))
        if not self.tasks:
            raise DatasetError("tasks must name at least one task")
        for name, accepted in (("kinematics", KINEMATICS), ("contacts", CONTACTS)):
            if getattr(self, name) not in accepted:
                raise DatasetError(f"{name} source must be one of {accepted}, got {getattr(self, name)!r}")
        if not (np.isfinite(self.tactile_noise_n) and self.tactile_noise_n >= 0):
            raise DatasetError(f"tactile_noise_n must be >= 0 N, got {self.tactile_noise_n!r}")
        if not (np.isfinite(self.noise_m) and self.noise_m >= 0):
            raise DatasetError(f"noise_m must be >= 0 m, got {self.noise_m!r}")
        if not (np.isfinite(self.max_gap_n) and self.max_gap_n > 0):
            raise DatasetError(f"max_gap_n must be > 0 N, got {self.max_gap_n!r}")
        if int(self.min_fingers) < 2:
            raise DatasetError(f"min_fingers must be >= 2 (internal forces need two fingers), got {self.min_fingers!r}")
        self._check_grid()

    def _check_grid(self) -> None:
        """Every task, user, grasp and mass exists and the duration suits every task (before any work)."""
        from benchmark.world.assets import validate

        try:
            base = Scenario(noise_m=self.noise_m, duration_s=self.duration_s, fps=self.fps)
            for t in self.tasks:
                validate(replace(base, task=t))
            for name, values in (("user", self.users), ("grasp", self.grasps), ("mass", self.masses)):
                for v in values:
                    validate(replace(base, task=self.tasks[0], **{name: v}))
        except ScenarioError as e:
            raise DatasetError(str(e)) from None

    def scenarios(self) -> list[Scenario]:
        """Every scenario of the grid, in a fixed order."""
        return [
            Scenario(task=t, user=u, grasp=g, mass=m, seed=s, noise_m=self.noise_m, duration_s=self.duration_s, fps=self.fps)
            for t in self.tasks for u in self.users for g in self.grasps for m in self.masses for s in self.seeds
        ]

    def as_dict(self) -> dict:
        return {f.name: (list(v) if isinstance(v := getattr(self, f.name), tuple) else v) for f in fields(self)}


def episode_id(sc: Scenario) -> str:
    """File stem of a scenario's table, e.g. ``lift_u0_g1_m2_s3``."""
    return f"{sc.task}_u{sc.user}_g{sc.grasp}_m{sc.mass}_s{sc.seed}"


_ON_FRAME = None
"""Called with 1 after every tracked frame of the episode being built (the progress of ``generate``;
set per worker by :func:`_run_one`)."""


def track_episode(episode):
    """Renders a simulated episode and tracks it from depth alone with the method's tracker stage,
    exactly as ``fsv-bench`` does (same camera inputs, same random streams): ``(rendered episode, Tracking)``."""
    from benchmark.camera.render import render
    from benchmark.method import camera_input
    from fsv.method import ReferenceTracker

    ep = render(episode)
    return ep, ReferenceTracker(on_frame=_ON_FRAME)(camera_input(ep), ep.scenario.rng("tracker"))


def episode_contacts(episode, source: str, tracking=None) -> Contacts:
    """The contacts behind the features: "tracker" (``tracking.contacts``), "oracle" (the truth's)
    or "error-model" (the truth's moved by the paper's contact-point error model,
    ``benchmark.world.contact_error``)."""
    from benchmark.world.contact_error import contacts_from_truth, vision_like_contacts

    if source == "tracker":
        if tracking is None:
            raise DatasetError("contacts source 'tracker' needs the episode's tracking (see track_episode)")
        return tracking.contacts
    truth = contacts_from_truth(episode.truth)
    if source == "oracle":
        return truth
    if source != "error-model":
        raise DatasetError(f"contacts source must be one of {CONTACTS}, got {source!r}")
    return vision_like_contacts(truth, episode.object_model, episode.scenario.rng("contact-error"))


def build_episode(scenario: Scenario, spec: DatasetSpec) -> pa.Table:
    """Simulates one scenario and returns its kept samples as a table (see the module docstring)."""
    from benchmark.world.motion import episode_kinematics
    from benchmark.world.simulate import simulate
    from benchmark.world.tactile import tactile_normal_forces
    from fsv.forces import FrameStatus, decompose_forces
    from fsv.method.reference import TRACKED_POSES

    ep, tracking = simulate(scenario), None
    if spec.contacts == "tracker":
        ep, tracking = track_episode(ep)
    tr, model = ep.truth, ep.object_model
    # tracked poses are differentiated as the reference method does (its window, not Table 1's)
    config = TRACKED_POSES if (tracking is not None and spec.kinematics == "algebraic") else None
    kin = episode_kinematics(ep, spec.kinematics, config, poses=None if tracking is None else tracking.box)
    con = episode_contacts(ep, spec.contacts, tracking)
    feats = grasp_features(kin, con, model, gravity=tr.gravity)
    # unbounded range: the firm synthetic users exceed the FSG020's 20 N on the thumb
    measured = tactile_normal_forces(tr, scenario.rng("tactile"), full_scale_n=np.inf, noise_n=spec.tactile_noise_n)
    keep_contacts, keep, gap = sample_mask(kin, con, feats, tr, spec.min_fingers, spec.max_gap_n)
    idx = np.flatnonzero(keep)
    dec = decompose_forces(_take_kin(kin, idx), _take_con(con, idx), model, measured[idx], gravity=tr.gravity,
                           settings=DATASET_FORCE_SETTINGS)
    ok = dec.status == int(FrameStatus.OPTIMAL)
    rows = idx[ok]
    stats = dict(
        frames=len(tr.t), rows=int(len(rows)), dropped_contacts=int(np.sum(~keep_contacts)),
        dropped_gap=int(np.sum(keep_contacts & ~keep)), dropped_solver=int(np.sum(~ok)),
    )
    cols = _columns(scenario, tr, kin, con, feats, measured, true_normal_forces(tr), gap, rows)
    names = tuple(tr.finger_names)
    for k, name in enumerate(names):
        cols[f"f_nom_{name}"] = dec.nominal_normal[ok, k]
        cols[f"f_int_{name}"] = dec.internal_normal[ok, k]
    stats["object_model"] = dict(
        size_m=model.size_m.tolist(), mass_kg=model.mass_kg, inertia=model.inertia.tolist(),
        friction=model.friction, table_friction=model.table_friction,
    )
    stats["gravity"] = np.asarray(tr.gravity, float).tolist()
    if tracking is not None:
        from benchmark.scores.tracking import score_tracking

        stats["tracking"] = score_tracking(tracking, tr)
    return _with_meta(pa.table(cols), scenario, spec, names, stats, status="ok")


def _columns(sc, tr, kin, con, feats, measured, true_normal, gap, rows) -> dict:
    n = len(rows)
    cols = dict(
        episode=np.full(n, episode_id(sc)), task=np.full(n, sc.task), user=np.full(n, sc.user),
        grasp=np.full(n, sc.grasp), mass=np.full(n, sc.mass), seed=np.full(n, sc.seed),
        frame=rows.astype(np.int64), t=kin.t[rows],
    )
    for name in ("pos", "vel", "acc", "omega", "alpha"):
        for a in range(3):
            cols[f"{name}_{_AX[a]}"] = getattr(kin, name)[rows, a]
    for i in range(3):
        for j in range(3):
            cols[f"rot_{i}{j}"] = kin.rot[rows, i, j]
    cols["p1"], cols["p3"] = feats.p1[rows], feats.p3[rows]
    for k, name in enumerate(con.finger_names):
        cols[f"p2_{name}"] = feats.p2[rows, k]
        cols[f"p4_{name}"] = feats.p4[rows, k]
        cols[f"active_{name}"] = con.active[rows, k]
        cols[f"sliding_{name}"] = con.sliding[rows, k]
        for a in range(3):
            cols[f"point_{_AX[a]}_{name}"] = con.point[rows, k, a]
            cols[f"normal_{_AX[a]}_{name}"] = con.normal[rows, k, a]
            cols[f"slide_{_AX[a]}_{name}"] = con.slide_dir[rows, k, a]
        cols[f"f_meas_{name}"] = np.nan_to_num(measured[rows, k], nan=0.0)
        cols[f"f_true_{name}"] = true_normal[rows, k]
        cols[f"true_active_{name}"] = np.asarray(tr.contact_active, bool)[rows, k]
        for a in range(3):
            cols[f"true_point_{_AX[a]}_{name}"] = np.asarray(tr.contact_point, float)[rows, k, a]
    cols["net_gap_n"] = gap[rows]
    return cols


def _with_meta(table: pa.Table, sc: Scenario, spec: DatasetSpec, finger_names, stats: dict, status: str) -> pa.Table:
    meta = dict(
        format=FORMAT, version=VERSION, episode=episode_id(sc), scenario=asdict(sc), finger_names=list(finger_names),
        kinematics=spec.kinematics, contacts=spec.contacts, status=status, **stats,
    )
    return table.replace_schema_metadata({b"fsv": json.dumps(meta).encode()})


def _run_one(scenario: Scenario, spec: DatasetSpec, build, on_frame=None) -> pa.Table:
    """Builds one episode's table in a worker; a world failure becomes an empty table with the error.

    ``on_frame`` (a callable, or a queue whose ``put`` is called) hears of every tracked frame.
    """
    global _ON_FRAME
    _ON_FRAME = getattr(on_frame, "put", on_frame)
    t0 = time.perf_counter()
    try:
        table = build(scenario, spec)
    except BenchmarkError as e:
        table = _with_meta(pa.table({"episode": pa.array([], pa.string())}), scenario, spec, [], dict(frames=0, rows=0),
                           status=f"failed: {type(e).__name__}: {e}")
    meta = json.loads(table.schema.metadata[b"fsv"])
    meta["seconds"] = time.perf_counter() - t0
    return table.replace_schema_metadata({b"fsv": json.dumps(meta).encode()})


def _write_sealed(table: pa.Table, path: str) -> str:
    """Seals ``table`` (:func:`benchmark.sealed_table.seal`), writes it atomically and returns the
    SHA-256 of the bytes written."""
    data = to_bytes(seal(table))
    write_bytes(path, data)
    return file_sha256(data)


def _prepare(spec: DatasetSpec, out: str) -> str:
    episodes = os.path.join(out, "episodes")
    os.makedirs(episodes, exist_ok=True)
    if not _Claims(out).others_live():  # no other run is writing here: leftovers are a killed run's
        for tmp in glob.glob(os.path.join(out, ".tmp-*")) + glob.glob(os.path.join(episodes, ".tmp-*")):
            os.unlink(tmp)  # never a complete file
    from benchmark.fingerprint import world_fingerprint

    header = dict(format=FORMAT, version=VERSION, spec=spec.as_dict(), world=world_fingerprint())
    path = os.path.join(out, "dataset.json")
    if os.path.exists(path):
        with open(path) as fh:
            old = json.load(fh)
        if old.get("format") != FORMAT or old.get("version") != VERSION:
            raise DatasetError(f"{out!r} holds a dataset of format {old.get('format')!r} version {old.get('version')!r}; "
                               f"this fsv-bench writes version {VERSION} (with digests): use a new folder")
        if old.get("spec") != header["spec"]:
            raise DatasetError(
                f"{out!r} holds a dataset made with another spec ({old.get('spec')}); "
                f"use a new folder or the same arguments ({header['spec']})"
            )
        if old.get("world") != header["world"]:
            raise DatasetError(f"{out!r} holds a dataset of another world (the simulation, the sensor or their assets "
                               "changed since it was made): use a new folder")
        now = provenance()
        if now != old.get("provenance") and now not in old.get("resumed_with", []):
            old["resumed_with"] = old.get("resumed_with", []) + [now]
            write_text(path, json.dumps(old, indent=1))
    else:
        write_text(path, json.dumps(dict(header, provenance=provenance()), indent=1))
    return episodes


def _expected_stem(meta: dict) -> str | None:
    sc = meta.get("scenario")
    if not isinstance(sc, dict):
        return None
    return f"{sc.get('task')}_u{sc.get('user')}_g{sc.get('grasp')}_m{sc.get('mass')}_s{sc.get('seed')}"


def read_episode_file(path: str, sha256: str | None = None, data: bytes | None = None) -> tuple[pa.Table, dict, str]:
    """Reads one episode table and checks it.

    Args:
        path: The ``episodes/<id>.parquet`` file.
        sha256: The SHA-256 of the file's bytes recorded in the manifest, if any.
        data: The file's bytes, if the caller has read them already.

    Returns:
        ``(table, fsv metadata, SHA-256 of the file's bytes)``.

    Raises:
        DatasetFileError: If the file cannot be read, its bytes differ from ``sha256``, its
            content differs from its own digest, or it holds another episode than its name says
            (e.g. a copy of another episode's file); the message names the file.
    """
    if data is None:
        try:
            with open(path, "rb") as fh:
                data = fh.read()
        except OSError as e:
            raise DatasetFileError(f"cannot read {path}: {e}") from e
    table, meta = read_sealed(data, path)
    stem = os.path.basename(path)[: -len(".parquet")]
    if meta.get("episode") != stem or _expected_stem(meta) != stem:
        raise DatasetFileError(f"{path} holds episode {meta.get('episode')!r} (scenario {_expected_stem(meta)!r}), "
                               f"not {stem!r}: a renamed or copied file")
    if meta.get("format") != FORMAT or meta.get("version") != VERSION:
        raise DatasetFileError(f"{path} is a {meta.get('format')!r} table of version {meta.get('version')!r}; "
                               f"this fsv-bench reads {FORMAT!r} version {VERSION}")
    digest = file_sha256(data)
    if sha256 is not None and digest != sha256:  # sees damaged bytes that the content digest cannot
        raise DatasetFileError(f"{path} is corrupt: its bytes do not match the SHA-256 in the manifest")
    return table, meta, digest


def _check_existing(spec: DatasetSpec, out: str, episodes: str) -> dict:
    """Checks the episode files of an existing dataset folder before resuming.

    Every file must read, match its digest (and the SHA-256 of its bytes in ``manifest.parquet``,
    if listed there) and hold the episode its name says, made with ``spec``. A file that does not
    is reported on stderr and removed, so that it is built again; the manifest is then rewritten
    without it.

    Returns:
        ``{relative file path: SHA-256 of its bytes}`` of the good files.
    """
    listed = {}
    if os.path.exists(os.path.join(out, "manifest.parquet")):
        try:
            man = read_manifest(out)
            listed = dict(zip(man["file"], man["sha256"]))
        except DatasetFileError as e:
            print(f"generate: {e}; it is rebuilt from the episode files", file=sys.stderr)
    expected = {episode_id(sc): sc for sc in spec.scenarios()}
    good, bad = {}, 0
    for path in sorted(glob.glob(os.path.join(episodes, "*.parquet"))):
        rel = os.path.relpath(path, out)
        try:
            _, meta, digest = read_episode_file(path, listed.get(rel))
            sc = expected.get(meta["episode"])
            if sc is not None and (meta.get("scenario") != asdict(sc) or meta.get("kinematics") != spec.kinematics
                                   or meta.get("contacts") != spec.contacts):
                raise DatasetFileError(f"{path} holds episode {meta['episode']} made with another scenario or "
                                       f"sources ({meta.get('scenario')}, {meta.get('kinematics')}, {meta.get('contacts')})")
        except DatasetFileError as e:
            print(f"generate: {e}; {'rebuilding' if os.path.basename(path)[:-8] in expected else 'removing'} it",
                  file=sys.stderr)
            os.unlink(path)
            bad += 1
            continue
        good[rel] = digest
    if bad and listed:
        write_manifest(out, good)
    return good


def generate(spec: DatasetSpec, out, *, workers: int | None = None, ray_address: str | None = None,
             progress: bool = True, build=build_episode) -> pd.DataFrame:
    """Generates (or completes) the dataset ``spec`` in folder ``out``.

    Resuming checks every episode file already there (:func:`read_episode_file`): a truncated,
    corrupt or misnamed file is reported on stderr and built again.

    Args:
        spec: The grid of scenarios and the sample rules.
        out: Dataset folder; created if missing. An existing folder must hold the same spec.
        workers: Local worker processes (default: all cores); 1 builds in this process.
        ray_address: Address of a running Ray cluster (e.g. "auto" or "ray://host:10001"); the
            episodes then run as Ray tasks instead of the local pool.
        progress: Show a tqdm progress bar on stderr.
        build: Function ``(Scenario, DatasetSpec) -> pyarrow.Table`` making one episode's table.

    Returns:
        The manifest (one row per episode), also written to ``out/manifest.parquet``.
    """
    out = os.fspath(out)
    if workers is not None and (isinstance(workers, bool) or int(workers) != workers or workers < 1):
        raise DatasetError(f"workers must be a positive integer, got {workers!r}")
    if ray_address is not None:
        check_ray_address(ray_address)
    episodes = _prepare(spec, out)
    written = _check_existing(spec, out, episodes)
    todo = [sc for sc in spec.scenarios() if os.path.join("episodes", episode_id(sc) + ".parquet") not in written]
    total = len(spec.scenarios())
    from tqdm.auto import tqdm

    bar = tqdm(total=total, initial=total - len(todo), unit="episode", desc="generate", disable=not progress, file=sys.stderr)
    tracked = spec.contacts == "tracker" and build is build_episode and ray_address is None
    frames = tqdm(total=sum(_frames_of(sc) for sc in todo), unit="frame", desc="tracked", position=1, leave=True,
                  disable=not (progress and tracked), file=sys.stderr)  # per frame across the episodes
    claims = _Claims(out)

    def done(table: pa.Table) -> None:
        meta = json.loads(table.schema.metadata[b"fsv"])
        seconds = meta.pop("seconds", None)  # timing stays out of the file: the same bytes from any engine
        rel = os.path.join("episodes", meta["episode"] + ".parquet")
        written[rel] = _write_sealed(table.replace_schema_metadata({b"fsv": json.dumps(meta).encode()}),
                                     os.path.join(out, rel))
        if seconds is not None:
            write_text(os.path.join(out, "episodes", meta["episode"] + TIMING_SUFFIX), json.dumps({"seconds": seconds}))
        claims.release(meta["episode"])
        bar.update(1)

    try:
        while todo:
            mine = [sc for sc in todo if claims.take(episode_id(sc))]  # episodes another live run makes are skipped
            if ray_address is not None:
                _run_ray(mine, spec, build, ray_address, done)
            elif (workers or os.cpu_count() or 1) == 1 or len(mine) <= 1:
                for sc in mine:
                    done(_run_one(sc, spec, build, frames.update if tracked and progress else None))
            else:
                _run_pool(mine, spec, build, min(int(workers or os.cpu_count() or 1), len(mine)), done,
                          frames if tracked and progress else None)
            todo = [sc for sc in todo if sc not in mine]
            todo = claims.wait_for_others(todo, bar)  # until their files appear, or their runs die (then ours)
    finally:
        claims.release_all()
        frames.close()
        bar.close()
    return write_manifest(out, _check_existing(spec, out, episodes) if claims.waited else written)


CLAIM_POLL_S = 0.5
"""How often a run checks on the episodes another run is making [s]."""


class _Claims:
    """Which run makes which episode of a dataset folder: ``episodes/<id>.claim`` files.

    A run creates the claim (exclusively: ``O_CREAT | O_EXCL``, so two runs never both get it) with
    its host name and process id before building the episode and removes it once the episode's file
    is written. A claim whose process is gone (same host) is stale and may be taken over; claims of
    other hosts are trusted. Concurrent ``generate`` runs into one folder thus share the work.
    """

    def __init__(self, out: str):
        import socket

        self.folder = os.path.join(out, "episodes")
        self.host, self.pid = socket.gethostname(), os.getpid()
        self.mine: set = set()
        self.waited = False

    def _path(self, episode: str) -> str:
        return os.path.join(self.folder, episode + ".claim")

    def take(self, episode: str) -> bool:
        path = self._path(episode)
        for _ in range(2):
            try:
                fd = os.open(path, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
            except FileExistsError:
                if not self._stale(path):
                    return False
                try:
                    os.unlink(path)
                except FileNotFoundError:
                    pass
                continue
            with os.fdopen(fd, "w") as fh:
                fh.write(json.dumps({"host": self.host, "pid": self.pid}))
            self.mine.add(episode)
            return True
        return False

    def others_live(self) -> bool:
        """Whether another live run holds a claim in this folder (its temporary files are not debris)."""
        return any(not self._stale(c) for c in glob.glob(os.path.join(self.folder, "*.claim")))

    def _stale(self, path: str) -> bool:
        try:
            with open(path) as fh:
                owner = json.loads(fh.read() or "{}")
        except (OSError, ValueError):
            return False  # being written right now
        if owner.get("host") != self.host or not isinstance(owner.get("pid"), int):
            return False
        try:
            os.kill(owner["pid"], 0)
        except ProcessLookupError:
            return True
        except PermissionError:
            return False
        return False

    def release(self, episode: str) -> None:
        if episode in self.mine:
            self.mine.discard(episode)
            try:
                os.unlink(self._path(episode))
            except FileNotFoundError:
                pass

    def release_all(self) -> None:
        for episode in list(self.mine):
            self.release(episode)

    def wait_for_others(self, todo: list, bar) -> list:
        """Waits while other runs make the episodes of ``todo``; returns those whose run died."""
        while todo:
            self.waited = True
            left = []
            for sc in todo:
                e = episode_id(sc)
                if os.path.exists(os.path.join(self.folder, e + ".parquet")) and not os.path.exists(self._path(e)):
                    bar.update(1)
                elif os.path.exists(self._path(e)) and not self._stale(self._path(e)):
                    left.append(sc)
                else:
                    return todo  # a claim went stale (or vanished without a file): build what is left
            if not left:
                return []
            todo = left
            time.sleep(CLAIM_POLL_S)
        return []


def _exit_with_parent(parent_pid: int) -> None:
    """Worker initializer: one core's work (:func:`benchmark.parallel.one_core_worker`), and the
    worker ends if this process (its parent) dies, e.g. on SIGKILL."""
    import threading

    from benchmark.parallel import one_core_worker

    one_core_worker()

    def watch():
        while os.getppid() == parent_pid:
            time.sleep(1.0)
        os._exit(1)

    threading.Thread(target=watch, daemon=True).start()


def _frames_of(sc: Scenario) -> int:
    """Frames of a scenario's episode (as the simulation makes them)."""
    from benchmark.world.simulate import duration_of

    return int(np.floor(duration_of(sc) * sc.fps + 1e-9)) + 1


def _run_pool(todo, spec, build, workers, done, frames=None) -> None:
    """Builds ``todo`` in a pool of ``workers`` processes; ``frames`` (a progress bar) hears of every
    tracked frame through a queue the workers put to."""
    import queue as queue_module

    ctx = multiprocessing.get_context("spawn")  # no forked torch/OpenGL state in the workers
    pool = ProcessPoolExecutor(max_workers=workers, mp_context=ctx, initializer=_exit_with_parent,
                               initargs=(os.getpid(),))
    manager = ctx.Manager() if frames is not None else None
    heard = manager.Queue() if manager is not None else None

    def drain():
        while heard is not None:
            try:
                frames.update(heard.get_nowait())
            except queue_module.Empty:
                return

    try:
        pending = {pool.submit(_run_one, sc, spec, build, heard) for sc in todo}
        while pending:
            finished, pending = wait(pending, timeout=0.2, return_when=FIRST_COMPLETED)
            drain()
            for f in finished:
                done(f.result())
    except BaseException:
        pool.shutdown(wait=False, cancel_futures=True)
        if manager is not None:
            manager.shutdown()
        raise
    pool.shutdown(wait=True)
    if manager is not None:
        drain()
        manager.shutdown()


def _run_ray(todo, spec, build, address, done) -> None:
    """Builds ``todo`` as tasks on the Ray cluster at ``address`` (:func:`benchmark.parallel.run_jobs`)."""
    from benchmark.parallel import RayUnavailable, run_jobs

    try:
        for _, table in run_jobs(_run_one_job, [(sc, spec, build) for sc in todo], ray_address=address):
            done(table)
    except RayUnavailable as e:
        raise DatasetError(str(e)) from e


def _run_one_job(job) -> pa.Table:
    """:func:`_run_one` of a ``(scenario, spec, build)`` job."""
    return _run_one(*job)


TIMING_SUFFIX = ".seconds.json"
"""Beside ``episodes/<id>.parquet``: the seconds its build took (not in the table, whose bytes depend
only on the episode: a local pool and a Ray cluster write the same files)."""


def _build_seconds(parquet_path: str) -> float:
    """The build time recorded beside an episode file (NaN if none or unreadable)."""
    try:
        with open(parquet_path[: -len(".parquet")] + TIMING_SUFFIX) as fh:
            return float(json.load(fh)["seconds"])
    except (OSError, ValueError, KeyError, TypeError):
        return float("nan")


MANIFEST_COLUMNS = (
    "episode", "file", "sha256", "task", "user", "grasp", "mass", "seed", "status", "frames", "rows",
    "dropped_contacts", "dropped_gap", "dropped_solver", "seconds", "kinematics", "contacts",
)


def write_manifest(out, checked: dict | None = None) -> pd.DataFrame:
    """Rebuilds ``out/manifest.parquet`` from the episode files present (atomically) and returns it.

    Args:
        out: Dataset folder.
        checked: ``{relative file path: SHA-256 of its bytes}`` of files already checked with
            :func:`read_episode_file` (by the caller); the others are checked here.

    Raises:
        DatasetFileError: If an episode file that was not checked yet fails the check.
    """
    out = os.fspath(out)
    checked = dict(checked or {})
    rows = []
    for path in sorted(glob.glob(os.path.join(out, "episodes", "*.parquet"))):
        rel = os.path.relpath(path, out)
        if rel in checked:
            meta = json.loads(pq.read_schema(path).metadata[b"fsv"])
        else:
            _, meta, checked[rel] = read_episode_file(path)
        sc = meta.pop("scenario")
        rows.append(dict(
            episode=meta["episode"], file=rel, sha256=checked[rel], task=sc["task"], user=sc["user"],
            grasp=sc["grasp"], mass=sc["mass"], seed=sc["seed"], status=meta["status"],
            frames=meta.get("frames", 0), rows=meta.get("rows", 0), dropped_contacts=meta.get("dropped_contacts", 0),
            dropped_gap=meta.get("dropped_gap", 0), dropped_solver=meta.get("dropped_solver", 0),
            seconds=_build_seconds(path), kinematics=meta["kinematics"], contacts=meta["contacts"],
        ))
    manifest = pd.DataFrame(rows, columns=list(MANIFEST_COLUMNS))
    table = pa.Table.from_pandas(manifest, preserve_index=False)
    meta = {b"fsv": json.dumps(dict(format=FORMAT + "-manifest", version=VERSION)).encode()}
    _write_sealed(table.replace_schema_metadata({**(table.schema.metadata or {}), **meta}),
                  os.path.join(out, "manifest.parquet"))
    return manifest


def read_manifest(out) -> pd.DataFrame:
    """Reads ``out/manifest.parquet`` and checks its digest.

    Raises:
        DatasetError: If the folder has no manifest.
        DatasetFileError: If the manifest is corrupt or was written without digests.
    """
    out = os.fspath(out)
    path = os.path.join(out, "manifest.parquet")
    if not os.path.exists(path):
        raise DatasetError(f"{out!r} is not a dataset folder (no manifest.parquet); make one with `fsv-bench generate`")
    with open(path, "rb") as fh:
        data = fh.read()
    _, meta = read_sealed(data, path)
    if meta.get("version") != VERSION:
        raise DatasetFileError(f"{path} is of dataset version {meta.get('version')!r}; this fsv-bench reads {VERSION}")
    return pd.read_parquet(io.BytesIO(data))


def read_episode_frame(out, row) -> pd.DataFrame:
    """One episode's table as a DataFrame, checked against the manifest ``row`` (a mapping with
    ``file`` and ``sha256``) and its own digest (:func:`read_episode_file`)."""
    path = os.path.join(os.fspath(out), row["file"])
    try:
        with open(path, "rb") as fh:
            data = fh.read()
    except OSError as e:
        raise DatasetFileError(f"cannot read {path}: {e}") from e
    read_episode_file(path, row["sha256"], data)
    return pd.read_parquet(io.BytesIO(data))


def load_dataset(out, max_excess_n: float | None = None, **where) -> pd.DataFrame:
    """All kept samples of a dataset as one DataFrame, optionally filtered by scenario fields.

    Every file read is checked: the manifest against its digest, each episode file against the
    SHA-256 of its bytes in the manifest, its own content digest and its name.

    Args:
        out: Dataset folder.
        max_excess_n: If given, also drop the rows whose nominal forces exceed the tactile readings
            by more than this (the plausibility rule, :func:`nominal_excess_n`), [N].
        **where: Column filters, e.g. ``user=[0]`` or ``grasp=1`` (a value or a list of values).

    Raises:
        DatasetFileError: If a file is corrupt, truncated, renamed or without digests (names it).
    """
    out = os.fspath(out)
    man = read_manifest(out)
    man = man[man["status"] == "ok"]
    for key, val in where.items():
        if key not in ("task", "user", "grasp", "mass", "seed"):
            raise DatasetError(f"cannot filter on {key!r}; accepted: task, user, grasp, mass, seed")
        man = man[man[key].isin(val if isinstance(val, (list, tuple, set)) else [val])]
    frames = [read_episode_frame(out, row) for row in man.to_dict("records")]
    frames = [f for f in frames if len(f)]
    if not frames:
        raise DatasetError(f"no samples in {out!r} for {where or 'the whole dataset'}")
    df = pd.concat(frames, ignore_index=True)
    if max_excess_n is not None:
        names = finger_names_of(df)
        col = lambda prefix: df[[f"{prefix}_{n}" for n in names]].to_numpy()
        df = df[nominal_excess_n(col("f_nom"), col("f_meas"), col("active")) <= float(max_excess_n)]
        if df.empty:
            raise DatasetError(f"no samples in {out!r} for {where or 'the whole dataset'} pass max_excess_n={max_excess_n}")
        df = df.reset_index(drop=True)
    return df


def finger_names_of(df: pd.DataFrame) -> tuple:
    """The finger slots of a dataset table, in column order (thumb first)."""
    return tuple(c[len("active_"):] for c in df.columns if c.startswith("active_"))


def training_set(df: pd.DataFrame, grips: dict | None = None):
    """The networks' samples of a dataset table (:class:`fsv.learn.TrainingSet`): features,
    decomposition targets, episode groups, and with ``grips`` (``{user: fsv.grip.GripCalibration}``,
    :func:`benchmark.method.grip_file.read_calibration`) each sample's user's grip calibration."""
    from fsv.learn import TrainingSet  # torch: imported only where it is used, not in the workers
    names = finger_names_of(df)
    grip = None
    if grips is not None:
        users = sorted(int(u) for u in df["user"].unique())
        missing = [u for u in users if u not in grips]
        if missing:
            raise InputError(f"the grip calibration has no user {', '.join(map(str, missing))} of the dataset "
                             f"(it has users {', '.join(map(str, sorted(grips)))})")
        grip = np.stack([grips[int(u)].vector() for u in df["user"].to_numpy()]) if len(df) else np.zeros((0, 2))
    x = np.concatenate([
        df[["p1", "p3"]].to_numpy(float), df[[f"p2_{n}" for n in names]].to_numpy(float),
        df[[f"p4_{n}" for n in names]].to_numpy(float), df[[f"active_{n}" for n in names]].to_numpy(float),
    ], axis=1)
    return TrainingSet(
        x, df[[f"f_int_{n}" for n in names]].to_numpy(float), df[[f"active_{n}" for n in names]].to_numpy(bool),
        groups=pd.factorize(df["episode"])[0], grip=grip,
    )


def frames_of(df: pd.DataFrame) -> tuple[Kinematics, Contacts]:
    """Rebuilds the kinematics and contacts of a dataset table's rows (in row order)."""
    names = finger_names_of(df)
    v = {name: df[[f"{name}_{a}" for a in _AX]].to_numpy(float) for name in ("pos", "vel", "acc", "omega", "alpha")}
    rot = df[[f"rot_{i}{j}" for i in range(3) for j in range(3)]].to_numpy(float).reshape(-1, 3, 3)
    kin = Kinematics(df["t"].to_numpy(float), v["pos"], rot, v["vel"], v["acc"], v["omega"], v["alpha"],
                     np.ones(len(df), bool), method="dataset")
    per = lambda fmt: np.stack([df[[fmt.format(a, n) for a in _AX]].to_numpy(float) for n in names], axis=1)
    con = Contacts(
        names, df[[f"active_{n}" for n in names]].to_numpy(bool), df[[f"sliding_{n}" for n in names]].to_numpy(bool),
        per("point_{}_{}"), per("normal_{}_{}"), per("slide_{}_{}"),
    )
    return kin, con


def _ints(text: str) -> tuple:
    """Parses "0,2,5-7" into (0, 2, 5, 6, 7)."""
    out = []
    for part in str(text).split(","):
        part = part.strip()
        try:
            if "-" in part:
                a, b = part.split("-")
                out += range(int(a), int(b) + 1)
            else:
                out.append(int(part))
        except ValueError:
            raise DatasetError(f"expected integers like '0,2,5-7', got {text!r}") from None
    return tuple(out)


def add_arguments(p: argparse.ArgumentParser) -> None:
    """The arguments of ``fsv-bench generate``."""
    p.add_argument("--out", required=True, help="dataset folder (created, or resumed if it exists)")
    p.add_argument("--tasks", default="lift", help="comma-separated task names (default: lift)")
    p.add_argument("--users", default="0", help="user indices, e.g. 0,1 or 0-3")
    p.add_argument("--grasps", default="0", help="grasp indices")
    p.add_argument("--masses", default="0", help="mass indices")
    p.add_argument("--seeds", default="0", help="seeds, e.g. 0-9")
    p.add_argument("--duration", type=float, default=None, help="episode length in seconds (default: the task's)")
    p.add_argument("--noise", type=float, default=0.01, help="depth noise in metres (sets the pose errors; default 0.01)")
    p.add_argument("--kinematics", default="algebraic", choices=KINEMATICS, help="kinematics source (default: algebraic)")
    p.add_argument("--contacts", default="tracker", choices=CONTACTS,
                   help="contacts (and poses) source: tracker (render and track every episode, the method; "
                        "default), error-model (truth + the paper's contact error, tracker-like poses; cheaper) "
                        "or oracle (the truth's contacts; an ablation)")
    p.add_argument("--workers", type=int, default=None, help="local worker processes (default: all cores)")
    p.add_argument("--ray-address", default=None, help="run on a Ray cluster at this address (needs the 'ray' extra)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")


def run(args: argparse.Namespace) -> pd.DataFrame:
    """Runs ``fsv-bench generate`` with parsed arguments; prints a one-paragraph summary."""
    spec = DatasetSpec(
        tasks=tuple(t.strip() for t in args.tasks.split(",") if t.strip()), users=_ints(args.users),
        grasps=_ints(args.grasps), masses=_ints(args.masses), seeds=_ints(args.seeds), duration_s=args.duration,
        noise_m=args.noise, kinematics=args.kinematics, contacts=args.contacts,
    )
    from benchmark.suites.evaluate import check_out

    check_out(pathlib.Path(args.out))
    t0 = time.perf_counter()
    man = generate(spec, args.out, workers=args.workers, ray_address=args.ray_address, progress=not args.no_progress)
    failed = int((man["status"] != "ok").sum())
    print(
        f"dataset {args.out}: {len(man)} episodes ({failed} failed), {int(man['rows'].sum())} samples kept; "
        f"dropped {int(man['dropped_gap'].sum())} for |vision - tactile net force| > {spec.max_gap_n} N, "
        f"{int(man['dropped_contacts'].sum())} with < {spec.min_fingers} fingers or invalid kinematics, "
        f"{int(man['dropped_solver'].sum())} unsolved; kinematics={spec.kinematics}, contacts={spec.contacts} "
        f"(oracle = from the truth; error-model = truth + the paper's contact error; tracker = rendered and tracked); {time.perf_counter() - t0:.1f} s"
    )
    return man
