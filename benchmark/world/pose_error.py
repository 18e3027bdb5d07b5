"""A tracker-like pose error model: what the kinematics stage sees until (or instead of) a tracker.

A model-based tracker fits the object model to each depth frame starting from the previous
frame's solution, so its errors are roughly Gaussian but *correlated in time* (the paper, §3.2:
"not independent of one another, which rules out the white noise formalism"). We model them as
stationary first-order Gauss-Markov (AR(1)) processes, independent per axis:

    e_k = rho e_(k-1) + sqrt(1 - rho^2) sigma xi_k,   rho = exp(-dt / corr_time_s),  e_0 ~ N(0, sigma^2),

added to the true centre-of-mass position (world frame) and composed with the true orientation as
a body-frame rotation vector, R_obs = R_true exp([e]x). Each e_k has standard deviation sigma at
every frame; consecutive errors have correlation rho (0.72 at 30 fps for 0.1 s).

Scale: the pose error of a tracker grows with the depth noise. ``for_scenario`` scales the
reference standard deviations (given at 1 cm depth noise) linearly with ``Scenario.noise_m``; at
0 noise the poses are exact. The reference values (1.5 mm, 3 deg, 0.1 s) are our choice: a few
millimetres and degrees, like model-based RGB-D trackers on a hand-occluded box. At 30 fps they
make three-point central accelerations about as noisy as the paper's (Table 1: 1.7 m/s^2) and
central angular velocities about half as noisy (0.8 vs 1.6 rad/s). They set the noise level, not
the ranking of the differentiators.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from benchmark.errors import ScenarioError
from benchmark.world.scenario import Scenario
from benchmark.world.truth import Truth
from fsv import Poses
from fsv.kinematics import so3
from fsv.rotation import quat_to_rot

REFERENCE_NOISE_M = 0.01


@dataclass(frozen=True)
class PoseErrorModel:
    """Correlated Gaussian pose errors (see the module docstring).

    Attributes:
        pos_std_m: Standard deviation of each position coordinate's error, [m].
        rot_std_rad: Standard deviation of each component of the body-frame rotation error, [rad].
        corr_time_s: Correlation time of the AR(1) processes, [s] (0 = white errors).
    """

    pos_std_m: float = 0.0015
    rot_std_rad: float = float(np.deg2rad(3.0))
    corr_time_s: float = 0.1

    def __post_init__(self):
        for key in ("pos_std_m", "rot_std_rad", "corr_time_s"):
            v = getattr(self, key)
            if not (isinstance(v, (int, float, np.integer, np.floating)) and np.isfinite(v) and v >= 0):
                raise ScenarioError(f"PoseErrorModel.{key} must be a finite number >= 0, got {v!r}")

    @classmethod
    def for_scenario(cls, scenario: Scenario) -> "PoseErrorModel":
        """The reference model scaled by the scenario's depth noise (relative to 1 cm)."""
        ref = cls()
        s = float(scenario.noise_m) / REFERENCE_NOISE_M
        return cls(ref.pos_std_m * s, ref.rot_std_rad * s, ref.corr_time_s)

    def errors(self, num_frames: int, dt: float, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
        """Draws position and rotation errors.

        Args:
            num_frames: T.
            dt: Frame period in [s].
            rng: The generator to draw from (6 T normal draws, in a fixed order).

        Returns:
            ``(pos_err, rot_err)``, each shape (T, 3): metres and body-frame rotation vectors in radians.
        """
        xi = rng.standard_normal((num_frames, 6))
        rho = float(np.exp(-dt / self.corr_time_s)) if self.corr_time_s > 0 else 0.0
        innovation = np.sqrt(1.0 - rho**2)
        e = np.empty_like(xi)
        e[0] = xi[0]
        for k in range(1, num_frames):
            e[k] = rho * e[k - 1] + innovation * xi[k]
        return e[:, :3] * self.pos_std_m, e[:, 3:] * self.rot_std_rad

    def corrupt(self, t: np.ndarray, pos: np.ndarray, rot: np.ndarray, rng: np.random.Generator) -> Poses:
        """True poses plus drawn errors.

        Args:
            t: Frame times, (T,), [s], evenly spaced.
            pos: True centre-of-mass positions, (T, 3), [m].
            rot: True world_R_object, (T, 3, 3).
            rng: Generator (e.g. ``scenario.rng("pose-error")``).

        Returns:
            The observed poses.
        """
        t = np.asarray(t, dtype=float)
        dt = float(t[1] - t[0]) if t.size > 1 else 1.0
        pos_err, rot_err = self.errors(t.size, dt, rng)
        q = so3.quat_mul(so3.quat_from_matrix(rot), so3.quat_exp(rot_err))
        return Poses(t=t, pos=np.asarray(pos, dtype=float) + pos_err, rot=quat_to_rot(q))


def tracker_like_poses(truth: Truth, scenario: Scenario, model: PoseErrorModel | None = None) -> Poses:
    """The true box poses corrupted by ``model`` (default: scaled to the scenario's noise).

    Randomness comes only from ``scenario.rng("pose-error")``: the same scenario gives the same poses.
    """
    model = PoseErrorModel.for_scenario(scenario) if model is None else model
    return model.corrupt(truth.t, truth.box_pos, truth.box_rot, scenario.rng("pose-error"))
