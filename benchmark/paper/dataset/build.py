"""Building a dataset: each episode simulated (rendered and tracked), its samples and targets, on a pool or Ray."""

from __future__ import annotations

import json
import os
import sys
import time
from dataclasses import asdict

import numpy as np
import pandas as pd
import pyarrow as pa

from benchmark.atomic import write_text
from benchmark.errors import BenchmarkError, DatasetError
from benchmark.method import camera_input
from benchmark.paper.dataset.claims import Claims
from benchmark.paper.dataset.files import (
    TIMING_SUFFIX,
    _check_existing,
    _prepare,
    _write_sealed,
    write_manifest,
)
from benchmark.paper.dataset.spec import (
    _AX,
    CONTACTS,
    FORMAT,
    VERSION,
    DatasetSpec,
)
from benchmark.parallel import (
    RayUnavailable,
    check_ray_address,
    report_progress,
    run_jobs,
)
from benchmark.scores.forces import true_normal_forces
from benchmark.scores.samples import DATASET_FORCE_SETTINGS, sample_mask
from benchmark.scores.samples import take_contacts as _take_con
from benchmark.scores.samples import take_kinematics as _take_kin
from benchmark.world.contact_error import contacts_from_truth, vision_like_contacts
from benchmark.world.motion import episode_kinematics
from benchmark.world.scenario import Scenario, episode_name
from benchmark.world.tactile import tactile_normal_forces
from fsv import Contacts
from fsv.features import grasp_features
from fsv.forces import FrameStatus, decompose_forces, to_object_frame
from fsv.method import ReferenceTracker
from fsv.method.reference import TRACKED_POSES

TRAINING_KNOWLEDGE = "exact"
"""What the tracker is told when a dataset is made: the simulation's own hand, box and camera (a
choice: the dataset's features are then in the true world frame that the tactile targets are in;
a lab's own recordings would carry its calibration errors, which the method meets at test time
only, under the default ``lab`` knowledge)."""


def track_episode(episode):
    """Renders a simulated episode and tracks it from depth alone with the method's tracker stage,
    as ``fsv-bench --knowledge exact`` does (same camera inputs, same random streams):
    ``(rendered episode, Tracking)``."""
    from benchmark.camera.render import render  # lazy: MuJoCo (0.25 s) off `fsv-bench generate`'s start-up

    ep = render(episode)
    return ep, ReferenceTracker(on_frame=report_progress)(camera_input(ep, knowledge=TRAINING_KNOWLEDGE),
                                                    ep.scenario.rng("tracker"))


def episode_contacts(episode, source: str, tracking=None) -> Contacts:
    """The contacts behind the features: "tracker" (``tracking.contacts``), "oracle" (the truth's)
    or "error-model" (the truth's moved by the paper's contact-point error model,
    ``benchmark.world.contact_error``)."""

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
    from benchmark.world.simulate import simulate  # lazy: MuJoCo (0.25 s) off `fsv-bench generate`'s start-up

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
    paper = idx[ok]  # the frames the paper's rules keep, with their targets
    rows = paper if spec.rows == "paper" else np.flatnonzero(kin.valid)
    paper_rule = np.isin(rows, paper)  # rows and paper ascend: rows[paper_rule] is paper, in order
    stats = dict(
        frames=len(tr.t), rows=int(len(rows)), paper_rows=int(len(paper)), dropped_contacts=int(np.sum(~keep_contacts)),
        dropped_gap=int(np.sum(keep_contacts & ~keep)), dropped_solver=int(np.sum(~ok)),
    )
    cols = _columns(scenario, tr, kin, con, feats, measured, true_normal_forces(tr), gap, rows)
    cols["paper_rule"] = paper_rule
    names = tuple(tr.finger_names)
    for k, name in enumerate(names):
        for prefix, values in (("f_nom", dec.nominal_normal), ("f_int", dec.internal_normal)):
            col = np.full(len(rows), np.nan)
            col[paper_rule] = values[ok, k]
            cols[f"{prefix}_{name}"] = col
    stats["object_model"] = dict(
        size_m=model.size_m.tolist(), mass_kg=model.mass_kg, inertia=model.inertia.tolist(),
        friction=model.friction, table_friction=model.table_friction,
    )
    stats["gravity"] = np.asarray(tr.gravity, float).tolist()
    if tracking is not None:
        from benchmark.scores.tracking import (  # lazy: scipy.stats (0.4 s) off `fsv-bench generate`'s start-up
            score_tracking,
        )

        stats["tracking"] = score_tracking(tracking, tr)
    return _with_meta(pa.table(cols), scenario, spec, names, stats, status="ok")


def _columns(sc, tr, kin, con, feats, measured, true_normal, gap, rows) -> dict:
    n = len(rows)
    cols = dict(
        episode=np.full(n, episode_name(sc)), task=np.full(n, sc.task), user=np.full(n, sc.user),
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
        true_force = np.where(np.asarray(tr.contact_active, bool)[rows, k, None],
                              np.asarray(tr.contact_force, float)[rows, k], 0.0)
        for a in range(3):
            cols[f"F_true_{_AX[a]}_{name}"] = true_force[:, a]
    env = table_wrench_in_object_frame(tr)[rows]
    for a in range(3):
        cols[f"env_F_{_AX[a]}"] = env[:, a]
    for a in range(3):
        cols[f"env_T_{_AX[a]}"] = env[:, 3 + a]
    cols["net_gap_n"] = gap[rows]
    return cols


def table_wrench_in_object_frame(truth) -> np.ndarray:
    """The table's force and torque on the box about its centre of mass, in the object frame
    (along the box's edges, by the true orientation), shape (T, 6), [N, N m]; the truth records
    them in the world frame."""
    wrench = np.concatenate([np.asarray(truth.env_force, float), np.asarray(truth.env_torque, float)], axis=1)
    return to_object_frame(truth.box_rot, wrench)


def _with_meta(table: pa.Table, sc: Scenario, spec: DatasetSpec, finger_names, stats: dict, status: str) -> pa.Table:
    meta = dict(
        format=FORMAT, version=VERSION, episode=episode_name(sc), scenario=asdict(sc), finger_names=list(finger_names),
        kinematics=spec.kinematics, contacts=spec.contacts, sample_rows=spec.rows, status=status, **stats,
    )
    return table.replace_schema_metadata({b"fsv": json.dumps(meta).encode()})


def _run_one(scenario: Scenario, spec: DatasetSpec, build) -> pa.Table:
    """Builds one episode's table in a worker; a world failure becomes an empty table with the error.

    Every tracked frame is reported to the caller's progress bar (:func:`benchmark.parallel.report_progress`).
    """
    t0 = time.perf_counter()
    try:
        table = build(scenario, spec)
    except BenchmarkError as e:
        table = _with_meta(pa.table({"episode": pa.array([], pa.string())}), scenario, spec, [], dict(frames=0, rows=0),
                           status=f"failed: {type(e).__name__}: {e}")
    meta = json.loads(table.schema.metadata[b"fsv"])
    meta["seconds"] = time.perf_counter() - t0
    return table.replace_schema_metadata({b"fsv": json.dumps(meta).encode()})


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
    todo = [sc for sc in spec.scenarios() if os.path.join("episodes", episode_name(sc) + ".parquet") not in written]
    total = len(spec.scenarios())
    from tqdm.auto import tqdm  # lazy: tqdm (30 ms) off `fsv-bench generate`'s start-up

    bar = tqdm(total=total, initial=total - len(todo), unit="episode", desc="generate", disable=not progress, file=sys.stderr)
    tracked = spec.contacts == "tracker" and build is build_episode and ray_address is None
    frames = tqdm(total=sum(_frames_of(sc) for sc in todo), unit="frame", desc="tracked", position=1, leave=True,
                  disable=not (progress and tracked), file=sys.stderr)  # per frame across the episodes
    claims = Claims(out)

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
            mine = [sc for sc in todo if claims.take(episode_name(sc))]  # episodes another live run makes are skipped
            local = 1 if len(mine) <= 1 else min(int(workers or os.cpu_count() or 1), len(mine))
            jobs = [(sc, spec, build) for sc in mine]
            try:
                for _, table in run_jobs(_run_one_job, jobs, workers=local, ray_address=ray_address,
                                         on_progress=frames.update if tracked and progress else None):
                    done(table)
            except RayUnavailable as e:
                raise DatasetError(str(e)) from e
            todo = [sc for sc in todo if sc not in mine]
            todo = claims.wait_for_others(todo, bar)  # until their files appear, or their runs die (then ours)
    finally:
        claims.release_all()
        frames.close()
        bar.close()
    return write_manifest(out, _check_existing(spec, out, episodes) if claims.waited else written)


def _frames_of(sc: Scenario) -> int:
    """Frames of a scenario's episode (as the simulation makes them)."""
    from benchmark.world.simulate import duration_of  # lazy: MuJoCo (0.25 s) off `fsv-bench generate`'s start-up

    return int(np.floor(duration_of(sc) * sc.fps + 1e-9)) + 1


def _run_one_job(job) -> pa.Table:
    """:func:`_run_one` of a ``(scenario, spec, build)`` job."""
    return _run_one(*job)


