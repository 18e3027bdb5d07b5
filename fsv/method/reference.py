"""The reference method's stages: the paper's tracker, differentiator, force programs and networks.

Each is a small immutable callable with a ``name``; :func:`fsv.method.make_method` composes them.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from fsv.forces import ForceSettings, ForceSolution, nominal_forces
from fsv.kinematics import AlgebraicConfig, CentralConfig, GaussianConfig, differentiate_poses
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


@dataclass(frozen=True)
class StencilDifferentiator:
    """Pose differentiation by stencils on SO(3) x R^3 (:func:`fsv.kinematics.differentiate_poses`)."""

    config: AlgebraicConfig | CentralConfig | GaussianConfig = field(default_factory=AlgebraicConfig)

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
        model: A trained ``fsv.learn.InternalForceModel``; None loads the shipped one on first use.
        settings: Settings of the cone program.
        source: Where the model came from, for the label (e.g. its file).
    """

    model: object = None
    settings: ForceSettings | None = None
    source: str = ""

    @property
    def name(self) -> str:
        return f"learned internal forces ({self.source or ('shipped model' if self.model is None else 'user model')})"

    def __call__(self, kinematics: Kinematics, contacts: Contacts, object_model, gravity) -> tuple:
        from fsv.learn import default_model, learned_forces  # torch is loaded only when this stage runs

        model = self.model if self.model is not None else default_model()
        return learned_forces(model, kinematics, contacts, object_model, gravity=gravity, settings=self.settings)
