"""A digital Butterworth band-pass filter in second-order sections: the simulated person's tremor.

:func:`bandpass_sos` is ``scipy.signal.butter(order, (low, high), btype="bandpass", output="sos")``
and :func:`sosfilt` is ``scipy.signal.sosfilt(sos, x)`` for a 1-D signal: the same operations in
the same order, so the same bits (``tests/test_butterworth.py`` compares them over a sweep of bands).
They are here because importing ``scipy.signal`` imports ``scipy.stats``, ``scipy.interpolate``,
``scipy.integrate``, ``scipy.ndimage``, ``scipy.optimize`` and ``scipy.spatial`` with it: 0.45 s of
CPU, a third of the main command's start-up, for the one filter the world uses
(:mod:`benchmark.world.living`).

Ported from SciPy 1.17 (BSD-3-Clause, Copyright (c) 2001-2002 Enthought, Inc. 2003, SciPy
Developers): ``buttap``, ``iirfilter``, ``lp2bp_zpk``, ``bilinear_zpk``, ``zpk2sos`` (pairing
"nearest") with ``_cplxreal``, ``_nearest_real_complex_idx``, ``_single_zpksos``, ``zpk2tf`` and
``poly`` from ``scipy/signal/_filter_design.py`` and ``_polyutils.py``, and the recursion of
``scipy/signal/_sosfilt.pyx`` (transposed direct form II, one section after another).
"""

from __future__ import annotations

import numpy as np

from benchmark.errors import BenchmarkError
from fsv.jit import kernel


def bandpass_sos(order: int, low: float, high: float) -> np.ndarray:
    """The second-order sections of a digital Butterworth band-pass filter.

    Args:
        order: The low-pass prototype's order N (the band-pass filter has 2N poles, N sections).
        low: The lower band edge as a fraction of the Nyquist frequency, in (0, 1).
        high: The upper band edge, in (low, 1).

    Returns:
        ``(N, 6)`` sections ``[b0, b1, b2, 1, a1, a2]``, the gain in the first.

    Raises:
        BenchmarkError: For an order below 1 or band edges outside 0 < low < high < 1.
    """
    if int(order) != order or order < 1:
        raise BenchmarkError(f"order must be an integer >= 1, got {order!r}")
    wn = np.asarray([low, high], dtype=np.float64)
    if not (0 < wn[0] < wn[1] < 1):
        raise BenchmarkError(f"band edges must satisfy 0 < low < high < 1 (fractions of Nyquist), got {low!r}, {high!r}")
    n = int(order)
    # buttap: the analog prototype, cut-off 1 rad/s
    z = np.asarray([], dtype=np.float64)
    m = np.arange(-n + 1, n, 2, dtype=np.float64)
    p = -np.exp(1j * np.pi * m / (2 * n))
    k = 1.0
    # iirfilter: pre-warp the band edges, at fs = 2 (half-cycles per sample)
    fs = 2.0
    warped = 2 * fs * np.tan(np.pi * wn / fs)
    bw = warped[1] - warped[0]
    wo = np.sqrt(warped[0] * warped[1])
    z, p, k = _lp2bp_zpk(z, p, k, wo, bw)
    z, p, k = _bilinear_zpk(z, p, k, fs)
    return _zpk2sos(z, p, k)


def sosfilt(sos: np.ndarray, x: np.ndarray) -> np.ndarray:
    """``x`` (N,) filtered by the sections ``sos`` (S, 6) from rest: a new (N,) float64 array."""
    sos = np.asarray(sos, dtype=np.float64)
    if sos.ndim != 2 or sos.shape[1] != 6 or not np.all(sos[:, 3] == 1):
        raise BenchmarkError(f"sos must be (sections, 6) with a0 = 1, got shape {sos.shape}")
    out = np.array(x, dtype=np.float64, order="C")
    if out.ndim != 1:
        raise BenchmarkError(f"x must be one signal (N,), got shape {out.shape}")
    _sosfilt(np.ascontiguousarray(sos), out, np.zeros((sos.shape[0], 2)))
    return out


@kernel
def _sosfilt(sos, x, zi):  # pragma: no cover - compiled
    # scipy/signal/_sosfilt.pyx, _sosfilt_float: in place, the same products and sums in order
    for n in range(x.shape[0]):
        x_cur = x[n]
        for s in range(sos.shape[0]):
            x_new = sos[s, 0] * x_cur + zi[s, 0]
            zi[s, 0] = sos[s, 1] * x_cur - sos[s, 4] * x_new + zi[s, 1]
            zi[s, 1] = sos[s, 2] * x_cur - sos[s, 5] * x_new
            x_cur = x_new
        x[n] = x_cur


def _lp2bp_zpk(z, p, k, wo, bw) -> tuple:
    z = z.astype(np.complex128)  # scipy promotes the zeros with the poles
    wo, bw = float(wo), float(bw)
    degree = p.shape[0] - z.shape[0]
    z_lp = z * bw / 2
    p_lp = p * bw / 2
    z_lp = z_lp.astype(np.complex128)
    p_lp = p_lp.astype(np.complex128)
    z_bp = np.concatenate((z_lp + np.sqrt(z_lp**2 - wo**2), z_lp - np.sqrt(z_lp**2 - wo**2)))
    p_bp = np.concatenate((p_lp + np.sqrt(p_lp**2 - wo**2), p_lp - np.sqrt(p_lp**2 - wo**2)))
    z_bp = np.concatenate((z_bp, np.zeros(degree)))
    return z_bp, p_bp, k * bw**degree


def _bilinear_zpk(z, p, k, fs) -> tuple:
    degree = p.shape[0] - z.shape[0]
    fs2 = 2.0 * fs
    z_z = (fs2 + z) / (fs2 - z)
    p_z = (fs2 + p) / (fs2 - p)
    z_z = np.concatenate((z_z, -np.ones(degree)))
    k_z = k * np.real(np.prod(fs2 - z) / np.prod(fs2 - p))
    return z_z, p_z, k_z


def _cplxreal(z) -> tuple:
    z = np.atleast_1d(z)
    if z.size == 0:
        return z, z
    tol = 100 * np.finfo((1.0 * z).dtype).eps
    z = z[np.lexsort((abs(z.imag), z.real))]
    real_indices = abs(z.imag) <= tol * abs(z)
    zr = z[real_indices].real
    if len(zr) == len(z):
        return np.array([]), zr
    z = z[~real_indices]
    zp = z[z.imag > 0]
    zn = z[z.imag < 0]
    if len(zp) != len(zn):
        raise BenchmarkError("a complex zero or pole without its conjugate")
    same_real = np.diff(zp.real) <= tol * abs(zp[:-1])
    diffs = np.diff(np.concatenate(([0], same_real, [0])))
    run_starts = np.nonzero(diffs > 0)[0]
    run_stops = np.nonzero(diffs < 0)[0]
    for i in range(len(run_starts)):
        start = run_starts[i]
        stop = run_stops[i] + 1
        for chunk in (zp[start:stop], zn[start:stop]):
            chunk[...] = chunk[np.lexsort([abs(chunk.imag)])]
    if any(abs(zp - zn.conj()) > tol * abs(zn)):
        raise BenchmarkError("a complex zero or pole without its conjugate")
    zc = (zp + zn.conj()) / 2
    return zc, zr


def _nearest_real_complex_idx(fro, to, which: str):
    order = np.argsort(np.abs(fro - to))
    if which == "any":
        return order[0]
    mask = np.isreal(fro[order])
    if which == "complex":
        mask = ~mask
    return order[np.nonzero(mask)[0][0]]


def _poly(zeros) -> np.ndarray:
    zeros = np.atleast_1d(np.asarray(zeros))
    if zeros.shape[0] == 0:
        return np.asarray(1.0, dtype=np.real(zeros).dtype)
    a = np.ones((1,), dtype=zeros.dtype)
    one = np.ones_like(zeros[0])
    for zero in zeros:
        a = np.convolve(a, np.stack((one, -zero)), mode="full")
    if np.iscomplexobj(a):
        roots = np.asarray(zeros, dtype=np.complex128)
        if np.all(np.sort(np.imag(roots)) == np.sort(np.imag(np.conj(roots)))):
            a = np.array(np.real(a), copy=True)
    return a


def _single_zpksos(z, p, k) -> np.ndarray:
    sos = np.zeros(6)
    z, p = np.asarray(z), np.asarray(p)
    k = np.atleast_1d(np.asarray(k, dtype=np.result_type(np.real(z), np.real(p), k)))
    b = np.multiply(k, _poly(np.atleast_1d(z)))
    a = np.atleast_1d(np.asarray(_poly(p)))
    sos[3 - len(b):3] = b
    sos[6 - len(a):6] = a
    return sos


def _zpk2sos(z, p, k) -> np.ndarray:
    z, p, k = np.asarray(z), np.asarray(p), np.asarray(k)
    p = np.concatenate((p, np.zeros(max(len(z) - len(p), 0))))
    z = np.concatenate((z, np.zeros(max(len(p) - len(z), 0))))
    n_sections = (max(len(p), len(z)) + 1) // 2
    if len(p) % 2 == 1:
        p = np.concatenate((p, [0.0]))
        z = np.concatenate((z, [0.0]))
    z = np.concatenate(_cplxreal(z))
    p = np.concatenate(_cplxreal(p))
    if not np.isreal(k):
        raise BenchmarkError("the gain must be real")
    k = k.real

    def idx_worst(p):  # digital: the pole closest to the unit circle
        return np.argmin(np.abs(1 - np.abs(p)))

    sos = np.zeros((n_sections, 6))
    for si in range(n_sections - 1, -1, -1):  # the "worst" sections last
        p1_idx = idx_worst(p)
        p1 = p[p1_idx]
        p = np.delete(p, p1_idx)
        if np.isreal(p1) and np.isreal(p).sum() == 0:  # the last real pole
            z1_idx = _nearest_real_complex_idx(z, p1, "real")
            z1 = z[z1_idx]
            z = np.delete(z, z1_idx)
            sos[si] = _single_zpksos([z1, 0], [p1, 0], 1)
        elif len(p) + 1 == len(z) and not np.isreal(p1) and np.isreal(p).sum() == 1 and np.isreal(z).sum() == 1:
            z1_idx = _nearest_real_complex_idx(z, p1, "complex")  # one real pole and zero left: a complex zero
            z1 = z[z1_idx]
            z = np.delete(z, z1_idx)
            sos[si] = _single_zpksos([z1, z1.conj()], [p1, p1.conj()], 1)
        else:
            if np.isreal(p1):
                prealidx = np.flatnonzero(np.isreal(p))
                p2_idx = prealidx[idx_worst(p[prealidx])]
                p2 = p[p2_idx]
                p = np.delete(p, p2_idx)
            else:
                p2 = p1.conj()
            if len(z) > 0:
                z1_idx = _nearest_real_complex_idx(z, p1, "any")
                z1 = z[z1_idx]
                z = np.delete(z, z1_idx)
                if not np.isreal(z1):
                    sos[si] = _single_zpksos([z1, z1.conj()], [p1, p2], 1)
                elif len(z) > 0:
                    z2_idx = _nearest_real_complex_idx(z, p1, "real")
                    z2 = z[z2_idx]
                    z = np.delete(z, z2_idx)
                    sos[si] = _single_zpksos([z1, z2], [p1, p2], 1)
                else:
                    sos[si] = _single_zpksos([z1], [p1, p2], 1)
            else:
                sos[si] = _single_zpksos([], [p1, p2], 1)
    sos[0][:3] *= k
    return sos
