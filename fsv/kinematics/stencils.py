"""Derivative stencils: finite impulse responses that estimate the n-th derivative of a sampled signal.

Every differentiator here is a *causal* stencil ``w`` of length L: with samples x_k = x(t_k),
t_k = k dt,

    y_k = sum_{i=0}^{L-1} w_i x_{k-i}  ~  x^(n)(t_k - delay),

and it is exact, at that delay, on every polynomial of degree <= ``exact_degree``. The delay is a
property of the weights: with the moments m_j = sum_i w_i (-i dt)^j / j!, exactness on degree n
means m_j = 0 for j < n and m_n = 1; then for x(t) = t^(n+1)/(n+1)! the estimate at t = 0 is
m_(n+1) = x^(n)(-delay), so delay = -m_(n+1). An offline (centred) estimate is the same stencil
read ``delay`` later; when the delay is not a whole number of frames, two shifted copies are blended
linearly (``Stencil.taps``), which keeps exactness because the n-th derivative of a degree-(n+1)
polynomial is linear in time.

Order 0 is each method's smoothing filter; it gives the pose the kinematics refer to (which
matters: the AHRS comparison rotates a - g into the box frame with it, and a 3 degree orientation
error alone turns gravity into a 0.5 m/s^2 acceleration error). Three families:

* Algebraic: the minimal (kappa, mu) algebraic numerical differentiators of Mboup, Join and Fliess
  (Numer. Algorithms 50, 2009). Their kernel for the n-th derivative over a window of length
  T = L dt (tau = lag, 0 = newest sample) is, with u = tau / T,

      x^(n)(t - delay) ~ int_0^T g^(n)(tau) x(t - tau) dtau,
      g(tau) = u^(kappa+n) (1-u)^(mu+n) / (T B(kappa+n+1, mu+n+1)),

  a Jacobi weight (a = kappa + n on the newest end, b = mu + n on the oldest). The continuous
  estimator is exact on degree-(n+1) polynomials at delay (kappa+n+1) / (kappa+mu+2n+2) T. Each
  weight integrates g^(n) exactly over one sample interval, w_i = g^(n-1)((i+1) dt) - g^(n-1)(i dt)
  (the signal is held over the interval), so the weights of a derivative sum to exactly zero
  (g^(n-1) vanishes at both ends); then they are scaled so that m_n = 1. This is AlgDiff's
  ``analytic`` discretisation with its DC correction (Othmane, Kiltz, Rudolph). For kappa = mu the
  weights are (anti)symmetric, every moment below n vanishes and the delay is (L-1)/2 frames. For
  kappa != mu and n >= 2 the discretisation leaves m_1 != 0 (a linear ramp would leak into the
  acceleration); ``exact_moments`` removes that residue with the smallest change of the weights.
  Order 0 is the minimal (kappa, mu) smoother: the normalised Jacobi weight integrated over each
  interval (a regularised incomplete beta function), exact on lines at its delay.
* Central finite differences with a step of h frames: (x_(k+h) - x_(k-h)) / (2 h dt) and
  (x_(k+h) - 2 x_k + x_(k-h)) / (h dt)^2; no smoothing (order 0 is the sample itself).
* Gaussian filtering (standard deviation sigma frames, truncated at ``truncate`` sigma, normalised
  to unit sum) followed by the central differences of step 1: the convolution of the two.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import special

from fsv.errors import InputError
from fsv.linalg import convolve_full, mv, rows_mt, solve


@dataclass(frozen=True)
class Stencil:
    """A causal stencil for the n-th derivative.

    Attributes:
        order: Derivative order n (0 = the signal itself).
        weights: w_i applied to x_(k-i), shape (L,), [1/s^n].
        dt: Sampling period in [s].
        delay_s: The estimate at t_k is the n-th derivative at t_k - delay_s, [s].
        exact_degree: The estimate is exact at that delay on every polynomial of this degree or lower.
    """

    order: int
    weights: np.ndarray
    dt: float
    delay_s: float
    exact_degree: int

    def __post_init__(self):
        w = np.array(self.weights, dtype=float)
        if w.ndim != 1 or w.size == 0 or not np.all(np.isfinite(w)):
            raise InputError(f"Stencil.weights must be a non-empty finite 1-D array, got shape {w.shape}")
        w.setflags(write=False)
        object.__setattr__(self, "weights", w)

    def taps(self, lag_s: float) -> tuple[np.ndarray, np.ndarray]:
        """The stencil re-timed to estimate x^(n)(t_k - lag_s) at frame k.

        Args:
            lag_s: Wanted lag in [s]; 0 gives a centred (offline) estimate, lag_s >= delay_s a
                causal one.

        Returns:
            ``(offsets, coeffs)``, int and float arrays of equal length: the estimate at frame k
            is ``sum(coeffs * x[k + offsets])``.
        """
        shift = (lag_s - self.delay_s) / self.dt
        whole = math.floor(shift + 1e-9)
        frac = shift - whole
        lags = np.arange(self.weights.size)
        if frac < 1e-9:
            return -(lags + whole), self.weights.copy()
        offsets = np.concatenate([-(lags + whole), -(lags + whole + 1)])
        coeffs = np.concatenate([(1 - frac) * self.weights, frac * self.weights])
        keep = np.unique(offsets)
        summed = np.array([coeffs[offsets == o].sum() for o in keep])
        return keep, summed


def moments(weights: np.ndarray, upto: int) -> np.ndarray:
    """Dimensionless moments m_j = sum_i w_i (-i)^j / j! for j = 0..upto (dt = 1)."""
    i = np.arange(len(weights), dtype=float)
    return np.array([np.sum(weights * (-i) ** j) / math.factorial(j) for j in range(upto + 1)])


def _finish(order: int, unit_weights: np.ndarray, dt: float, exact_degree: int) -> Stencil:
    """Scales dimensionless weights (dt = 1) to a sampling period and computes the delay."""
    delay_frames = -moments(unit_weights, order + 1)[order + 1]
    return Stencil(order, unit_weights / dt**order, dt, float(delay_frames * dt), exact_degree)


def _check_dt(dt: float) -> float:
    if not (isinstance(dt, (int, float, np.floating)) and np.isfinite(dt) and dt > 0):
        raise InputError(f"sampling period dt must be a positive number of seconds, got {dt!r}")
    return float(dt)


def _check_order(order: int) -> int:
    if isinstance(order, bool) or not isinstance(order, (int, np.integer)) or not 0 <= order <= 2:
        raise InputError(f"derivative order must be 0, 1 or 2, got {order!r}")
    return int(order)


def _jacobi_weight_derivative(u: np.ndarray, a: float, b: float, m: int) -> np.ndarray:
    """d^m/du^m [u^a (1-u)^b] on [0, 1], for a, b > m - 1 (Leibniz rule; 0 at u = 0, 1 if a, b > m)."""
    out = np.zeros_like(u)
    for j in range(m + 1):
        fa = math.prod(a - r for r in range(j))
        fb = math.prod(b - r for r in range(m - j))
        out += math.comb(m, j) * fa * fb * (-1) ** (m - j) * u ** (a - j) * (1 - u) ** (b - m + j)
    return out


def algebraic_weights(order: int, window_frames: int, kappa: float, mu: float, exact_moments: bool = False) -> np.ndarray:
    """Dimensionless weights (dt = 1) of the minimal (kappa, mu) algebraic differentiator.

    Args:
        order: Derivative order n in {0, 1, 2}; 0 is the (kappa, mu) smoothing filter, whose
            weights integrate the normalised Jacobi weight over each interval (incomplete beta).
        window_frames: Number of samples L (window length T = L dt).
        kappa: Jacobi exponent offset on the newest end, > -1.
        mu: Jacobi exponent offset on the oldest end, > -1.
        exact_moments: Project the weights onto m_j = 0 (j < n), m_n = 1 with the smallest
            Euclidean change (only matters for kappa != mu and n >= 2).

    Returns:
        Weights w_i for x_(k-i), shape (L,); divide by dt^n for a sampling period dt.
    """
    a, b = kappa + order, mu + order
    u = np.arange(window_frames + 1) / window_frames
    prim = special.betainc(a + 1, b + 1, u) if order == 0 else _jacobi_weight_derivative(u, a, b, order - 1)
    w = np.diff(prim)
    w = w / moments(w, order)[order]
    if exact_moments:
        i = np.arange(window_frames, dtype=float)
        A = np.stack([(-i) ** j / math.factorial(j) for j in range(order + 1)])
        target = np.zeros(order + 1)
        target[order] = 1.0
        w = w - mv(A.T, solve(rows_mt(A, A), mv(A, w) - target))
    return w


@dataclass(frozen=True)
class AlgebraicConfig:
    """Minimal (kappa, mu) algebraic numerical differentiator (Mboup, Join, Fliess 2009).

    The defaults are the parameters tuned on the benchmark's calibration episodes (30 fps six-axis
    excitations with tracker-like pose errors; see ``benchmark.world.motion``).

    Attributes:
        window_frames: Samples per window L >= 3 (T = L / fps).
        kappa: Exponent offset on the newest end of the window, > -1.
        mu: Exponent offset on the oldest end, > -1. kappa = mu gives a centred window.
        causal: Real-time estimates (delayed, see ``Kinematics.delay_s``) instead of centred ones.
        exact_moments: Make the discrete weights exact on degree-(n+1) polynomials also for
            kappa != mu (see the module docstring); no effect for kappa = mu.
    """

    window_frames: int = 15
    kappa: float = 0.5
    mu: float = 0.5
    causal: bool = False
    exact_moments: bool = True

    name = "algebraic"

    def __post_init__(self):
        L = self.window_frames
        if isinstance(L, bool) or not isinstance(L, (int, np.integer)) or L < 3:
            raise InputError(f"AlgebraicConfig.window_frames must be an integer >= 3, got {L!r}")
        for key in ("kappa", "mu"):
            v = getattr(self, key)
            if not (isinstance(v, (int, float, np.integer, np.floating)) and np.isfinite(v) and v > -1):
                raise InputError(f"AlgebraicConfig.{key} must be a real number > -1, got {v!r}")
        _check_bool("AlgebraicConfig", causal=self.causal, exact_moments=self.exact_moments)

    def stencil(self, order: int, dt: float) -> Stencil:
        order, dt = _check_order(order), _check_dt(dt)
        w = algebraic_weights(order, int(self.window_frames), float(self.kappa), float(self.mu), self.exact_moments)
        exact = order + 1 if (self.exact_moments or self.kappa == self.mu or order == 1) else 0
        return _finish(order, w, dt, exact_degree=exact)

    def describe(self) -> str:
        return f"L={self.window_frames} frames, kappa={self.kappa:g}, mu={self.mu:g}"


@dataclass(frozen=True)
class CentralConfig:
    """Central finite differences.

    Attributes:
        step_frames: Step h in frames (1 = the textbook three-point differences).
        causal: Real-time estimates, h frames late.
    """

    step_frames: int = 1
    causal: bool = False

    name = "central"

    def __post_init__(self):
        h = self.step_frames
        if isinstance(h, bool) or not isinstance(h, (int, np.integer)) or h < 1:
            raise InputError(f"CentralConfig.step_frames must be an integer >= 1, got {h!r}")
        _check_bool("CentralConfig", causal=self.causal)

    def stencil(self, order: int, dt: float) -> Stencil:
        order, dt = _check_order(order), _check_dt(dt)
        if order == 0:
            return _finish(0, np.ones(1), dt, exact_degree=1)
        h = int(self.step_frames)
        w = np.zeros(2 * h + 1)
        if order == 1:
            w[0], w[-1] = 1 / (2 * h), -1 / (2 * h)
        else:
            w[0], w[h], w[-1] = 1 / h**2, -2 / h**2, 1 / h**2
        return _finish(order, w, dt, exact_degree=order + 1)

    def describe(self) -> str:
        return f"h={self.step_frames} frame{'s' if self.step_frames != 1 else ''}"


@dataclass(frozen=True)
class GaussianConfig:
    """Gaussian smoothing followed by central differences (step 1).

    The defaults are the benchmark's calibrated ones (as for :class:`AlgebraicConfig`).

    Attributes:
        sigma_frames: Standard deviation of the Gaussian in frames, > 0.
        truncate: Kernel half-width in standard deviations (radius = ceil(truncate * sigma)).
        causal: Real-time estimates, radius + 1 frames late.
    """

    sigma_frames: float = 3.0
    truncate: float = 2.0
    causal: bool = False

    name = "gaussian"

    def __post_init__(self):
        for key in ("sigma_frames", "truncate"):
            v = getattr(self, key)
            if not (isinstance(v, (int, float, np.integer, np.floating)) and np.isfinite(v) and v > 0):
                raise InputError(f"GaussianConfig.{key} must be a positive number, got {v!r}")
        _check_bool("GaussianConfig", causal=self.causal)

    def kernel(self) -> np.ndarray:
        """The normalised Gaussian, shape (2 r + 1,), r = ceil(truncate * sigma)."""
        r = max(1, math.ceil(self.truncate * self.sigma_frames))
        j = np.arange(-r, r + 1)
        g = np.exp(-0.5 * (j / self.sigma_frames) ** 2)
        return g / g.sum()

    def stencil(self, order: int, dt: float) -> Stencil:
        order, dt = _check_order(order), _check_dt(dt)
        if order == 0:
            return _finish(0, self.kernel(), dt, exact_degree=1)
        diff = np.array([0.5, 0.0, -0.5]) if order == 1 else np.array([1.0, -2.0, 1.0])
        w = convolve_full(self.kernel(), diff)
        return _finish(order, w, dt, exact_degree=2 if order == 1 else 3)

    def describe(self) -> str:
        return f"sigma={self.sigma_frames:g} frames, truncated at {self.truncate:g} sigma"


def _check_bool(owner: str, **flags) -> None:
    for key, v in flags.items():
        if not isinstance(v, (bool, np.bool_)):
            raise InputError(f"{owner}.{key} must be True or False, got {v!r}")
