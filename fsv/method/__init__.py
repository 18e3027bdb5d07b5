"""The FSV method as composable stages.

:func:`make_method` builds a :class:`Method` from a tracker, a differentiator, a force estimator and
an internal-force stage (each the reference's unless replaced); calling the method on a
:class:`CameraInput` gives an :class:`Estimate`. The stage signatures are in :mod:`fsv.method.stages`.
"""

from fsv.method.direct import DirectForces
from fsv.method.estimate import Estimate, TrackOutput
from fsv.method.inputs import GRAVITY, CameraInput
from fsv.method.method import Method, make_method, method_streams
from fsv.method.reference import LearnedInternalForces, NominalForces, ReferenceTracker, StencilDifferentiator
from fsv.method.stages import ORACLE, STAGES, Differentiator, ForceEstimator, InternalForces, Tracker, stage_label

__all__ = [
    "GRAVITY",
    "ORACLE",
    "STAGES",
    "CameraInput",
    "Differentiator",
    "DirectForces",
    "Estimate",
    "ForceEstimator",
    "InternalForces",
    "LearnedInternalForces",
    "Method",
    "NominalForces",
    "ReferenceTracker",
    "StencilDifferentiator",
    "TrackOutput",
    "Tracker",
    "make_method",
    "method_streams",
    "stage_label",
]
