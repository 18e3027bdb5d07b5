"""The joint hand-object tracker: box, then hand against the depth the box leaves unexplained, then contacts.

>>> tracking = track(depth, calib, object_model, hand_model, TrackInit(...))
"""

from __future__ import annotations

import itertools
import time
from dataclasses import dataclass, field

import numpy as np

from fsv._check import as_array
from fsv.compile_clock import CompileClock
from fsv.errors import InputError
from fsv.linalg import mm, mv, rigid_inverse
from fsv.models import HandModel, ObjectModel
from fsv.rotation import quat_to_rot, rot_to_quat
from fsv.track.contacts import ContactConfig, detect_contacts
from fsv.track.hand import HandState, HandTracker, HandTrackerConfig
from fsv.track.object import BoxTracker, BoxTrackerConfig, predict_box_depth
from fsv.track.table import TableFitConfig, TablePlane, fit_table, table_frame
from fsv.types import Calibration, Contacts, DepthVideo, Poses


@dataclass(frozen=True)
class TrackInit:
    """A coarse first-frame initialisation (the only non-visual input besides the models).

    Attributes:
        box_pos: Box centre in the world, shape (3,), [m].
        box_rot: world_R_object, shape (3, 3).
        palm_pos: Palm origin in the world, shape (3,), [m].
        palm_rot: world_R_palm, shape (3, 3).
        joints: Hinge angles in ``HandModel.joint_names`` order, shape (n,), [rad].
    """

    box_pos: np.ndarray
    box_rot: np.ndarray
    palm_pos: np.ndarray
    palm_rot: np.ndarray
    joints: np.ndarray

    def __post_init__(self):
        for name, shape in (("box_pos", (3,)), ("box_rot", (3, 3)), ("palm_pos", (3,)), ("palm_rot", (3, 3)),
                            ("joints", (None,))):
            arr = as_array(f"TrackInit.{name}", getattr(self, name), shape)
            if not np.all(np.isfinite(arr)):
                raise InputError(f"TrackInit.{name} must be finite")
            object.__setattr__(self, name, arr)
        for name in ("box_rot", "palm_rot"):
            R = getattr(self, name)
            if not np.allclose(R.T @ R, np.eye(3), atol=1e-4) or np.linalg.det(R) <= 0:
                raise InputError(f"TrackInit.{name} must be a rotation matrix")

    @classmethod
    def from_qpos(cls, box_pos, box_quat, hand_qpos) -> "TrackInit":
        """From a box position and quaternion (w, x, y, z) and a hand configuration (7 + n)."""
        hand_qpos = np.asarray(hand_qpos, dtype=float)
        if hand_qpos.ndim != 1 or hand_qpos.shape[0] < 8:
            raise InputError(f"hand_qpos must be (7 + n,), got {hand_qpos.shape}")
        return cls(box_pos=box_pos, box_rot=quat_to_rot(np.asarray(box_quat, dtype=float)),
                   palm_pos=hand_qpos[:3], palm_rot=quat_to_rot(hand_qpos[3:7]), joints=hand_qpos[7:])


@dataclass(frozen=True)
class TrackerConfig:
    """Parameters of every tracking stage."""

    box: BoxTrackerConfig = field(default_factory=BoxTrackerConfig)
    hand: HandTrackerConfig = field(default_factory=HandTrackerConfig)
    contacts: ContactConfig = field(default_factory=ContactConfig)
    table_z: float = 0.0
    table_fit: TableFitConfig | None = field(default_factory=TableFitConfig)
    """The table fitted to the first frame's depth (:mod:`fsv.track.table`); None: the
    calibration's table z = ``table_z``."""


@dataclass(frozen=True)
class Tracking:
    """Everything the tracker estimated, T frames, K fingers.

    Attributes:
        box: Box poses.
        hand_qpos: Palm position, palm quaternion (w, x, y, z) and hinge angles, shape (T, 7 + n).
        fingertips: Fingertip pad centres in the world, shape (T, K, 3), [m].
        observed: Whether each finger was seen, shape (T, K).
        box_inliers: Fraction of predicted-visible box pixels agreeing with the fit, shape (T,).
        hand_explained: Fraction of hand candidate points near the fitted hand, shape (T,).
        contacts: Contacts detected from the tracked fingertips (object frame).
        table: The table plane the tracker used, in the world (:class:`fsv.track.table.TablePlane`).
        table_from_world: The rigid motion (4, 4) that puts that table at z = 0 with its normal
            along +z (:func:`fsv.track.table.table_frame`): the frame in which the force stages
            find the box on the table, gravity along -z.
        timing_s: Seconds spent in each stage: ``box``, ``hand``, ``contacts``.
        first_frame_s: Seconds of the first frame's box and hand fits, part of ``box`` and ``hand``,
            without compiling, [s].
        compile_s: Seconds of the frames' box and hand fits spent compiling numba kernels, part of
            ``box`` and ``hand``: the first run after installing compiles them, later runs load them
            from numba's cache and spend none (:class:`fsv.compile_clock.CompileClock`), [s].
    """

    box: Poses
    hand_qpos: np.ndarray
    fingertips: np.ndarray
    observed: np.ndarray
    box_inliers: np.ndarray
    hand_explained: np.ndarray
    contacts: Contacts
    timing_s: dict
    first_frame_s: float = 0.0
    compile_s: float = 0.0
    table: TablePlane | None = None
    table_from_world: np.ndarray | None = None


def track(depth: DepthVideo, calib: Calibration, object_model: ObjectModel, hand_model: HandModel,
          init: TrackInit, *, config: TrackerConfig | None = None,
          rng: np.random.Generator | None = None, on_frame=None) -> Tracking:
    """Tracks the box and the hand through a depth video and detects their contacts.

    Args:
        depth: The depth video (T frames).
        calib: Camera calibration.
        object_model: The known box.
        hand_model: The known hand.
        init: First-frame initialisation.
        config: Parameters of every stage.
        rng: Generator of the trackers' re-initialisation searches.
        on_frame: Called with 1 after every frame (e.g. a progress bar's ``update``).

    Returns:
        The tracking result.
    """
    if not isinstance(depth, DepthVideo):
        raise InputError(f"depth must be an fsv.DepthVideo, got {type(depth).__name__}")
    if not isinstance(init, TrackInit):
        raise InputError(f"init must be an fsv.track.tracker.TrackInit, got {type(init).__name__}")
    if init.joints.shape != (hand_model.num_joints,):
        raise InputError(f"init.joints must have the hand's {hand_model.num_joints} angles, got {init.joints.shape}")
    with CompileClock() as compiling:
        return _track(depth, calib, object_model, hand_model, init, config, rng, on_frame, compiling)


def _track(depth, calib, object_model, hand_model, init, config, rng, on_frame, compiling: CompileClock) -> Tracking:
    """:func:`track` on checked inputs, its compilation timed by ``compiling``."""
    cfg = config or TrackerConfig()
    rng = rng if rng is not None else np.random.default_rng(0)
    box_rng, hand_rng = rng.spawn(2)
    frames = depth.frames()  # in order, each frame read once it is there (a DepthRecording's as it is recorded)
    first = next(frames, None)
    t0 = time.perf_counter()
    table = TablePlane.believed(cfg.table_z)
    if cfg.table_fit is not None and first is not None:
        table = fit_table(first, calib, init.box_pos, init.box_rot, object_model, table_z=cfg.table_z,
                          config=cfg.table_fit)
    to_table = table_frame(table)
    t_table = time.perf_counter() - t0
    if table.fitted:  # track in the table's frame (the table at z = 0), report in the calibration's world
        R, t = to_table[:3, :3], to_table[:3, 3]
        calib = Calibration(K=calib.K, T_world_cam=_rigid_product(to_table, calib.T_world_cam), width=calib.width,
                            height=calib.height)
        init = TrackInit(box_pos=mv(R, init.box_pos) + t, box_rot=mm(R, init.box_rot),
                         palm_pos=mv(R, init.palm_pos) + t, palm_rot=mm(R, init.palm_rot), joints=init.joints)
    table_z = 0.0 if table.fitted else cfg.table_z
    boxes = BoxTracker(calib, object_model, init.box_pos, init.box_rot, config=cfg.box, rng=box_rng, table_z=table_z)
    hands = HandTracker(calib, hand_model, object_model, HandState(init.palm_pos, init.palm_rot, init.joints),
                        config=cfg.hand, rng=hand_rng, table_z=table_z)
    T, K = depth.num_frames, len(hand_model.finger_names)
    box_pos, box_rot, inl = np.zeros((T, 3)), np.zeros((T, 3, 3)), np.zeros(T)
    qpos = np.zeros((T, 7 + hand_model.num_joints))
    tips, observed, explained = np.zeros((T, K, 3)), np.zeros((T, K), bool), np.zeros(T)
    t_box = t_hand = t_first = t_compile = 0.0
    for i, frame in enumerate(itertools.chain(() if first is None else (first,), frames)):
        t0, compiled = time.perf_counter(), compiling.s
        fit = boxes.update(frame, occluder=hands.predicted_depth)
        box_pos[i], box_rot[i], inl[i] = fit.pos, fit.rot, fit.inlier_fraction
        t1 = time.perf_counter()
        def scene(index, fit=fit):
            return predict_box_depth(boxes.rays, index, fit.pos, fit.rot, boxes.half, boxes.fx)[0]

        hf = hands.update(frame, scene, fit.pos, fit.rot, boxes.sigma or fit.sigma_m)
        s = hf.state
        qpos[i] = np.concatenate([s.palm_pos, rot_to_quat(s.palm_rot), s.joints])
        tips[i], observed[i], explained[i] = hf.fingertips, hf.observed, hf.explained
        t_box += t1 - t0
        t_hand += time.perf_counter() - t1
        t_compile += compiling.s - compiled
        if i == 0:
            t_first = time.perf_counter() - t0 - t_compile
        if on_frame is not None:
            on_frame(1)
    poses = Poses(t=depth.t, pos=box_pos, rot=box_rot)
    t2 = time.perf_counter()
    contacts = detect_contacts(tips, hand_model.fingertip_radius, observed, poses, object_model,
                               hand_model.finger_names, cfg.contacts)
    if table.fitted:  # back to the calibration's world
        back = rigid_inverse(to_table)
        R, t = back[:3, :3], back[:3, 3]
        poses = Poses(t=depth.t, pos=mv(R, box_pos) + t, rot=mm(R, box_rot))
        palm_rot = mm(R, quat_to_rot(qpos[:, 3:7]))
        qpos = np.concatenate([mv(R, qpos[:, :3]) + t, np.stack([rot_to_quat(r) for r in palm_rot]), qpos[:, 7:]],
                              axis=1)
        tips = mv(R, tips) + t
    timing = {"box": t_box, "hand": t_hand, "contacts": time.perf_counter() - t2, "table": t_table}
    if not table.fitted and cfg.table_z == 0.0:
        to_table = None  # the calibration's world is the table's frame
    return Tracking(box=poses, hand_qpos=qpos, fingertips=tips, observed=observed, box_inliers=inl,
                    hand_explained=explained, contacts=contacts, timing_s=timing, first_frame_s=t_first,
                    compile_s=t_compile, table=table, table_from_world=to_table)


def _rigid_product(A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """``A @ B`` of two rigid motions (4, 4), without BLAS."""
    out = np.eye(4)
    out[:3, :3] = mm(A[:3, :3], B[:3, :3])
    out[:3, 3] = mv(A[:3, :3], B[:3, 3]) + A[:3, 3]
    return out
