"""The estimates file: one episode's per-frame estimates of a method, written in any language.

FORMAT_DOC is the specification (also in docs/formats.md).
"""

from __future__ import annotations

import pathlib

import numpy as np

from benchmark.archive import read_archive, write_archive
from benchmark.errors import BenchmarkError
from benchmark.world.scenario import MAX_DURATION_S, MAX_FPS
from fsv import Contacts, FsvError, Kinematics, Poses
from fsv.forces import ForceSolution, FrameStatus
from fsv.method import Estimate, TrackOutput

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
    contacts/slide_dir (T, K, 3)  float  sliding direction, object frame; default 0      optional
                                         (required where a contact slides)
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

Types, exactly: float is float64 or float32 (not float16, complex, integer or boolean); bool is
bool, or uint8 holding only 0 and 1 (for writers without a boolean type); a status is an integer
type (int8 by fsv-bench) whose every value is one of the eight above. No other entry is read: an
array not listed here, or of other than the episode's T frames (at most MAX_FRAMES) and K fingers
(at most MAX_FINGERS), is refused from its header, before its data is read.

Physics is checked before scoring: rotations orthonormal with determinant +1 (within 1e-5),
positions finite and in the scene (box, filtered pose and fingertips within SCENE_BOUND_M = 5 m of
the world origin; an active contact's point within CONTACT_BOUND_M = 1 m of the box's centre), an
active contact's normal of unit length (within 1e-5), sliding only where active, the kinematics
finite and below KINEMATICS_BOUND (1e6 in SI units) where valid, forces finite or NaN (unsolved),
never infinite, and no finger force or table force above FORCE_WEIGHTS = 1000 times the heaviest
box's weight (sim_assets/masses.yaml; 6.5 kN), no table torque above that force times 1 m. A file
that fails names the array and the first bad frame.

``meta.json``: ``{"format": "fsv-bench-estimates", "version": 1, "episode": NAME, "finger_names":
[K names], "method": "one line naming the method", "stages": {"tracker": ..., ...}}``; ``episode``
(required) must be the name the file is found under; ``suite`` and ``world``, copied from the
camera-input file's meta, are optional and checked when present; so are ``knowledge`` and
``oracle`` (a list of stage names). ``version`` is the integer 1; names (``episode``, ``method``,
each finger, stage and label) are one printable line of at most MAX_NAME_CHARS = 1000 characters;
``stages`` maps names to labels; no other key is read (one is refused). Metrics of a missing
optional group are not scored: every episode counts at the metric's worst value
(docs/suites.md, "Every episode counts"), and a gate on them fails.
"""


class EstimatesFileError(BenchmarkError, ValueError):
    """An estimates file is missing, damaged, of another format, or does not fit its episode."""


ROTATION_TOL = 1e-5
"""How far a rotation matrix of an estimates file may be from a rotation: max |R^T R - I| and
|det R - 1| (a float32 writer's rounding is ~1e-7; a scaled or reflected matrix is far beyond)."""

UNIT_TOL = 1e-5
"""How far an active contact's normal may be from unit length."""

MAX_FRAMES = int(MAX_DURATION_S * MAX_FPS) + 1
"""The most frames an estimates array may have: the longest episode at the highest frame rate
(:data:`benchmark.world.scenario.MAX_DURATION_S`, ``MAX_FPS``); an array's size is bounded by it."""

MAX_FINGERS = 10
"""The most fingers (``finger_names``) an estimates file may name."""

MAX_NAME_CHARS = 1000
"""The longest name in ``meta.json`` (a method, a stage label, a finger), [characters]: fsv-bench's
longest method line is about 300."""

SCENE_BOUND_M = 5.0
"""How far from the world origin (the table top under the box's start) a world position may be,
[m]: the scene (table, hand, camera at about 0.55 m) is within a metre of it."""

CONTACT_BOUND_M = 1.0
"""How far from the box's centre an active contact point may be, object frame, [m] (the boxes'
half-diagonals are a few centimetres)."""

KINEMATICS_BOUND = 1e6
"""The largest velocity, acceleration, angular velocity or angular acceleration norm accepted where
valid, SI units: far beyond a hand's motion and a noisy finite difference (1 cm of noise at
240 fps is about 6e2 m/s^2), far below where squared errors overflow."""

FORCE_WEIGHTS = 1000.0
"""The largest finger or table force accepted, in weights of the heaviest box
(``sim_assets/masses.yaml``): no hand pushes so; a table torque is bounded by it times 1 m."""

ARRAYS = {
    "box/pos": ("float", (3,)), "box/rot": ("float", (3, 3)),
    "contacts/active": ("bool", ("K",)), "contacts/sliding": ("bool", ("K",)),
    "contacts/point": ("float", ("K", 3)), "contacts/normal": ("float", ("K", 3)),
    "contacts/slide_dir": ("float", ("K", 3)),
    **{f"kinematics/{f}": ("float", (3,)) for f in ("pos", "vel", "acc", "omega", "alpha")},
    "kinematics/rot": ("float", (3, 3)), "kinematics/valid": ("bool", ()),
    **{f"{g}/{f}": spec for g in ("nominal", "forces") for f, spec in
       (("force", ("float", ("K", 3))), ("env_wrench", ("float", (6,))), ("status", ("status", ())))},
    "hand/fingertips": ("float", ("K", 3)),
}
"""Every array of the format: ``name: (type, shape after the frame axis)``, ``"K"`` the fingers."""

TYPES = {"float": "float64 or float32", "bool": "bool (or uint8 of 0 and 1)",
         "status": "an integer type (int8) of fsv.forces.FrameStatus values 0-7"}
"""What each type of :data:`ARRAYS` accepts, as messages say it."""

META_KEYS = ("format", "version", "episode", "finger_names", "method", "stages", "oracle", "suite", "world",
             "knowledge", "array_sha256", "meta_sha256")
"""The keys ``meta.json`` may hold."""


def force_bound_n() -> float:
    """:data:`FORCE_WEIGHTS` times the heaviest box's weight, [N]."""
    from benchmark.world.assets import masses  # lazy: MuJoCo (0.25 s), which reading a file does not need

    return FORCE_WEIGHTS * max(float(m["mass_kg"]) for m in masses()) * 9.81


def _accepts(kind: str, dtype: np.dtype) -> bool:
    if kind == "float":
        return dtype.kind == "f" and dtype.itemsize in (4, 8)
    if kind == "bool":
        return dtype.kind == "b" or dtype == np.uint8
    return dtype.kind in "iu"


def _describe(dtype: np.dtype) -> str:
    names = {"b": "booleans", "c": "complex numbers", "S": "strings", "U": "strings", "O": "objects",
             "i": "integers", "u": "integers"}
    return f"{names.get(dtype.kind, 'numbers')} ({dtype.str})" if dtype.kind != "f" else f"{dtype.name}"


def _shown(value, chars: int = 60) -> str:
    """A value of a file as one line of a message: its repr (line breaks escaped), cut to ``chars``."""
    text = repr(value)
    return text if len(text) <= chars else text[:chars] + "..."


def _name_problem(value, what: str) -> str | None:
    if not isinstance(value, str):
        return f"{what} must be a string, got {type(value).__name__}"
    if len(value) > MAX_NAME_CHARS:
        return f"{what} has {len(value)} characters; at most {MAX_NAME_CHARS}"
    if not value.isprintable():
        return f"{what} holds a line break or control character; one printable line is accepted"
    return None


def check_meta(path, meta: dict) -> None:
    """Refuses a ``meta.json`` whose keys or values are not the format's (see ``FORMAT_DOC``).

    Raises:
        EstimatesFileError: One line naming the file, the key and what is accepted.
    """
    def refuse(text):
        raise EstimatesFileError(f"{path}: meta.json {text}")

    unknown = [k for k in meta if k not in META_KEYS]
    if unknown:
        refuse(f"key {str(unknown[0])[:40]!r} is not in the format; accepted: {', '.join(META_KEYS)}")
    for key in ("episode", "method", "world", "knowledge", "meta_sha256"):
        if key in meta and (problem := _name_problem(meta[key], f'"{key}"')):
            refuse(problem)
    names = meta.get("finger_names", [])
    if not isinstance(names, list) or not 0 < len(names) <= MAX_FINGERS:
        refuse(f'"finger_names" must be a list of 1 to {MAX_FINGERS} names, got {_shown(names)}')
    for key, value in (("stages", meta.get("stages", {})), ("array_sha256", meta.get("array_sha256", {}))):
        if not isinstance(value, dict) or len(value) > 2 * len(ARRAYS):
            refuse(f'"{key}" must be an object of at most {2 * len(ARRAYS)} names, got {_shown(value)}')
    oracle = meta.get("oracle", [])
    if not isinstance(oracle, list) or len(oracle) > len(ARRAYS):
        refuse(f'"oracle" must be a list of stage names, got {_shown(oracle)}')
    items = [('"finger_names" entry', v) for v in names] + [('"oracle" entry', v) for v in oracle]
    items += [('"stages" name', k) for k in meta.get("stages", {})]
    items += [(f'"stages" {str(k)[:40]!r}', v) for k, v in meta.get("stages", {}).items()]
    for what, value in items:
        if problem := _name_problem(value, what):
            refuse(problem)
    suite = meta.get("suite", {"name": "", "version": 0})
    if not (isinstance(suite, dict) and set(suite) == {"name", "version"} and isinstance(suite["name"], str)
            and type(suite["version"]) is int):
        refuse(f'"suite" must be {{"name": string, "version": integer}}, got {_shown(suite)}')


def check_entry(name: str, dtype: np.dtype, shape: tuple, meta: dict, frames: int | None = None) -> str | None:
    """The format's rule on one array, from its header alone (:func:`benchmark.archive.read_archive`'s
    ``check_entry``): why it is refused, or None. ``frames``: the episode's, when known (else any
    number up to :data:`MAX_FRAMES`)."""
    if name not in ARRAYS:
        return f"array {name!r} is not in the estimates format (docs/formats.md lists its arrays)"
    kind, tail = ARRAYS[name]
    if not _accepts(kind, dtype):
        return f"{name} holds {_describe(dtype)}; expected {TYPES[kind]}"
    K = len(meta.get("finger_names") or ())
    want = tuple(K if d == "K" else d for d in tail)
    if frames is not None and tuple(shape) != (frames, *want):
        return f"{name} has shape {tuple(shape)}, expected {(frames, *want)}"
    if len(shape) != 1 + len(tail) or tuple(shape[1:]) != want or shape[0] > MAX_FRAMES:
        expected = "(" + ", ".join(["T", *map(str, want)]) + ("," if not want else "") + ")"
        return (f"{name} has shape {shape}; expected {expected} with T <= {MAX_FRAMES} frames"
                + (f" and K = {K} fingers (finger_names)" if "K" in tail else ""))
    return None


def read_estimates(path, *, arrays: bool = True, identity=None, frames: int | None = None) -> tuple:
    """``(meta, sections)`` of an estimates file, every entry checked against the format from its
    header before any array is read (:func:`check_entry`), ``meta.json`` by :func:`check_meta`, then
    by ``identity(meta)`` if given (e.g. :func:`check_identity`), before the entries;
    ``arrays=False`` reads no array; ``frames``: the episode's frame count, when known (every array's
    first axis must be it).

    Raises:
        EstimatesFileError: The first problem, naming the file and the entry.
    """
    checked = []

    def rule(name, dtype, shape, meta):
        if not checked:
            check_meta(path, meta)
            if identity is not None:
                identity(meta)
            checked.append(True)
        return check_entry(name, dtype, shape, meta, frames)

    meta, sections = read_archive(path, FORMAT, VERSION, kind="estimates", error=EstimatesFileError,
                                  digests_required=False, check_entry=rule, arrays=arrays)
    if not checked:
        check_meta(path, meta)
        if identity is not None:
            identity(meta)
    return meta, sections


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


def check_physics(path, box, contacts, kinematics, solutions: dict, fingertips=None) -> None:
    """Refuses estimates that are not physical, naming the file, the array and the first bad frame.

    Rotations (``box/rot``, ``kinematics/rot``, finite as read) orthonormal with determinant +1
    within :data:`ROTATION_TOL`; world positions (``box/pos``, ``kinematics/pos``,
    ``hand/fingertips``) within :data:`SCENE_BOUND_M` of the origin; an active contact's point
    finite and within :data:`CONTACT_BOUND_M` of the box's centre, its normal of unit length
    (:data:`UNIT_TOL`); the kinematics finite and below :data:`KINEMATICS_BOUND` where valid; forces
    finite or NaN (an unsolved frame), never infinite, and not above :func:`force_bound_n`.

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
    scene = [("box/pos", box.pos), ("kinematics/pos", kinematics.pos)]
    if fingertips is not None:
        scene.append(("hand/fingertips", np.asarray(fingertips).reshape(len(box.pos), -1, 3)))
    for name, pos in scene:
        far = ~(np.abs(pos.reshape(len(pos), -1)) <= SCENE_BOUND_M).all(axis=1)
        if far.any():
            bad(name, far, f"has a coordinate beyond {SCENE_BOUND_M:g} m of the world origin (outside the scene)")
    act = contacts.active
    point_ok = np.isfinite(contacts.point).all(axis=2) | ~act
    if not point_ok.all():
        bad("contacts/point", ~point_ok.all(axis=1), "is not finite for an active finger")
    near = (np.abs(np.where(act[..., None], contacts.point, 0.0)) <= CONTACT_BOUND_M).all(axis=(1, 2))
    if not near.all():
        bad("contacts/point", ~near, f"has a coordinate beyond {CONTACT_BOUND_M:g} m of the box's centre for an "
                                     "active finger")
    length = np.linalg.norm(np.clip(np.where(act[..., None], contacts.normal, 1.0), -2.0, 2.0), axis=2)
    unit = (np.abs(length - 1.0) <= UNIT_TOL) | ~act
    if not unit.all():
        bad("contacts/normal", ~unit.all(axis=1), f"is not a unit vector for an active finger (within {UNIT_TOL:g})")
    slides = contacts.sliding & act
    if slides.any():
        n = np.where(slides[..., None], contacts.normal, 0.0)
        d = np.where(slides[..., None], np.clip(np.nan_to_num(contacts.slide_dir), -1e3, 1e3), 0.0)
        tangential = np.linalg.norm(d - np.einsum("tki,tki->tk", d, n)[..., None] * n, axis=2)
        flat = (slides & ~(tangential > 1e-6)).any(axis=1)
        if flat.any():
            bad("contacts/slide_dir", flat, "has no component in the contact's tangent plane for a sliding finger "
                                            "(a sliding contact needs its direction; the default is 0)")
    for f in ("vel", "acc", "omega", "alpha"):
        v = getattr(kinematics, f)
        ok = np.isfinite(v).all(axis=1) | ~kinematics.valid
        if not ok.all():
            bad(f"kinematics/{f}", ~ok, "is not finite where kinematics/valid is true")
        big = ~(np.abs(np.where(kinematics.valid[:, None], v, 0.0)) <= KINEMATICS_BOUND).all(axis=1)
        if big.any():
            bad(f"kinematics/{f}", big, f"has a component above {KINEMATICS_BOUND:g} (SI units) where "
                                        "kinematics/valid is true")
    bound = force_bound_n()
    for group, sol in solutions.items():
        for name, v in (("force", sol.force), ("env_wrench", sol.env_wrench)):
            inf = np.isinf(v).reshape(len(v), -1).any(axis=1)
            if inf.any():
                bad(f"{group}/{name}", inf, "is infinite (NaN marks an unsolved frame)")
        force = np.abs(np.nan_to_num(sol.force)).reshape(len(sol.force), -1).max(axis=1, initial=0.0)
        table = np.abs(np.nan_to_num(sol.env_wrench)).max(axis=1, initial=0.0)
        for name, value in (("force", force), ("env_wrench", table)):
            big = value > bound
            if big.any():
                bad(f"{group}/{name}", big, f"has a component above {bound:.4g} (N, or N m for a torque: "
                                            f"{FORCE_WEIGHTS:g} times the heaviest box's weight, times 1 m)")


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

    meta, s = read_estimates(path, frames=len(t), identity=lambda meta: _same_fingers(path, meta, finger_names))
    names = tuple(meta.get("finger_names") or ())
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
        if dtype is bool and value.dtype != bool and not np.isin(value, (0, 1)).all():
            raise EstimatesFileError(f"{path}: {section}/{name} must hold booleans (bool, or uint8 of 0 and 1)")
        if dtype is np.int8:
            codes = [int(c) for c in FrameStatus]
            wrong = ~np.isin(value, codes)
            if wrong.any():
                i = int(np.flatnonzero(wrong)[0])
                raise EstimatesFileError(f"{path}: {section}/{name} at frame {i} is {value[i]}; accepted: "
                                         f"{', '.join(map(str, codes))} (fsv.forces.FrameStatus)")
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
    check_physics(path, box, contacts, kin, solutions, tracking.fingertips)
    return Estimate(tracking=tracking, contacts=contacts, kinematics=kin, nominal=solutions.get("nominal"),
                    forces=solutions.get("forces"), internal_pred=None, oracle=tuple(meta.get("oracle", ())),
                    timing_s={}, labels=dict(meta.get("stages", {})))


def _same_fingers(path, meta: dict, finger_names) -> None:
    names = tuple(meta.get("finger_names") or ())
    if names != tuple(finger_names):
        raise EstimatesFileError(f"{path}: finger_names {list(names)} do not match the episode's {list(finger_names)}")


def _solution(kind: str, contacts, force: np.ndarray, env_wrench: np.ndarray, status: np.ndarray):
    T, K = contacts.active.shape
    nan6 = np.full((T, 6), np.nan)
    return ForceSolution(kind=kind, finger_names=contacts.finger_names, active=contacts.active,
                         sliding=contacts.sliding, point=contacts.point, normal=contacts.normal, force=force,
                         nominal=force, internal=np.zeros((T, K, 3)),
                         env_active=(np.abs(env_wrench[:, :3]).sum(axis=1) > 0).astype(np.int64),
                         env_wrench=env_wrench, env_internal_wrench=np.zeros((T, 6)), required=nan6,
                         residual=nan6, status=status, objective=np.full(T, np.nan), iterations=np.zeros(T, np.int64),
                         solve_time_s=np.zeros(T))
