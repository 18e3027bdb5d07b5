"""A dataset's files: sealed episode tables, ``dataset.json``, the manifest, and reading them back."""

from __future__ import annotations

import glob
import io
import json
import os
import sys
from dataclasses import asdict

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq

from benchmark.atomic import claim_folder, remove_stale_temporaries, write_bytes, write_text
from benchmark.errors import DatasetError, DatasetFileError
from benchmark.fingerprint import world_fingerprint
from benchmark.paper.dataset.spec import _AX, FORMAT, ROWS, VERSION, DatasetSpec
from benchmark.scores.samples import nominal_excess_n
from benchmark.sealed_table import file_sha256, read_sealed, seal, to_bytes
from benchmark.world.scenario import DEFAULT_GRIP_CONTROL, DEFAULT_HAND_SURFACE, episode_name
from fsv import Contacts, InputError, Kinematics
from fsv.learn import TrainingSet
from fsv.provenance import provenance


def _write_sealed(table: pa.Table, path: str) -> str:
    """Seals ``table`` (:func:`benchmark.sealed_table.seal`), writes it atomically and returns the
    SHA-256 of the bytes written."""
    data = to_bytes(seal(table))
    write_bytes(path, data)
    return file_sha256(data)


def read_header(out) -> dict:
    """A dataset folder's ``dataset.json`` (its spec, sources, format and world).

    Raises:
        DatasetFileError: Naming the file when it is missing, not JSON, or not a dataset's header.
    """
    path = os.path.join(os.fspath(out), "dataset.json")
    try:
        with open(path) as fh:
            header = json.load(fh)
    except (OSError, ValueError) as e:
        raise DatasetFileError(f"{path} is not a readable dataset header (made by `fsv-bench generate`): {e}") from e
    if not isinstance(header, dict) or not isinstance(header.get("spec"), dict):
        raise DatasetFileError(f"{path} is not a dataset header: it has no \"spec\" object")
    return header


def made_by_generate(out) -> bool:
    """Whether ``out`` is a real folder (not a link) holding a dataset header of this format: a
    dataset of ``fsv-bench generate``, perhaps of a version before folders carried
    :data:`benchmark.atomic.OUTPUT_MARKER`, which ``generate`` resumes and then marks.

    Raises:
        DatasetFileError: Naming ``dataset.json`` when it is there but damaged (:func:`read_header`).
    """
    path = os.path.join(os.fspath(out), "dataset.json")
    if os.path.islink(os.fspath(out)) or not os.path.isfile(path):
        return False
    return read_header(out).get("format") == FORMAT


def _prepare(spec: DatasetSpec, out: str) -> str:
    claim_folder(out, adopt=made_by_generate(out))  # new, empty, or fsv-bench's: never a user's folder
    episodes = os.path.join(out, "episodes")
    os.makedirs(episodes, exist_ok=True)
    for folder in (out, episodes):  # a killed run's half-written files (a live run's are kept)
        remove_stale_temporaries(folder, owner=out)

    header = dict(format=FORMAT, version=VERSION, spec=spec.as_dict(), world=world_fingerprint())
    path = os.path.join(out, "dataset.json")
    if os.path.exists(path):
        old = read_header(out)
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
    stem = f"{sc.get('task')}-u{sc.get('user')}-g{sc.get('grasp')}-m{sc.get('mass')}-s{sc.get('seed')}"
    return (stem + (f"-v{sc['view']}" if sc.get("view") else "")
            + (f"-{sc['hand_surface']}" if sc.get("hand_surface", DEFAULT_HAND_SURFACE) != DEFAULT_HAND_SURFACE else "")
            + (f"-{sc['grip_control']}" if sc.get("grip_control", DEFAULT_GRIP_CONTROL) != DEFAULT_GRIP_CONTROL else ""))


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
    expected = {episode_name(sc): sc for sc in spec.scenarios()}
    good, bad = {}, 0
    for path in sorted(glob.glob(os.path.join(episodes, "*.parquet"))):
        rel = os.path.relpath(path, out)
        try:
            _, meta, digest = read_episode_file(path, listed.get(rel))
            sc = expected.get(meta["episode"])
            if sc is not None and (meta.get("scenario") != asdict(sc) or meta.get("kinematics") != spec.kinematics
                                   or meta.get("contacts") != spec.contacts or meta.get("sample_rows") != spec.rows):
                raise DatasetFileError(f"{path} holds episode {meta['episode']} made with another scenario, "
                                       f"sources or rows ({meta.get('scenario')}, {meta.get('kinematics')}, "
                                       f"{meta.get('contacts')}, rows {meta.get('sample_rows')})")
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


def load_dataset(out, max_excess_n: float | None = None, *, rows: str = "paper", **where) -> pd.DataFrame:
    """All kept samples of a dataset as one DataFrame, optionally filtered by scenario fields.

    Every file read is checked: the manifest against its digest, each episode file against the
    SHA-256 of its bytes in the manifest, its own content digest and its name.

    Args:
        out: Dataset folder.
        max_excess_n: If given, also drop the rows whose nominal forces exceed the tactile readings
            by more than this (the plausibility rule, :func:`nominal_excess_n`), [N].
        rows: "paper": the rows the paper's sample rules keep (column ``paper_rule``; every row of
            a dataset made with ``rows="paper"``), those the internal-force networks learn from;
            "all": every row (of a dataset made with ``rows="all"``: every frame with kinematics).
        **where: Column filters, e.g. ``user=[0]`` or ``grasp=1`` (a value or a list of values).

    Raises:
        DatasetFileError: If a file is corrupt, truncated, renamed or without digests (names it).
    """
    if rows not in ROWS:
        raise DatasetError(f"rows must be one of {ROWS}, got {rows!r}")
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
    if rows == "paper" and "paper_rule" in df.columns and not df["paper_rule"].all():
        df = df[df["paper_rule"].to_numpy(bool)].reset_index(drop=True)
        if df.empty:
            raise DatasetError(f"no samples in {out!r} for {where or 'the whole dataset'} under the paper's rule")
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


