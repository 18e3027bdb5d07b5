"""The whole method in one call: depth -> tracking -> contacts -> kinematics -> forces.

Forces: the nominal forces of eq. 4-6 (the minimal forces that explain the motion) and, when a
trained internal-force model is given, the full forces of eq. 14 with learned internal forces.

>>> est = run_pipeline(depth, calib, object_model, hand_model, init)
>>> est.kinematics.acc, est.contacts.point, est.timing_s

Every stage sees only what a real camera set-up provides: the depth video, the calibration, the
known object and hand models, and a coarse first-frame initialisation (:class:`TrackInit`).
Labelled *oracle* ablations may replace the estimated contacts or kinematics (``contacts=`` /
``kinematics=``); the estimate records which stages were replaced in ``oracle``.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from fsv.errors import InputError
from fsv.forces import ForceSolution, nominal_forces
from fsv.kinematics import AlgebraicConfig, CentralConfig, GaussianConfig, differentiate_poses
from fsv.models import HandModel, ObjectModel
from fsv.track.tracker import TrackerConfig, TrackInit, Tracking, track
from fsv.types import Calibration, Contacts, DepthVideo, Kinematics

GRAVITY = np.array([0.0, 0.0, -9.81])


@dataclass(frozen=True)
class Estimate:
    """What the method estimated from one depth video.

    Attributes:
        tracking: Box and hand tracking, with the contacts detected from it.
        contacts: The contacts the force stage used (the tracked ones unless an oracle replaced them).
        kinematics: The box kinematics the force stage used.
        nominal: The nominal forces (eq. 4-6), or None when the force stage was not run.
        forces: The full forces with learned internal forces (eq. 14), or None without a model.
        internal_pred: The predicted internal normal forces fed to eq. 14, shape (T, K), [N], or None.
        oracle: Names of the stages replaced by truth ("contacts", "kinematics"); empty for the
            method proper.
        timing_s: Seconds spent per stage: ``track`` (with ``track_box``, ``track_hand``,
            ``track_contacts``), ``kinematics``, ``forces``, ``learn``, ``total``.
    """

    tracking: Tracking
    contacts: Contacts
    kinematics: Kinematics
    nominal: ForceSolution | None
    forces: ForceSolution | None
    internal_pred: np.ndarray | None
    oracle: tuple
    timing_s: dict


def run_pipeline(depth: DepthVideo, calib: Calibration, object_model: ObjectModel, hand_model: HandModel,
                 init: TrackInit, *, differentiator: AlgebraicConfig | CentralConfig | GaussianConfig | None = None,
                 tracker_config: TrackerConfig | None = None, contacts: Contacts | None = None,
                 kinematics: Kinematics | None = None, forces: bool = True, internal_model=None,
                 gravity=GRAVITY, rng: np.random.Generator | None = None) -> Estimate:
    """Runs the FSV method on a depth video.

    Args:
        depth: The depth video, T frames.
        calib: Camera calibration (intrinsics and camera pose in the world, table top at z = 0).
        object_model: The known box.
        hand_model: The known hand.
        init: First-frame initialisation of the box and the hand.
        differentiator: Kinematics differentiator; default ``AlgebraicConfig()`` (offline).
        tracker_config: Parameters of the tracking stages.
        contacts: Oracle ablation: contacts replacing the tracked ones (labelled in ``oracle``).
        kinematics: Oracle ablation: kinematics replacing the estimated ones.
        forces: Run the force stage.
        internal_model: A trained ``fsv.learn.InternalForceModel``; with it the force stage also
            reconstructs the full forces with learned internal forces (eq. 14).
        gravity: Gravity in the world, shape (3,), [m/s^2].
        rng: Generator of the trackers' re-initialisation searches.

    Returns:
        The estimate, with per-stage timings.
    """
    if not isinstance(depth, DepthVideo):
        raise InputError(f"depth must be an fsv.DepthVideo, got {type(depth).__name__}")
    T = depth.num_frames
    for name, value, kind in (("contacts", contacts, Contacts), ("kinematics", kinematics, Kinematics)):
        if value is not None and (not isinstance(value, kind) or len(value) != T):
            raise InputError(f"{name} must be None or an fsv.{kind.__name__} of {T} frames, got {value!r:.80}")
    gravity = np.asarray(gravity, dtype=float)
    if gravity.shape != (3,) or not np.all(np.isfinite(gravity)):
        raise InputError(f"gravity must be a finite (3,) vector in m/s^2, got {gravity!r}")
    timing = {}
    t_start = time.perf_counter()
    tracking = track(depth, calib, object_model, hand_model, init, config=tracker_config, rng=rng)
    timing["track"] = time.perf_counter() - t_start
    timing.update({f"track_{k}": v for k, v in tracking.timing_s.items()})
    oracle = []
    if contacts is None:
        contacts = tracking.contacts
    else:
        oracle.append("contacts")
    t0 = time.perf_counter()
    if kinematics is None:
        kinematics = differentiate_poses(tracking.box, differentiator or AlgebraicConfig())
    else:
        oracle.append("kinematics")
    timing["kinematics"] = time.perf_counter() - t0
    nominal = full = predicted = None
    timing["forces"] = timing["learn"] = 0.0
    if forces:
        t0 = time.perf_counter()
        nominal = nominal_forces(kinematics, contacts, object_model, gravity=gravity)
        timing["forces"] = time.perf_counter() - t0
        if internal_model is not None:
            from fsv.learn import learned_forces  # torch is loaded only when a model is used

            t0 = time.perf_counter()
            full, predicted = learned_forces(internal_model, kinematics, contacts, object_model, gravity=gravity)
            timing["learn"] = time.perf_counter() - t0
    timing["total"] = time.perf_counter() - t_start
    return Estimate(tracking=tracking, contacts=contacts, kinematics=kinematics, nominal=nominal, forces=full,
                    internal_pred=predicted, oracle=tuple(oracle), timing_s=timing)
