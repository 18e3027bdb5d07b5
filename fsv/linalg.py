"""Small linear algebra in a fixed order of operations: the same bits on every CPU and BLAS kernel.

NumPy hands ``@``, ``np.dot``, ``np.correlate``, ``np.convolve``, ``np.linalg.norm`` of a whole
array, ``np.linalg.solve`` and ``np.linalg.inv`` to BLAS and LAPACK. OpenBLAS picks its kernels by
CPU (or by ``OPENBLAS_CORETYPE``), and kernels with and without fused multiply-adds, or with other blockings,
round differently in the last bits. Fed back through a simulation or an iterative fit, those bits
grow into visibly different trajectories. Every product and solve in the simulation loop, the
renderer's inputs, the tracker and the force stage therefore goes through this module instead:

* products are :func:`numpy.einsum` contractions with ``optimize=False`` (NumPy's own loops,
  which never call BLAS) or explicit element-wise sums;
* solves are a Cholesky or LU factorisation compiled with numba, without fast-math, so the
  compiler may not reorder or fuse the arithmetic.

The arrays here are small (3 x 3 rotations, (N, 3) point sets, normal equations of at most a few
dozen unknowns); for them the cost is the call overhead, comparable to BLAS.
"""

from __future__ import annotations

import numpy as np

from fsv.jit import kernel


def mm(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Matrix product ``a @ b`` of (stacks of) matrices, broadcast over leading axes.

    Args:
        a: Shape (..., n, k).
        b: Shape (..., k, m).

    Returns:
        Shape (..., n, m).
    """
    return np.einsum("...ij,...jk->...ik", a, b)


def mv(a: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Matrix-vector product ``a @ x``, broadcast over leading axes: (..., n, k), (..., k) -> (..., n)."""
    return np.einsum("...ij,...j->...i", a, x)


def vm(x: np.ndarray, a: np.ndarray) -> np.ndarray:
    """Row vectors times a matrix, ``x @ a``: (..., k), (..., k, m) -> (..., m).

    A stack of points (N, 3) times a rotation (3, 3) is ``vm(points, R)``.
    """
    return np.einsum("...k,...km->...m", x, a)


def rows_mt(x: np.ndarray, a: np.ndarray) -> np.ndarray:
    """Rows of ``x`` times the transpose of ``a``, ``x @ a.T``: (N, k), (m, k) -> (N, m)."""
    return np.einsum("nk,mk->nm", x, a)


def dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Inner product along the last axis: (..., n), (..., n) -> (...)."""
    return np.einsum("...i,...i->...", a, b)


def norm(x: np.ndarray) -> float:
    """Euclidean norm of a whole array (what ``np.linalg.norm(x)`` computes through BLAS)."""
    x = np.ravel(x)
    return float(np.sqrt(np.einsum("i,i->", x, x)))


def rigid_inverse(T: np.ndarray) -> np.ndarray:
    """The inverse of a rigid transform, (4, 4) -> (4, 4): ``[R^T, -R^T t]`` in a fixed order of
    operations (no LAPACK inverse)."""
    T = np.asarray(T, dtype=float)
    out = np.eye(4)
    out[:3, :3] = T[:3, :3].T
    out[:3, 3] = -mv(out[:3, :3], T[:3, 3])
    return out


def correlate_valid(x: np.ndarray, w: np.ndarray) -> np.ndarray:
    """``np.correlate(x, w, "valid")`` of 1-D arrays: out[j] = sum_k x[j + k] w[k], (N,), (L,) -> (N - L + 1,)."""
    x, w = np.asarray(x, dtype=float), np.asarray(w, dtype=float)
    return np.einsum("nk,k->n", np.lib.stride_tricks.sliding_window_view(x, w.shape[0]), w)


def convolve_full(a: np.ndarray, v: np.ndarray) -> np.ndarray:
    """``np.convolve(a, v)`` ("full") of 1-D arrays: (N,), (M,) -> (N + M - 1,)."""
    a, v = np.asarray(a, dtype=float), np.asarray(v, dtype=float)
    pad = np.concatenate([np.zeros(v.shape[0] - 1), a, np.zeros(v.shape[0] - 1)])
    return correlate_valid(pad, v[::-1])


def gram(J: np.ndarray, w: np.ndarray | None = None) -> np.ndarray:
    """``J.T @ diag(w) @ J`` of a tall matrix, (N, P) -> (P, P), symmetric by construction.

    Args:
        J: Shape (N, P).
        w: Optional row weights, shape (N,).
    """
    J = np.ascontiguousarray(J, dtype=np.float64)
    if w is None:
        return _gram(J, np.ones(J.shape[0]))
    return _gram(J, np.ascontiguousarray(w, dtype=np.float64))


def tmv(J: np.ndarray, r: np.ndarray) -> np.ndarray:
    """``J.T @ r`` of a tall matrix: (N, P), (N,) -> (P,)."""
    return np.einsum("np,n->p", J, r)


@kernel
def _gram(J, w):  # pragma: no cover - compiled
    N, P = J.shape
    out = np.zeros((P, P))
    for n in range(N):
        wn = w[n]
        for i in range(P):
            a = wn * J[n, i]
            if a != 0.0:
                for j in range(i, P):
                    out[i, j] += a * J[n, j]
    for i in range(P):
        for j in range(i):
            out[i, j] = out[j, i]
    return out


def solve(A: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Solves ``A x = b`` for a small square ``A`` by LU with partial pivoting.

    Args:
        A: Shape (n, n), non-singular.
        b: Shape (n,) or (n, m).

    Returns:
        x with the shape of ``b``.

    Raises:
        np.linalg.LinAlgError: If ``A`` is singular (a zero pivot).
    """
    A = np.array(A, dtype=np.float64, order="C")
    b = np.asarray(b, dtype=np.float64)
    if A.ndim != 2 or A.shape[0] != A.shape[1] or b.shape[0] != A.shape[0]:
        raise ValueError(f"solve needs A (n, n) and b (n,) or (n, m); got {A.shape} and {b.shape}")
    B = np.array(b.reshape(b.shape[0], -1), order="C")
    if not _lu_solve(A, B):
        raise np.linalg.LinAlgError("singular matrix")
    return B.reshape(b.shape)


def inv(A: np.ndarray) -> np.ndarray:
    """Inverse of a small square matrix (LU with partial pivoting, fixed order)."""
    A = np.asarray(A, dtype=np.float64)
    return solve(A, np.eye(A.shape[0]))


@kernel
def _lu_solve(A, B):  # pragma: no cover - compiled
    n = A.shape[0]
    m = B.shape[1]
    for k in range(n):
        p = k
        big = abs(A[k, k])
        for i in range(k + 1, n):
            if abs(A[i, k]) > big:
                big = abs(A[i, k])
                p = i
        if big == 0.0:
            return False
        if p != k:
            for j in range(n):
                t = A[k, j]
                A[k, j] = A[p, j]
                A[p, j] = t
            for j in range(m):
                t = B[k, j]
                B[k, j] = B[p, j]
                B[p, j] = t
        piv = A[k, k]
        for i in range(k + 1, n):
            f = A[i, k] / piv
            if f != 0.0:
                for j in range(k + 1, n):
                    A[i, j] -= f * A[k, j]
                for j in range(m):
                    B[i, j] -= f * B[k, j]
    for i in range(n - 1, -1, -1):
        for j in range(m):
            s = B[i, j]
            for c in range(i + 1, n):
                s -= A[i, c] * B[c, j]
            B[i, j] = s / A[i, i]
    return True
