"""Object kinematics from poses (the paper's §3.2) with interchangeable differentiators.

>>> kin = differentiate_poses(poses, AlgebraicConfig(window_frames=9, kappa=1, mu=1))

``AlgebraicConfig`` (minimal (kappa, mu) algebraic differentiators, offline or causal),
``CentralConfig`` (central finite differences) and ``GaussianConfig`` (Gaussian smoothing then
differences) all reduce to stencils (``fsv.kinematics.stencils``); rotations are differentiated on
SO(3) through relative rotation vectors (``fsv.kinematics.differentiate``).
"""

from fsv.kinematics.differentiate import differentiate_poses, kinematics_in_frame, sampling_period
from fsv.kinematics.stencils import (
    AlgebraicConfig,
    CentralConfig,
    GaussianConfig,
    Stencil,
    algebraic_weights,
    moments,
)

METHODS = {"algebraic": AlgebraicConfig, "central": CentralConfig, "gaussian": GaussianConfig}

__all__ = [
    "METHODS",
    "AlgebraicConfig",
    "CentralConfig",
    "GaussianConfig",
    "Stencil",
    "algebraic_weights",
    "differentiate_poses",
    "kinematics_in_frame",
    "moments",
    "sampling_period",
]
