"""A person's grip, measured once in a calibration recording: :class:`GripCalibration`.

The amount of internal force a person adds is invisible to a camera: the object's motion is the
same whoever squeezes it. People differ in how much they add (how far their grip exceeds the slip
limit, and how much they squeeze without load), so a user-blind estimator errs most on the people
farthest from the population it was trained on. A calibration recording
measures it: the person lifts the object a few times with force sensors on the fingertips, the
internal forces of those frames are computed (the decomposition of eq. 9 with the sensors'
readings, the same targets the networks are trained on), and their amount (L2 norm over the
fingers) is fitted as a straight line of the load the hand carries (p1 = |F_c|, eq. 10). The line's
two coefficients are given to the networks beside the paper's features, for every frame of that
person's recordings.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fsv.errors import InputError

MIN_CALIBRATION_SAMPLES = 30
"""Fewest frames a grip calibration is fitted on (one second at 30 fps)."""


@dataclass(frozen=True)
class GripCalibration:
    """How much internal force a person adds, as a straight line of the load.

    Attributes:
        baseline_n: Amount of internal force at zero load (the line's intercept), [N].
        gain: Added amount per newton of load |F_c|, [N/N].
        samples: Frames the line was fitted on.
    """

    baseline_n: float
    gain: float
    samples: int = 0

    def __post_init__(self):
        for name in ("baseline_n", "gain"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float, np.floating)) and np.isfinite(v)):
                raise InputError(f"GripCalibration.{name} must be a finite number, got {v!r}")
            object.__setattr__(self, name, float(v))
        if not (isinstance(self.samples, (int, np.integer)) and self.samples >= 0):
            raise InputError(f"GripCalibration.samples must be an integer >= 0, got {self.samples!r}")
        object.__setattr__(self, "samples", int(self.samples))

    def vector(self) -> np.ndarray:
        """The networks' extra inputs ``[baseline_n, gain]``, shape (2,)."""
        return np.array([self.baseline_n, self.gain])


def fit_grip(load_n, internal_n, active) -> GripCalibration:
    """Fits a person's grip line to the frames of a calibration recording.

    Args:
        load_n: The load the hand carries, p1 = |F_c| (eq. 10), shape (N,), [N].
        internal_n: Internal normal forces per finger (eq. 9 with the sensors' readings), shape (N, K), [N].
        active: Finger in contact, shape (N, K); frames without two fingers in contact are not used.

    Returns:
        The least-squares line of the amount (L2 norm over the fingers in contact) against the load.

    Raises:
        InputError: On mismatched shapes, non-finite values, or fewer than
            :data:`MIN_CALIBRATION_SAMPLES` usable frames or a load that does not vary.
    """
    p = np.asarray(load_n, dtype=float)
    f = np.asarray(internal_n, dtype=float)
    a = np.asarray(active, dtype=bool)
    if p.ndim != 1 or f.ndim != 2 or f.shape[0] != p.shape[0] or a.shape != f.shape:
        raise InputError(f"fit_grip expects load (N,), internal and active (N, K), got {p.shape}, {f.shape}, {a.shape}")
    use = (a.sum(axis=1) >= 2) & np.isfinite(p) & np.all(np.isfinite(np.where(a, f, 0.0)), axis=1)
    if use.sum() < MIN_CALIBRATION_SAMPLES:
        raise InputError(f"a grip calibration needs at least {MIN_CALIBRATION_SAMPLES} frames with two fingers "
                         f"in contact, got {int(use.sum())}")
    amount = np.sqrt(np.sum(np.where(a, f, 0.0)[use] ** 2, axis=1))
    x = p[use]
    dx = x - x.mean()
    sxx = float(np.sum(dx * dx))
    if not sxx > 1e-12 * max(1.0, float(np.sum(x * x))):
        raise InputError("a grip calibration needs frames at different loads (the object lifted and set down)")
    gain = float(np.sum(dx * (amount - amount.mean()))) / sxx
    return GripCalibration(baseline_n=float(amount.mean()) - gain * float(x.mean()), gain=gain, samples=int(use.sum()))
