"""The grip controller's inner loops, compiled: the same operations in the same order as NumPy's.

:meth:`benchmark.world.grip.GripPolicy.hold` presses the digits one after another, pass after pass,
over every control tick of an episode; written with NumPy it spent most of a simulation's CPU in
the interpreter (a 10 s lift: 0.5-0.7 s of 1.9-2.4 s). :func:`hold_passes` is the same arithmetic
in a loop compiled by numba without fast-math (no reordering, no fused multiply-adds), and each
sum in the order NumPy computes it at the baseline instructions the package pins
(:mod:`benchmark.simd`): ``np.einsum`` over three components adds the first and the third, then
the second. ``tests/test_grip_kernels.py`` compares it with the NumPy loop bit for bit.
"""

from __future__ import annotations

import math

import numba
import numpy as np

_jit = numba.njit(cache=True, nogil=True, error_model="numpy")


def hold_passes(f: np.ndarray, c: np.ndarray, slope: np.ndarray, held_load: np.ndarray | None,
                press: np.ndarray, normals_in: np.ndarray, order: np.ndarray, min_force_n: float,
                passes: int, tolerance_n: float) -> None:
    """The digit-by-digit passes of :meth:`~benchmark.world.grip.GripPolicy.hold`, in place.

    In each pass every digit of ``order`` in turn is pressed by its deficit, ``max(max(slope t,
    min_force_n) - n, 0)`` (n its normal force, t its tangential load or ``held_load`` where that
    is larger): the deficit is added to its press ``c`` and its unit press times the deficit to
    the forces ``f``. The passes stop after ``passes`` or once no digit of any tick was short by
    more than ``tolerance_n``.

    Args:
        f: The digits' forces per tick, (N, K, 3) [N], float64, C-contiguous: updated.
        c: The presses per tick, (N, K) [N], float64, C-contiguous: updated.
        slope: Normal force per newton of tangential load per tick, (N,).
        held_load: The least tangential load each digit is pressed for, (N, K) [N], or None.
        press: Unit presses per digit, (K, K, 3).
        normals_in: Unit normals into the box, (K, 3).
        order: The digits in the order they are pressed, (A,) int.
        min_force_n: Every digit's least normal force, [N].
        passes: Passes at most.
        tolerance_n: A deficit this small or smaller needs no further pass, [N].
    """
    N, K = f.shape[:2]
    held = np.zeros((N, K)) if held_load is None else np.ascontiguousarray(held_load, dtype=np.float64)
    _hold_passes(f, c, np.ascontiguousarray(slope, dtype=np.float64), held, held_load is not None,
                 np.ascontiguousarray(press, dtype=np.float64), np.ascontiguousarray(normals_in, dtype=np.float64),
                 np.ascontiguousarray(order, dtype=np.int64), float(min_force_n), int(passes), float(tolerance_n))


@_jit
def _maximum(a, b):  # pragma: no cover - compiled
    # np.maximum of two scalars: NaN if either is NaN, else the larger
    if a != a or a >= b:
        return a
    return b


@_jit
def _hold_passes(f, c, slope, held, use_held, press, normals, order, min_force, passes, tol):  # pragma: no cover - compiled
    N, K = f.shape[0], f.shape[1]
    deficit = np.empty(N)
    for _ in range(passes):
        added = 0.0
        for j in order:
            u0, u1, u2 = normals[j, 0], normals[j, 1], normals[j, 2]
            peak = -np.inf
            peak_nan = False
            for i in range(N):
                # n = einsum("nd,d->n", f[:, j], u): (f0 u0 + f2 u2) + f1 u1
                n = (f[i, j, 0] * u0 + f[i, j, 2] * u2) + f[i, j, 1] * u1
                # t = |f - n u|: sqrt of einsum("ni,ni->n"), (d0 d0 + d2 d2) + d1 d1
                d0 = f[i, j, 0] - n * u0
                d1 = f[i, j, 1] - n * u1
                d2 = f[i, j, 2] - n * u2
                t = math.sqrt((d0 * d0 + d2 * d2) + d1 * d1)
                if use_held:
                    t = _maximum(t, held[i, j])
                e = _maximum(_maximum(slope[i] * t, min_force) - n, 0.0)
                deficit[i] = e
                if e != e:
                    peak_nan = True
                elif e > peak:
                    peak = e
            for i in range(N):
                e = deficit[i]
                c[i, j] += e
                for k in range(K):
                    for d in range(3):
                        f[i, k, d] = f[i, k, d] + e * press[j, k, d]
            # added = max(added, float(np.max(deficit))): np.max is NaN where any deficit is, and
            # Python's max keeps ``added`` against a NaN
            if not peak_nan and N > 0 and peak > added:
                added = peak
        if added <= tol:
            break
