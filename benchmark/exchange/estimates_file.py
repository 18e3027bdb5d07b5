"""The estimates file: one episode's per-frame estimates of a method, written in any language.

FORMAT_DOC is the specification (also in docs/formats.md).
"""

from __future__ import annotations

import pathlib

import numpy as np

from benchmark.archive import read_archive, write_archive
from benchmark.errors import BenchmarkError

FORMAT = "fsv-bench-estimates"
VERSION = 1
FORMAT_DOC = """\
An estimates file is a NumPy ``.npz`` archive of arrays named ``<section>/<field>`` plus a
``meta.json`` entry: a uint8 array of UTF-8 JSON. T frames (the camera-input file's), K fingers
(its hand's ``finger_names``, thumb first). Object frame: the box's centre of mass, axes along its
edges. Digests (``array_sha256``, ``meta_sha256``, as in :mod:`benchmark.archive`) are optional for
files written by other programs; when present they are checked.

    box/pos            (T, 3)     float  box centre in the world, [m]                    required
    box/rot            (T, 3, 3)  float  world_R_box                                     required
    contacts/active    (T, K)     bool   finger k touches the box at frame i             required
    contacts/sliding   (T, K)     bool   that contact slides (subset of active)          required
    contacts/point     (T, K, 3)  float  contact point, object frame, [m]                required
    contacts/normal    (T, K, 3)  float  unit normal into the box, object frame          required
    kinematics/vel, acc, omega, alpha  (T, 3)  world frame, [m/s, m/s^2, rad/s, rad/s^2] required
    kinematics/valid   (T,)       bool   frames whose derivatives are defined            required
    kinematics/pos     (T, 3), kinematics/rot (T, 3, 3)  the filtered pose; default box/*  optional
    nominal/force      (T, K, 3)  float  nominal finger forces on the box, object frame, [N]  optional
    nominal/env_wrench (T, 6)     float  table force and torque about the COM, object frame   optional
    nominal/status     (T,)       int8   0 solved, 1 least violation, 2 no contacts,
                                         3 no kinematics, 4 failed, 5 solved with static
                                         friction, 6 above the physical bound, 7 solved
                                         with contacts added (fsv.forces.FrameStatus)     optional
    forces/force, forces/env_wrench, forces/status   the method's final forces, as nominal/*  optional
    hand/fingertips    (T, K, 3)  float  fingertip pad centres in the world, [m]          optional

Physics is checked before scoring: rotations orthonormal with determinant +1 (within 1e-5),
positions finite, an active contact's point finite and its normal of unit length (within 1e-5),
sliding only where active, the kinematics finite where valid, forces finite or NaN (unsolved),
never infinite. A file that fails names the array and the first bad frame.

``meta.json``: ``{"format": "fsv-bench-estimates", "version": 1, "episode": NAME, "finger_names":
[K names], "method": "one line naming the method", "stages": {"tracker": ..., ...}}``; ``episode``
(required) must be the name the file is found under; ``suite`` and ``world``, copied from the
camera-input file's meta, are optional and checked when present. Metrics of a
missing optional group are not scored (NaN); a gate on them fails.
"""


class EstimatesFileError(BenchmarkError, ValueError):
    """An estimates file is missing, damaged, of another format, or does not fit its episode."""


ROTATION_TOL = 1e-5
"""How far a rotation matrix of an estimates file may be from a rotation: max |R^T R - I| and
|det R - 1| (a float32 writer's rounding is ~1e-7; a scaled or reflected matrix is far beyond)."""

UNIT_TOL = 1e-5
"""How far an active contact's normal may be from unit length."""


def check_identity(path, meta: dict, *, episode: str, suite, world: str | None = None,
                   knowledge: str | None = None) -> None:
    """Refuses an estimates file of another episode: ``meta["episode"]`` must be ``episode`` (the name
    the file is found under); ``meta["suite"]`` (``{"name", "version"}``), ``meta["world"]`` and
    ``meta["knowledge"]`` (the camera-input file's ``knowledge.knowledge``), copied from the
    camera-input file, must match where the file carries them.

    Raises:
        EstimatesFileError: Naming the file and what it holds instead.
    """
    held = meta.get("episode")
    if held != episode:
        raise EstimatesFileError(f"{path}: meta.json names episode {held!r}, not {episode!r}: the estimates of "
                                 "another episode (a renamed or copied file), or no \"episode\" entry")
    if "suite" in meta and meta["suite"] != {"name": suite.name, "version": suite.version}:
        raise EstimatesFileError(f"{path}: meta.json names suite {meta['suite']}, not "
                                 f"{{'name': {suite.name!r}, 'version': {suite.version}}}")
    if world is not None and "world" in meta and meta["world"] != world:
        raise EstimatesFileError(f"{path}: made for another world (meta.json world {str(meta['world'])[:12]}..., this "
                                 f"benchmark's {world[:12]}...): export the camera inputs again")
    if knowledge is not None and "knowledge" in meta and meta["knowledge"] != knowledge:
        raise EstimatesFileError(f"{path}: made from camera inputs with --knowledge {meta['knowledge']}, scored with "
                                 f"--knowledge {knowledge}: score with --knowledge {meta['knowledge']}")


def check_physics(path, box, contacts, kinematics, solutions: dict) -> None:
    """Refuses estimates that are not physical, naming the file, the array and the first bad frame.

    Rotations (``box/rot``, ``kinematics/rot``, finite as read) orthonormal with determinant +1
    within :data:`ROTATION_TOL`; an active contact's point finite and normal of unit
    length (:data:`UNIT_TOL`); the kinematics finite where valid; forces
    finite or NaN (an unsolved frame), never infinite.

    Raises:
        EstimatesFileError: The first violation found.
    """
    def bad(name, mask, what):
        i = int(np.flatnonzero(mask)[0])
        raise EstimatesFileError(f"{path}: {name} at frame {i} {what}")

    for name, rot in (("box/rot", box.rot), ("kinematics/rot", kinematics.rot)):
        gram = np.abs(np.einsum("tki,tkj->tij", rot, rot) - np.eye(3)).max(axis=(1, 2))
        det = np.linalg.det(rot)
        wrong = (gram > ROTATION_TOL) | (np.abs(det - 1.0) > ROTATION_TOL)
        if wrong.any():
            i = int(np.flatnonzero(wrong)[0])
            bad(name, wrong, f"is not a rotation (max |R^T R - I| = {gram[i]:.3g}, det = {det[i]:.6g}); "
                             f"expected orthonormal with determinant +1 within {ROTATION_TOL:g}")
    act = contacts.active
    point_ok = np.isfinite(contacts.point).all(axis=2) | ~act
    if not point_ok.all():
        bad("contacts/point", ~point_ok.all(axis=1), "is not finite for an active finger")
    length = np.linalg.norm(contacts.normal, axis=2)
    unit = (np.abs(length - 1.0) <= UNIT_TOL) | ~act
    if not unit.all():
        bad("contacts/normal", ~unit.all(axis=1), f"is not a unit vector for an active finger (within {UNIT_TOL:g})")
    for f in ("vel", "acc", "omega", "alpha"):
        v = getattr(kinematics, f)
        ok = np.isfinite(v).all(axis=1) | ~kinematics.valid
        if not ok.all():
            bad(f"kinematics/{f}", ~ok, "is not finite where kinematics/valid is true")
    for group, sol in solutions.items():
        for name, v in (("force", sol.force), ("env_wrench", sol.env_wrench)):
            inf = np.isinf(v).reshape(len(v), -1).any(axis=1)
            if inf.any():
                bad(f"{group}/{name}", inf, "is infinite (NaN marks an unsolved frame)")


def save_estimate(estimate, path, *, episode: str, method: str, knowledge: str | None = None) -> pathlib.Path:
    """Writes an ``fsv.method.Estimate`` as an estimates file (with digests).

    Args:
        estimate: The estimate.
        path: Destination ``.npz``.
        episode: The episode's name in its suite.
        method: One line naming the method.
        knowledge: The camera-input file's knowledge (its meta's ``knowledge.knowledge``), if known:
            ``fsv-bench score`` then refuses to score it under another.
    """
    c, k = estimate.contacts, estimate.kinematics
    arrays = {"box/pos": estimate.box.pos, "box/rot": estimate.box.rot,
              "contacts/active": c.active, "contacts/sliding": c.sliding, "contacts/point": c.point,
              "contacts/normal": c.normal, "contacts/slide_dir": c.slide_dir}
    arrays.update({f"kinematics/{f}": getattr(k, f) for f in ("pos", "rot", "vel", "acc", "omega", "alpha", "valid")})
    for group, sol in (("nominal", estimate.nominal), ("forces", estimate.forces)):
        if sol is not None:
            arrays.update({f"{group}/force": sol.force, f"{group}/env_wrench": sol.env_wrench,
                           f"{group}/status": sol.status})
    if estimate.fingertips is not None:
        arrays["hand/fingertips"] = np.asarray(estimate.fingertips, float)
    meta = {"episode": episode, "finger_names": list(c.finger_names), "method": method,
            "stages": dict(estimate.labels), "oracle": list(estimate.oracle)}
    if knowledge is not None:
        meta["knowledge"] = knowledge
    return write_archive(path, FORMAT, VERSION, meta, arrays)


def load_estimate(path, *, t: np.ndarray, finger_names: tuple):
    """Reads an estimates file as an ``fsv.method.Estimate`` for an episode of frame times ``t``.

    Forces come back as ``fsv.forces.ForceSolution`` with what the file holds (force, table
    wrench, status); fields a file does not carry (required wrench, residual, objective) are NaN.

    Raises:
        EstimatesFileError: If the file is missing or damaged, of another format, or its frames or
            fingers do not match the episode's (the message names the array).
    """
    from fsv import Contacts, FsvError, Kinematics, Poses
    from fsv.method import Estimate, TrackOutput

    meta, s = read_archive(path, FORMAT, VERSION, kind="estimates", error=EstimatesFileError, digests_required=False)
    names = tuple(meta.get("finger_names") or ())
    if names != tuple(finger_names):
        raise EstimatesFileError(f"{path}: finger_names {list(names)} do not match the episode's {list(finger_names)}")
    T, K = len(t), len(names)

    def get(section, name, shape, dtype=float, default=None, finite=False):
        value = s.get(section, {}).get(name)
        if value is None:
            if default is not None:
                return default
            raise EstimatesFileError(f"{path}: required array {section}/{name} is missing")
        value = np.asarray(value)
        if value.shape != shape:
            raise EstimatesFileError(f"{path}: {section}/{name} has shape {value.shape}, expected {shape}")
        if dtype is bool and not np.isin(value, (0, 1)).all():
            raise EstimatesFileError(f"{path}: {section}/{name} must hold booleans (0/1)")
        value = value.astype(dtype)
        if finite and not np.isfinite(value).all():
            i = int(np.flatnonzero(~np.isfinite(value).reshape(len(value), -1).all(axis=1))[0])
            raise EstimatesFileError(f"{path}: {section}/{name} at frame {i} is not finite")
        return value

    try:
        box = Poses(t=t, pos=get("box", "pos", (T, 3), finite=True), rot=get("box", "rot", (T, 3, 3), finite=True))
        zeros = np.zeros((T, K, 3))
        active, sliding = get("contacts", "active", (T, K), bool), get("contacts", "sliding", (T, K), bool)
        if (sliding & ~active).any():
            i = int(np.flatnonzero((sliding & ~active).any(axis=1))[0])
            raise EstimatesFileError(f"{path}: contacts/sliding at frame {i} marks a finger that is not active")
        contacts = Contacts(finger_names=names, active=active, sliding=sliding,
                            point=get("contacts", "point", (T, K, 3)), normal=get("contacts", "normal", (T, K, 3)),
                            slide_dir=get("contacts", "slide_dir", (T, K, 3), default=zeros))
        kin = Kinematics(t=t, pos=get("kinematics", "pos", (T, 3), default=box.pos, finite=True),
                         rot=get("kinematics", "rot", (T, 3, 3), default=box.rot, finite=True),
                         **{f: get("kinematics", f, (T, 3)) for f in ("vel", "acc", "omega", "alpha")},
                         valid=get("kinematics", "valid", (T,), bool), method=str(meta.get("stages", {}).get(
                             "differentiator", "")))
        solutions = {}
        for group, kind in (("nominal", "nominal"), ("forces", "reconstruction")):
            if group in s:
                solutions[group] = _solution(kind, contacts, get(group, "force", (T, K, 3)),
                                             get(group, "env_wrench", (T, 6)), get(group, "status", (T,), np.int8))
        tips = s.get("hand", {}).get("fingertips")
        tracking = TrackOutput(box=box, contacts=contacts,
                               fingertips=None if tips is None else get("hand", "fingertips", (T, K, 3)))
    except FsvError as e:
        raise EstimatesFileError(f"{path}: {e}") from e
    check_physics(path, box, contacts, kin, solutions)
    return Estimate(tracking=tracking, contacts=contacts, kinematics=kin, nominal=solutions.get("nominal"),
                    forces=solutions.get("forces"), internal_pred=None, oracle=tuple(meta.get("oracle", ())),
                    timing_s={}, labels=dict(meta.get("stages", {})))


def _solution(kind: str, contacts, force: np.ndarray, env_wrench: np.ndarray, status: np.ndarray):
    from fsv.forces import ForceSolution

    T, K = contacts.active.shape
    nan6 = np.full((T, 6), np.nan)
    return ForceSolution(kind=kind, finger_names=contacts.finger_names, active=contacts.active,
                         sliding=contacts.sliding, point=contacts.point, normal=contacts.normal, force=force,
                         nominal=force, internal=np.zeros((T, K, 3)),
                         env_active=(np.abs(env_wrench[:, :3]).sum(axis=1) > 0).astype(np.int64),
                         env_wrench=env_wrench, env_internal_wrench=np.zeros((T, 6)), required=nan6,
                         residual=nan6, status=status, objective=np.full(T, np.nan), iterations=np.zeros(T, np.int64),
                         solve_time_s=np.zeros(T))
