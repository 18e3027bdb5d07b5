"""The whole method in one call: depth -> tracking -> contacts -> kinematics -> forces.

Forces: the nominal forces of eq. 4-6 (the minimal forces that explain the motion) and, when a
trained internal-force model is given, the full forces of eq. 14 with learned internal forces.

>>> est = run_pipeline(depth, calib, object_model, hand_model, init)
>>> est.kinematics.acc, est.contacts.point, est.timing_s

A convenience over :func:`fsv.method.make_method` for the reference stages with their settings.
Every stage sees only what a real camera set-up provides: the depth video, the calibration, the
known object and hand models, and a coarse first-frame initialisation (:class:`TrackInit`).
Labelled *oracle* ablations may replace the estimated contacts or kinematics (``contacts=`` /
``kinematics=``); the estimate records which stages were replaced in ``oracle``.
"""

from __future__ import annotations

import numpy as np

from fsv.kinematics import AlgebraicConfig, CentralConfig, GaussianConfig
from fsv.method import (
    GRAVITY,
    CameraInput,
    Estimate,
    LearnedInternalForces,
    ReferenceTracker,
    StencilDifferentiator,
    make_method,
)
from fsv.models import HandModel, ObjectModel
from fsv.track.tracker import TrackerConfig, TrackInit
from fsv.types import Calibration, Contacts, DepthVideo, Kinematics

__all__ = ["Estimate", "GRAVITY", "run_pipeline"]


def run_pipeline(depth: DepthVideo, calib: Calibration, object_model: ObjectModel, hand_model: HandModel,
                 init: TrackInit, *, differentiator: AlgebraicConfig | CentralConfig | GaussianConfig | None = None,
                 tracker_config: TrackerConfig | None = None, contacts: Contacts | None = None,
                 kinematics: Kinematics | None = None, forces: bool = True, internal_model=None,
                 gravity=GRAVITY, rng: np.random.Generator | None = None, grip=None) -> Estimate:
    """Runs the reference FSV method on a depth video.

    Args:
        depth: The depth video, T frames.
        calib: Camera calibration (intrinsics and camera pose in the world, table top at z = 0).
        object_model: The known box.
        hand_model: The known hand.
        init: First-frame initialisation of the box and the hand.
        differentiator: Kinematics differentiator; default the reference method's
            (``fsv.method.reference.TRACKED_POSES``, offline).
        tracker_config: Parameters of the tracking stages.
        contacts: Oracle ablation: contacts replacing the tracked ones (labelled in ``oracle``).
        kinematics: Oracle ablation: kinematics replacing the estimated ones.
        forces: Run the force stage.
        internal_model: A trained ``fsv.learn.InternalForceModel``; with it the force stage also
            reconstructs the full forces with learned internal forces (eq. 14).
        gravity: Gravity in the world, shape (3,), [m/s^2].
        rng: Generator of the trackers' re-initialisation searches.
        grip: The person's grip calibration (:class:`fsv.grip.GripCalibration`), for an internal
            model trained with grip inputs; None: the model's training mean.

    Returns:
        The estimate, with per-stage timings.
    """
    method = make_method(
        tracker=ReferenceTracker(tracker_config or TrackerConfig()),
        differentiator=StencilDifferentiator() if differentiator is None else StencilDifferentiator(differentiator),
        forces=None if forces else False,
        internal=LearnedInternalForces(internal_model) if forces and internal_model is not None else False,
    )
    inputs = CameraInput(depth=depth, calib=calib, object_model=object_model, hand_model=hand_model, init=init,
                         gravity=gravity, grip=grip)
    return method(inputs, rng, contacts=contacts, kinematics=kinematics)
