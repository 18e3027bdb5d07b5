"""Bounded nonlinear least squares without BLAS: the same bits on every CPU and OpenBLAS kernel.

:func:`solve` minimises ``0.5 * sum(fun(x)**2)`` subject to ``lb <= x <= ub`` by a projected
Levenberg-Marquardt method. It replaces ``scipy.optimize.least_squares`` where the solution must not
depend on the BLAS kernel: scipy's trust-region solvers factor the Jacobian with LAPACK (QR, SVD)
and multiply with BLAS, whose kernels (picked per CPU, or by ``OPENBLAS_CORETYPE``) round
differently in the last bits, and an iterative fit carries those bits into its answer.

Here every reduction is a loop in a fixed order compiled by numba without fast-math (the normal
equations, the Cholesky factorisation, the cost; :mod:`fsv.linalg`'s rule), and everything else is
NumPy element-wise arithmetic (+ - * /, comparisons, clipping), which rounds the same everywhere.

The method, in the variables scaled by ``x_scale`` (``u = x / x_scale``, as scipy's ``x_scale``):

* the Jacobian by forward differences with scipy's ``'2-point'`` steps (``sqrt(eps) * max(1, |x|)``,
  signed like ``x``, flipped where the step would leave the bounds), one column at a time;
* the variables on a bound whose gradient points out of the box are held; for the others the step
  solves ``(J^T J + lam I) p = -J^T f`` (a written-out Cholesky), and ``x + p`` is clipped into the
  bounds;
* the step is taken if it lowers the cost; ``lam`` follows Nielsen's rule (initially ``1e-3`` times
  the largest diagonal element of ``J^T J``; down by up to 3 after a step taken by its gain ratio, up
  by 2, 4, 8, ... after each refused);
* it stops (deterministically: every test is on the same bits) when a step taken lowers the cost by
  less than ``ftol`` of it, a step is shorter than ``xtol * (xtol + |u|)``, the largest projected
  gradient is below ``gtol``, ``lam`` exceeds 1e16, or after ``max_nfev`` evaluations of ``fun``
  (not counting the Jacobian's, as scipy's ``'trf'``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fsv.jit import kernel

_EPS = np.finfo(float).eps


@dataclass(frozen=True)
class Result:
    """The answer of :func:`solve`.

    Attributes:
        x: The solution, (n,), within the bounds.
        cost: ``0.5 * sum(fun(x)**2)`` (summed in a fixed order).
        nfev: Evaluations of ``fun`` outside the Jacobian.
        njev: Jacobians computed.
        status: Why it stopped: ``"ftol"``, ``"xtol"``, ``"gtol"``, ``"lam"`` or ``"max_nfev"``.
    """

    x: np.ndarray
    cost: float
    nfev: int
    njev: int
    status: str


@kernel
def half_sum_squares(f):  # pragma: no cover - compiled
    """``0.5 * sum(f**2)``, summed in index order."""
    s = 0.0
    for i in range(f.shape[0]):
        s += f[i] * f[i]
    return 0.5 * s


@kernel
def _normal_equations(J, f, scale):  # pragma: no cover - compiled
    """``A = Js^T Js`` and ``g = Js^T f`` of the column-scaled Jacobian ``Js = J diag(scale)``,
    summed over rows in index order."""
    m, n = J.shape
    A = np.zeros((n, n))
    g = np.zeros(n)
    for r in range(m):
        fr = f[r]
        for i in range(n):
            a = J[r, i] * scale[i]
            if a != 0.0:
                g[i] += a * fr
                for j in range(i, n):
                    A[i, j] += a * (J[r, j] * scale[j])
    for i in range(n):
        for j in range(i):
            A[i, j] = A[j, i]
    return A, g


@kernel
def _damped_step(A, g, free, lam):  # pragma: no cover - compiled
    """The step ``p`` with ``(A_FF + lam I) p_F = -g_F`` on the free variables (zero elsewhere), by
    a Cholesky factorisation written out; ``ok`` False if a pivot is not positive."""
    n = A.shape[0]
    idx = np.empty(n, np.int64)
    k = 0
    for i in range(n):
        if free[i]:
            idx[k] = i
            k += 1
    L = np.zeros((k, k))
    for a in range(k):
        for b in range(a + 1):
            s = A[idx[a], idx[b]]
            if a == b:
                s += lam
            for c in range(b):
                s -= L[a, c] * L[b, c]
            if a == b:
                if not s > 0.0:
                    return np.zeros(n), False
                L[a, a] = np.sqrt(s)
            else:
                L[a, b] = s / L[b, b]
    y = np.zeros(k)
    for a in range(k):
        s = -g[idx[a]]
        for c in range(a):
            s -= L[a, c] * y[c]
        y[a] = s / L[a, a]
    z = np.zeros(k)
    for a in range(k - 1, -1, -1):
        s = y[a]
        for c in range(a + 1, k):
            s -= L[c, a] * z[c]
        z[a] = s / L[a, a]
    p = np.zeros(n)
    for a in range(k):
        p[idx[a]] = z[a]
    return p, True


@kernel
def _predicted_reduction(A, g, d):  # pragma: no cover - compiled
    """``-(g.d + 0.5 d^T A d)``: the cost's decrease that the linearisation predicts for step ``d``."""
    n = d.shape[0]
    lin = 0.0
    quad = 0.0
    for i in range(n):
        lin += g[i] * d[i]
        s = 0.0
        for j in range(n):
            s += A[i, j] * d[j]
        quad += d[i] * s
    return -(lin + 0.5 * quad)


@kernel
def _norm(v):  # pragma: no cover - compiled
    s = 0.0
    for i in range(v.shape[0]):
        s += v[i] * v[i]
    return np.sqrt(s)


def _steps(x: np.ndarray, lb: np.ndarray, ub: np.ndarray) -> np.ndarray:
    """scipy's ``'2-point'`` absolute steps (``approx_derivative``): ``sqrt(eps) max(1, |x|)`` signed
    like ``x`` (+ for 0), flipped where ``x + h`` leaves the bounds and ``-h`` fits."""
    sign = np.where(x >= 0, 1.0, -1.0)
    h = np.sqrt(_EPS) * sign * np.maximum(1.0, np.abs(x))
    violated = ((x + h) < lb) | ((x + h) > ub)
    fitting = np.abs(h) <= np.maximum(x - lb, ub - x)
    return np.where(violated & fitting, -h, h)


def jacobian(fun, x: np.ndarray, f0: np.ndarray, lb: np.ndarray, ub: np.ndarray) -> np.ndarray:
    """Forward-difference Jacobian of ``fun`` at ``x`` ((m,), ``f0 = fun(x)``), one column at a time: (m, n)."""
    h = _steps(x, lb, ub)
    J = np.empty((f0.shape[0], x.shape[0]))
    for j in range(x.shape[0]):
        xj = x.copy()
        xj[j] = x[j] + h[j]
        J[:, j] = (np.asarray(fun(xj), dtype=float) - f0) / (xj[j] - x[j])
    return J


def solve(fun, x0, lb, ub, x_scale, *, max_nfev: int = 400, ftol: float = 1e-8, xtol: float = 1e-8,
          gtol: float = 1e-8) -> Result:
    """Minimises ``0.5 * sum(fun(x)**2)`` over ``lb <= x <= ub`` (see the module's text).

    Args:
        fun: The residuals, x (n,) -> (m,); it must itself be free of BLAS for the answer to be.
        x0: Start, (n,); clipped into the bounds.
        lb, ub: Bounds, (n,) each, ``lb < ub``.
        x_scale: The variables' characteristic sizes, (n,), > 0 (as scipy's ``x_scale``).
        max_nfev: Evaluations of ``fun`` (outside the Jacobian) before it stops.
        ftol, xtol, gtol: Tolerances on the cost's relative decrease, the step and the gradient.

    Returns:
        A :class:`Result`.
    """
    lb, ub = np.asarray(lb, dtype=float), np.asarray(ub, dtype=float)
    scale = np.ascontiguousarray(x_scale, dtype=float)
    x = np.clip(np.asarray(x0, dtype=float), lb, ub)
    f = np.ascontiguousarray(fun(x), dtype=float)
    cost = half_sum_squares(f)
    nfev, njev, lam, nu = 1, 0, -1.0, 2.0
    while True:
        J = np.ascontiguousarray(jacobian(fun, x, f, lb, ub))
        njev += 1
        A, g = _normal_equations(J, f, scale)
        free = ~(((x <= lb) & (g > 0)) | ((x >= ub) & (g < 0)))
        if np.max(np.abs(np.where(free, g, 0.0))) < gtol:
            return Result(x, cost, nfev, njev, "gtol")
        if lam < 0:
            lam = 1e-3 * float(np.max(np.diagonal(A)))
        while True:
            if nfev >= max_nfev:
                return Result(x, cost, nfev, njev, "max_nfev")
            if lam > 1e16:
                return Result(x, cost, nfev, njev, "lam")
            p, ok = _damped_step(A, g, free, lam)
            if not ok:
                lam, nu = lam * nu, 2 * nu
                continue
            x_new = np.clip(x + p * scale, lb, ub)
            d = (x_new - x) / scale
            f_new = np.ascontiguousarray(fun(x_new), dtype=float)
            nfev += 1
            cost_new = half_sum_squares(f_new)
            actual = cost - cost_new
            predicted = _predicted_reduction(A, g, d)
            step = _norm(d)
            if actual > 0 and predicted > 0:
                t = 2 * (actual / predicted) - 1
                lam, nu = lam * max(1 / 3, 1 - t * t * t), 2.0
                x, f, cost_old, cost = x_new, f_new, cost, cost_new
                if actual < ftol * cost_old:
                    return Result(x, cost, nfev, njev, "ftol")
                if step < xtol * (xtol + _norm(x / scale)):
                    return Result(x, cost, nfev, njev, "xtol")
                break
            if step < xtol * (xtol + _norm(x / scale)):
                return Result(x, cost, nfev, njev, "xtol")
            lam, nu = lam * nu, 2 * nu
