"""benchmark.world.grip_kernels: the compiled passes of the grip's hold, the bits of the NumPy loop."""

import numpy as np
import pytest

from benchmark.world.grip_kernels import hold_passes


def _numpy_passes(f, slope, held_load, press, normals_in, order, min_force_n, passes, tolerance_n):
    """The hold's passes as NumPy computes them (the loop the kernel replaces): ``(f, c)``."""
    N, K = f.shape[:2]
    c = np.zeros((N, K))
    for _ in range(passes):
        added = 0.0
        for j in order:
            n = np.einsum("nd,d->n", f[:, j], normals_in[j])
            d = f[:, j] - n[:, None] * normals_in[j]
            t = np.sqrt(np.einsum("ni,ni->n", d, d))
            if held_load is not None:
                t = np.maximum(t, held_load[:, j])
            deficit = np.maximum(np.maximum(slope * t, min_force_n) - n, 0.0)
            c[:, j] += deficit
            f = f + deficit[:, None, None] * press[j]
            added = max(added, float(np.max(deficit)))
        if added <= tolerance_n:
            break
    return f, c


def _case(seed, N=700, K=5):
    rng = np.random.default_rng(seed)
    normals = rng.normal(size=(K, 3))
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    f = rng.normal(size=(N, K, 3)) * 10.0 ** rng.uniform(-2, 1.5, size=(N, K, 1))
    press = 0.3 * rng.normal(size=(K, K, 3))
    for j in range(K):  # a digit's own press pushes it along its normal, as the grip's do
        press[j, j] = normals[j]
    slope = rng.uniform(1.0, 4.0, size=N)
    return f, slope, np.abs(rng.normal(size=(N, K))) * 3.0, press, normals


@pytest.mark.parametrize("seed", [0, 1, 2])
@pytest.mark.parametrize("held", [False, True])
def test_the_passes_are_the_numpy_loops_bits(seed, held):
    f, slope, held_load, press, normals = _case(seed)
    held_load = held_load if held else None
    order = np.array([1, 2, 4, 0])
    want_f, want_c = _numpy_passes(f.copy(), slope, held_load, press, normals, order, 1.0, 30, 1e-6)
    got_f, got_c = f.copy(), np.zeros(f.shape[:2])
    hold_passes(got_f, got_c, slope, held_load, press, normals, order, 1.0, 30, 1e-6)
    assert got_f.tobytes() == want_f.tobytes() and got_c.tobytes() == want_c.tobytes()
    assert np.all(got_c[:, 3] == 0.0) and got_c[:, [1, 2, 4, 0]].max() > 1.0  # digit 3 is not in the order


def test_the_passes_stop_at_the_tolerance_or_the_limit():
    f, slope, _, press, normals = _case(3, N=50)
    order = np.array([0, 1, 2])
    one_f, one_c = f.copy(), np.zeros(f.shape[:2])
    hold_passes(one_f, one_c, slope, None, press, normals, order, 1.0, 1, 1e-6)
    assert one_c.tobytes() == _numpy_passes(f.copy(), slope, None, press, normals, order, 1.0, 1, 1e-6)[1].tobytes()
    # a tolerance larger than any deficit: one pass, whatever the limit
    loose_f, loose_c = f.copy(), np.zeros(f.shape[:2])
    hold_passes(loose_f, loose_c, slope, None, press, normals, order, 1.0, 30, 1e9)
    assert loose_c.tobytes() == one_c.tobytes()
    many_f, many_c = f.copy(), np.zeros(f.shape[:2])
    hold_passes(many_f, many_c, slope, None, press, normals, order, 1.0, 30, 1e-6)
    assert not np.array_equal(many_c, one_c)
