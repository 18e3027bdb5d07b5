"""The four stages of the method, as protocols any replacement satisfies.

A stage is any callable with the stage's signature (a function, or an object with ``__call__``).
An optional ``name`` attribute labels it in reports; otherwise its qualified name does.

* :class:`Tracker`: ``(inputs: CameraInput, rng) -> tracking`` with ``.box`` (:class:`fsv.Poses`, T
  frames) and ``.contacts`` (:class:`fsv.Contacts`, T frames), e.g. :class:`fsv.method.TrackOutput`.
* :class:`Differentiator`: ``(poses: Poses) -> Kinematics`` (world frame, T frames).
* :class:`ForceEstimator`: ``(kinematics, contacts, object_model, gravity) -> ForceSolution``: the
  nominal forces that explain the motion. A force stage whose output is already the method's
  final forces (a network predicting each finger's force, :class:`fsv.method.direct.DirectForces`)
  declares it with an attribute ``final = True`` (:func:`is_final`).
* :class:`InternalForces`: ``(kinematics, contacts, object_model, gravity) -> (ForceSolution,
  predicted)``: the final forces with internal forces added, and the internal normal forces used,
  shape (T, K), [N]. A stage that accepts a keyword ``grip`` is also given the person's grip
  calibration (``CameraInput.grip``, :class:`fsv.grip.GripCalibration` or None).
"""

from __future__ import annotations

import inspect
from typing import Protocol, runtime_checkable

import numpy as np

from fsv.errors import InputError
from fsv.forces import ForceSolution
from fsv.models import ObjectModel
from fsv.types import Contacts, Kinematics, Poses

STAGES = ("tracker", "differentiator", "forces", "internal")
"""The stage names, in the order the method runs them."""

ORACLE = "oracle"
"""The label reserved for a stage replaced by the truth (no method's stage may carry it)."""


@runtime_checkable
class Tracker(Protocol):
    """``(inputs: CameraInput, rng) -> tracking`` with ``.box`` (Poses) and ``.contacts`` (Contacts), T frames."""

    def __call__(self, inputs, rng: np.random.Generator): ...


@runtime_checkable
class Differentiator(Protocol):
    """``(poses: Poses) -> Kinematics``: world-frame velocities and accelerations, T frames."""

    def __call__(self, poses: Poses) -> Kinematics: ...


@runtime_checkable
class ForceEstimator(Protocol):
    """``(kinematics, contacts, object_model, gravity) -> ForceSolution``: the nominal forces."""

    def __call__(self, kinematics: Kinematics, contacts: Contacts, object_model: ObjectModel,
                 gravity: np.ndarray) -> ForceSolution: ...


@runtime_checkable
class InternalForces(Protocol):
    """``(kinematics, contacts, object_model, gravity) -> (ForceSolution, predicted)``: the final forces."""

    def __call__(self, kinematics: Kinematics, contacts: Contacts, object_model: ObjectModel,
                 gravity: np.ndarray) -> tuple: ...


def accepts_grip(stage) -> bool:
    """Whether an internal-force stage takes the keyword ``grip`` (or any keyword)."""
    try:
        params = inspect.signature(stage).parameters.values()
    except (TypeError, ValueError):  # a builtin without a signature: the four positional arguments only
        return False
    return any((p.name == "grip" and p.kind in (p.KEYWORD_ONLY, p.POSITIONAL_OR_KEYWORD)) or p.kind == p.VAR_KEYWORD
               for p in params)


def is_final(stage) -> bool:
    """Whether a force stage declares its output the method's final forces (``final`` is True)."""
    return getattr(stage, "final", False) is True


def stage_label(stage) -> str:
    """How reports name a stage: its ``name`` attribute, else its module-qualified name."""
    name = getattr(stage, "name", None)
    if not isinstance(name, str) or not name:
        kind = stage if hasattr(stage, "__qualname__") else type(stage)  # a class or function, else an instance
        name = f"{kind.__module__}:{kind.__qualname__}"
    if name == ORACLE:
        raise InputError(f"a method's stage may not be named {ORACLE!r} (reserved for stages replaced by truth)")
    return name
