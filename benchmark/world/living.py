"""A living grip: how a person's grip force varies within a hold and from one trial to the next.

The grip policy (:class:`benchmark.world.grip.GripPolicy`) gives the grip a person needs; a
person does not produce it as a constant. Per trial, from the scenario's "grip" random stream:

* **Trial-to-trial variability.** The user's safety margin and baseline grip are scaled by one
  log-normal factor of coefficient of variation :data:`TRIAL_CV` (the same person lifting the same
  object grips differently from lift to lift; Westling & Johansson 1984, Exp. Brain Res. 53).
* **Relaxation during holds.** While the box is held still, the grip kept beyond the load's need
  (the baseline) relaxes exponentially toward a fraction :data:`RELAX_FLOOR` of itself, with a time
  constant drawn from :data:`RELAX_TAU_S`, and is restored when the next movement starts: the grip
  drifts down toward the slip limit plus the safety margin in static holds (Johansson & Westling
  1984, Exp. Brain Res. 56, the static phase). Floor and time constants are chosen.
* **Fluctuations.** The produced grip is multiplied by ``1 + drift(t) + tremor(t)``: ``drift`` is
  slow (an Ornstein-Uhlenbeck process of time constant :data:`DRIFT_TAU_S`), ``tremor`` is
  band-limited noise in the physiological tremor band :data:`TREMOR_BAND_HZ` (8-12 Hz; McAuley &
  Marsden 2000, Brain 123). Force variability grows with the force produced (signal-dependent
  noise, Jones, Hamilton & Wolpert 2002, J. Neurophysiol. 88), hence multiplicative. Their
  coefficients of variation are drawn per trial from :data:`DRIFT_CV` and :data:`TREMOR_CV`: the
  total, 2-4 % in steady holds, is the range of steady pinch-force variability at moderate forces
  (Slifkin & Newell 1999, J. Exp. Psychol. Hum. Percept. Perform. 25).

The contact forces stay what the simulator computes, so the truth obeys Newton-Euler as before.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from benchmark.world.butterworth import bandpass_sos, sosfilt

TRIAL_CV = 0.10
"""Coefficient of variation of the per-trial grip scale."""
RELAX_TAU_S = (3.0, 6.0)
"""Range of the relaxation's time constant, [s]."""
RELAX_FLOOR = 0.3
"""The baseline grip relaxes toward this fraction of itself."""
DRIFT_TAU_S = 1.0
"""Time constant of the slow drift, [s]."""
DRIFT_CV = (0.015, 0.03)
"""Range of the drift's coefficient of variation."""
TREMOR_BAND_HZ = (8.0, 12.0)
"""Physiological tremor band, [Hz]."""
TREMOR_CV = (0.005, 0.015)
"""Range of the tremor's coefficient of variation."""
MOVING_ACC = 0.3
"""The planned box acceleration above which the hand counts as moving (no relaxation), [m/s^2]."""
MOVING_ALPHA = 1.0
"""The planned angular acceleration above which the hand counts as moving, [rad/s^2]."""


@dataclass(frozen=True)
class LivingGrip:
    """One trial's draws of the grip's variability.

    Attributes:
        trial_scale: Factor on the user's safety margin and baseline grip.
        relax_tau_s: Time constant of the relaxation during holds, [s].
        drift_cv: Coefficient of variation of the slow drift.
        tremor_cv: Coefficient of variation of the tremor.
    """

    trial_scale: float
    relax_tau_s: float
    drift_cv: float
    tremor_cv: float

    @staticmethod
    def draw(rng: np.random.Generator) -> "LivingGrip":
        """The draws of one trial (four uniforms/normals from ``rng``, in this order)."""
        sigma = np.sqrt(np.log1p(TRIAL_CV**2))
        scale = float(np.exp(sigma * rng.standard_normal() - sigma**2 / 2))  # mean 1
        return LivingGrip(trial_scale=scale, relax_tau_s=float(rng.uniform(*RELAX_TAU_S)),
                          drift_cv=float(rng.uniform(*DRIFT_CV)), tremor_cv=float(rng.uniform(*TREMOR_CV)))

    def relaxation(self, t: np.ndarray, moving: np.ndarray) -> np.ndarray:
        """The baseline's factor: 1 while moving, relaxing toward RELAX_FLOOR since the last movement.

        Args:
            t: Times of the control ticks, (N,), [s], increasing.
            moving: Whether the hand moves at each tick, (N,) bool.

        Returns:
            Factors in [RELAX_FLOOR, 1], (N,).
        """
        t = np.asarray(t, float)
        last = np.maximum.accumulate(np.where(np.asarray(moving, bool), np.arange(len(t)), -1))
        since = np.where(last >= 0, t - t[np.maximum(last, 0)], t - t[0])
        return RELAX_FLOOR + (1.0 - RELAX_FLOOR) * np.exp(-since / self.relax_tau_s)

    def modulation(self, t: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """The produced grip's factor 1 + drift + tremor at the control ticks.

        Args:
            t: Times of the control ticks, (N,), [s], evenly spaced.
            rng: The trial's generator (two standard normals per tick are drawn).

        Returns:
            Factors, (N,), mean about 1.
        """
        t = np.asarray(t, float)
        n = len(t)
        if n < 2:
            return np.ones(n)
        dt = t[1] - t[0]
        white = rng.standard_normal((2, n))
        keep = np.exp(-dt / DRIFT_TAU_S)
        drift = np.empty(n)
        drift[0] = white[0, 0]
        gain = np.sqrt(1.0 - keep**2)
        for i in range(1, n):  # stationary Ornstein-Uhlenbeck process of unit variance
            drift[i] = keep * drift[i - 1] + gain * white[0, i]
        nyquist = 0.5 / dt
        lo, hi = TREMOR_BAND_HZ
        tremor = np.zeros(n)
        if hi < nyquist:
            sos = bandpass_sos(4, lo / nyquist, hi / nyquist)  # scipy.signal.butter's, bit for bit
            warm = int(round(1.0 / dt))  # one second of filter warm-up, discarded
            pre = rng.standard_normal(warm)
            band = sosfilt(sos, np.concatenate([pre, white[1]]))[warm:]
            tremor = band / max(float(np.sqrt(np.mean(band**2))), 1e-12)
        return 1.0 + self.drift_cv * drift + self.tremor_cv * tremor
