"""The reference method's stages: the paper's tracker, differentiator, force programs and networks.

Each is a small immutable callable with a ``name``; :func:`fsv.method.make_method` composes them.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from fsv.errors import InputError
from fsv.forces import ForceSettings, ForceSolution, nominal_forces
from fsv.kinematics import AlgebraicConfig, CentralConfig, GaussianConfig, differentiate_poses
from fsv.learn import AMOUNT_SMOOTHING_S, default_model, learned_forces
from fsv.track.tracker import TrackerConfig, Tracking, track
from fsv.types import Contacts, Kinematics, Poses


@dataclass(frozen=True)
class ReferenceTracker:
    """Box, then hand against the depth the box leaves unexplained, then contacts (:func:`fsv.track.tracker.track`)."""

    config: TrackerConfig = field(default_factory=TrackerConfig)
    name: str = "reference tracker"
    on_frame: object = field(default=None, compare=False)  # called with 1 after every frame (progress)

    def __call__(self, inputs, rng: np.random.Generator) -> Tracking:
        return track(inputs.depth, inputs.calib, inputs.object_model, inputs.hand_model, inputs.init,
                     config=self.config, rng=rng, on_frame=self.on_frame)


TRACKED_POSES = AlgebraicConfig(window_frames=7, kappa=0.5, mu=0.5)
"""The reference method's differentiator of tracked poses: the algebraic one on L = 7 frames (0.23 s).
Chosen on the ``dev`` suite (seeds 500-547, tracked poses, the method's contacts), with the net force
scored against the truth's mean over each frame's interval (``benchmark.scores.forces``): L = 5, 7, 9
gave a median net force error of 0.219, 0.125, 0.133 N, on its worst task (``shake``) 0.259, 0.295,
0.389 N and on ``free`` 0.294, 0.252, 0.337 N; the learned forces 20.6 % at L = 7 against 20.1 % at
L = 9. kappa = mu = 0 and 1 did no better (0.130 N at L = 7, 0.134 N at L = 9). An adaptive choice
of the window per frame (intersection of confidence intervals over L = 5, 7, 9, 13) matched it
(0.132 N; 0.278 N on ``shake``) at four times the cost. Table 1's L = 15 (``AlgebraicConfig()``) was
tuned on the paper's tracker-like pose errors, which are noisier than this tracker's poses."""


@dataclass(frozen=True)
class StencilDifferentiator:
    """Pose differentiation by stencils on SO(3) x R^3 (:func:`fsv.kinematics.differentiate_poses`);
    by default the algebraic differentiator of :data:`TRACKED_POSES`."""

    config: AlgebraicConfig | CentralConfig | GaussianConfig = TRACKED_POSES

    @property
    def name(self) -> str:
        kind = {AlgebraicConfig: "algebraic", CentralConfig: "central", GaussianConfig: "gaussian"}[type(self.config)]
        return f"{kind} differentiation ({self.config.describe()})"

    def __call__(self, poses: Poses) -> Kinematics:
        return differentiate_poses(poses, self.config)


@dataclass(frozen=True)
class NominalForces:
    """The minimal contact forces that explain the motion (eq. 4-6, :func:`fsv.forces.nominal_forces`)."""

    settings: ForceSettings | None = None
    name: str = "nominal forces (eq. 4-6)"

    def __call__(self, kinematics: Kinematics, contacts: Contacts, object_model, gravity) -> ForceSolution:
        return nominal_forces(kinematics, contacts, object_model, gravity=gravity, settings=self.settings)


@dataclass(frozen=True)
class LearnedInternalForces:
    """Learned internal forces and the reconstruction of eq. 14 (:func:`fsv.learn.learned_forces`).

    Attributes:
        model: A trained ``fsv.learn.InternalForceModel``; None: a shipped one
            (:func:`fsv.learn.default_model`), the user-blind model for a person without a grip
            calibration, the model with grip inputs for a person with one.
        settings: Settings of the cone program.
        source: Where the model came from, for the label (e.g. its file).
        smoothing_s: Gaussian window over which the predicted amount of internal force is averaged,
            [s] (``fsv.learn.AMOUNT_SMOOTHING_S``); 0: per frame.
    """

    model: object = None
    settings: ForceSettings | None = None
    source: str = ""
    smoothing_s: float = AMOUNT_SMOOTHING_S

    def __post_init__(self):
        if not (isinstance(self.smoothing_s, (int, float)) and np.isfinite(self.smoothing_s) and self.smoothing_s >= 0):
            raise InputError(f"LearnedInternalForces.smoothing_s must be a finite number of seconds >= 0, "
                             f"got {self.smoothing_s!r}")

    @property
    def name(self) -> str:
        model = self.source or ("shipped model of the protocol" if self.model is None else "user model")
        window = f", amount averaged over {self.smoothing_s:g} s" if self.smoothing_s > 0 else ", per frame"
        return f"learned internal forces ({model}{window})"

    def model_for(self, grip=None):
        """The model this stage uses for a person with grip calibration ``grip`` (None: nothing is
        known of the person): :attr:`model`, or the protocol's shipped model."""

        return self.model if self.model is not None else default_model(blind=grip is None)

    def __call__(self, kinematics: Kinematics, contacts: Contacts, object_model, gravity, *, grip=None) -> tuple:
        """The final forces; ``grip`` is the person's :class:`fsv.grip.GripCalibration` (or None:
        nothing is known of the person), used by a model trained with grip inputs and choosing the
        shipped model when :attr:`model` is None."""

        model = self.model_for(grip)
        return learned_forces(model, kinematics, contacts, object_model, gravity=gravity, settings=self.settings,
                              smoothing_s=self.smoothing_s, grip=grip)
