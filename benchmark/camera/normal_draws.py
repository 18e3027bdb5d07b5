"""NumPy's float32 standard normal draws, compiled: the same values and the same generator state as
``rng.standard_normal(dtype=np.float32, out=out)``, about three times faster.

NumPy draws float32 normals one at a time in C through its bit generator's function pointers
(``random_standard_normal_f``, ``numpy/random/src/distributions/distributions.c``: a 256-layer
ziggurat on one 32-bit word per draw, with a wedge test in double precision and an exponential
tail). :func:`standard_normal_f32` runs that algorithm, step for step and in the same precisions,
as a numba loop that calls the same bit generator's ``next_uint32`` (numba's binding of
``bit_generator.ctypes``), so it consumes the same words in the same order. Measured on the
2-core Xeon: 7.8 ns a draw through NumPy, 2.3 ns here; the depth sensor draws three normals a
pixel every frame (230 400 a 320 x 240 frame: 1.8 ms -> 0.5 ms). Numba's own
``Generator.standard_normal(dtype=float32)`` is not used: its wedge test computes the
exponential in single precision, where NumPy's C computes it in double, so a draw near the wedge's
edge could differ.

The ziggurat's tables are numba's copy of NumPy's (``numba.np.random._constants``), the word and
float draws numba's bindings of the bit generator (``numba.np.random.generator_core``; both part of
numba's ``Generator`` support since 0.56). tests/test_normal_draws.py checks the bits and the
generator's state against NumPy's over a million draws a seed, through the wedge and the tail, on
seeds where a single-precision wedge test would differ.

Like any use of a generator outside its own methods, this does not take the bit generator's lock:
a generator must not be drawn from by two threads at once.
"""

from __future__ import annotations

import math

import numpy as np
from numba.np.random._constants import fi_float, ki_float, wi_float, ziggurat_nor_inv_r_f, ziggurat_nor_r_f
from numba.np.random.distributions import np_log1pf
from numba.np.random.generator_core import next_float, next_uint32

from benchmark.errors import BenchmarkError
from fsv.jit import kernel

_WI = np.asarray(wi_float, dtype=np.float32)
_KI = np.asarray(ki_float, dtype=np.uint32)
_FI = np.asarray(fi_float, dtype=np.float32)
_R = np.float32(ziggurat_nor_r_f)
_INV_R = np.float32(ziggurat_nor_inv_r_f)


def standard_normal_f32(rng: np.random.Generator, out: np.ndarray) -> np.ndarray:
    """Fills ``out`` with standard normal draws from ``rng``, in C order: the bits and the state
    that ``rng.standard_normal(dtype=np.float32, out=out)`` gives.

    Args:
        rng: The generator; advanced by the draws.
        out: A C-contiguous float32 array of any shape.

    Returns:
        ``out``.
    """
    if not isinstance(rng, np.random.Generator):
        raise BenchmarkError(f"standard_normal_f32 takes a numpy.random.Generator, got {type(rng).__name__}")
    if not (isinstance(out, np.ndarray) and out.dtype == np.float32 and out.flags.c_contiguous and out.flags.writeable):
        what = f"{out.dtype} array" if isinstance(out, np.ndarray) else type(out).__name__
        raise BenchmarkError(f"standard_normal_f32 fills a writeable C-contiguous float32 array, got a {what}")
    _fill(rng, out.reshape(-1))
    return out


@kernel(nogil=False)
def _fill(rng, flat):  # pragma: no cover - compiled
    bitgen = rng.bit_generator
    for i in range(flat.size):
        flat[i] = _draw(bitgen)


@kernel(nogil=False, inline="always")
def _draw(bitgen):  # pragma: no cover - compiled
    # random_standard_normal_f of NumPy's distributions.c, line for line
    while True:
        r = next_uint32(bitgen)
        idx = r & 0xFF
        sign = (r >> 8) & 0x1
        rabs = (r >> 9) & 0x0007FFFFF
        x = np.float32(np.float32(rabs) * _WI[idx])
        if sign & 0x1:
            x = -x
        if rabs < _KI[idx]:
            return x  # 99.3 % of the draws
        if idx == 0:  # the tail beyond r, by an exponential's rejection (float precision)
            while True:
                xx = np.float32(-_INV_R * np_log1pf(-next_float(bitgen)))
                yy = np.float32(-np_log1pf(-next_float(bitgen)))
                if np.float32(yy + yy) > np.float32(xx * xx):
                    return -np.float32(_R + xx) if (rabs >> 8) & 0x1 else np.float32(_R + xx)
        else:  # the wedge: a float uniform in the layer against exp(-x^2 / 2) in double, as C promotes it
            u = np.float32(np.float32((_FI[idx - 1] - _FI[idx]) * next_float(bitgen)) + _FI[idx])
            if np.float64(u) < math.exp(-0.5 * np.float64(x) * np.float64(x)):
                return x
