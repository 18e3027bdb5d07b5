"""benchmark.world.grip_kernels: the compiled passes of the grip's hold, the bits of the NumPy loop."""

import numpy as np
import pytest

from benchmark.world.grip_kernels import (
    commanded_forces,
    contact_loads,
    correct_feedback,
    finger_torques,
    first_order_response,
    hold_passes,
    running_max,
)


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


def _rng_case(seed, K=5, C=9):
    rng = np.random.default_rng(seed)
    scale = lambda *s: rng.normal(size=s) * 10.0 ** rng.uniform(-2, 1.5, size=s)  # noqa: E731
    R = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    normals = rng.normal(size=(K, 3))
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    return rng, scale, R, normals


@pytest.mark.parametrize("seed", range(4))
def test_contact_loads_are_the_numpy_sums_bits(seed):
    from fsv.linalg import rows_mt, vm

    rng, scale, R, normals = _rng_case(seed)
    fingers = rng.integers(0, 5, size=9)
    signs = rng.choice([-1.0, 1.0], size=9)
    forces, frames = scale(9, 3), np.linalg.qr(rng.normal(size=(9, 3, 3)))[0]
    force = np.zeros((5, 3))
    for k, s, f, fr in zip(fingers, signs, forces, frames):
        force[k] += s * vm(f, fr)
    f_obj = rows_mt(force, R.T)
    want_n = np.einsum("kj,kj->k", f_obj, normals)
    d = f_obj - want_n[:, None] * normals
    want_t = np.sqrt(np.einsum("ni,ni->n", d, d))
    n, t = contact_loads(fingers, signs, forces, frames, R, normals)
    assert n.tobytes() == want_n.tobytes() and t.tobytes() == want_t.tobytes()
    assert np.all(t[np.setdiff1d(np.arange(5), fingers)] == 0.0)
    n0, t0 = contact_loads(np.zeros(0, int), np.zeros(0), np.zeros((0, 3)), np.zeros((0, 3, 3)), R, normals)
    assert not n0.any() and not t0.any()


@pytest.mark.parametrize("seed", range(4))
def test_the_commanded_forces_and_torques_are_the_numpy_products_bits(seed):
    from fsv.linalg import rows_mt, vm

    rng, scale, R, normals = _rng_case(seed)
    forces_obj, feedback, press = scale(5, 3), np.abs(scale(5)), scale(5, 5, 3)
    planned = np.maximum(np.einsum("kd,kd->k", forces_obj, normals), 0.0)
    want = rows_mt(forces_obj + np.einsum("j,jkd->kd", feedback * planned, press), R)
    assert commanded_forces(forces_obj, R, normals, feedback, press).tobytes() == want.tobytes()
    assert commanded_forces(forces_obj, R).tobytes() == rows_mt(forces_obj, R).tobytes()
    jacs = scale(3, 3, 14)
    rows = np.array([(k, a, dof) for a, k in enumerate((0, 2, 4)) for dof in range(4 * a, 4 * a + 4)])
    qfrc = np.full(14, 7.0)
    finger_torques(want, jacs, rows, qfrc)
    for a, k in enumerate((0, 2, 4)):
        dofs = slice(4 * a, 4 * a + 4)
        assert qfrc[dofs].tobytes() == vm(want[k], jacs[a][:, dofs]).tobytes()
    assert np.all(qfrc[12:] == 7.0)  # dofs of no listed digit are left alone


def test_the_feedback_is_the_numpy_updates_bits():
    rng = np.random.default_rng(5)
    active = np.array([True, True, False, True, True])
    deficits, feedback = np.zeros((4, 5)), np.zeros(5)
    want_def, want_fb = deficits.copy(), feedback.copy()
    for tick in range(40):
        n, t = rng.normal(2.0, 2.0, size=5), np.abs(rng.normal(1.0, 1.0, size=5))
        slope = rng.uniform(1.0, 3.0)
        need = np.maximum(slope * t, 1.0)
        short = (need - n) / np.maximum(need, 1.0)
        want_def[tick % 4] = np.where(active & (n > 0), short, 0.0)
        sensed = want_def[(tick + 1) % 4]
        want_fb = np.where(sensed > 0, want_fb + 0.04 * sensed, want_fb * 0.99)
        correct_feedback(n, t, slope, 1.0, active, deficits, tick % 4, (tick + 1) % 4, feedback, 0.04, 0.99)
        assert deficits.tobytes() == want_def.tobytes() and feedback.tobytes() == want_fb.tobytes()
    assert feedback.max() > 0.05 and np.all(deficits[:, 2] == 0.0)


def test_the_response_is_the_numpy_loops_bits():
    rng = np.random.default_rng(6)
    target = np.abs(rng.normal(size=(300, 4))) * 5.0
    want, filtered = np.zeros_like(target), np.zeros_like(target)
    g = np.zeros(4)
    for i in range(300):
        g = 0.9 * g + (1 - 0.9) * target[i]
        want[i] = g
    first_order_response(target, filtered, 0, 0.9)
    assert filtered.tobytes() == want.tobytes()
    filtered[150:] = -1.0  # a restart from tick 150 continues from the tick before
    first_order_response(target, filtered, 150, 0.9)
    assert filtered.tobytes() == want.tobytes()


def _shifted_max(x, half):
    """The running maximum over the shifts 1..half, each first from after, then from before, each
    step keeping the running value where it is NaN or not below the other (NaN wins, and of two equal
    values the running one: -0.0 stays against +0.0, where np.maximum would give +0.0)."""
    peak = x.copy()

    def keep(a, b):
        return np.where(np.isnan(a) | (a >= b), a, b)

    for shift in range(1, min(half, len(x) - 1) + 1):
        peak[:-shift] = keep(peak[:-shift], x[shift:])
        peak[shift:] = keep(peak[shift:], x[:len(x) - shift])
    return peak


@pytest.mark.parametrize("N, half", [(1, 3), (2, 1), (7, 3), (7, 9), (300, 1), (300, 12), (2500, 125)])
def test_the_running_maximum_is_the_shifted_loops_bits_with_ties_nans_and_signed_zeros(N, half):
    """Columns of plain values, of many ties (values on a coarse grid), with -0.0 beside +0.0, with a
    NaN, and with both: each column's bits are the shifted loop's (the queue takes the plain and the
    tied columns; which zero or NaN a window keeps depends on the order, which the loop keeps)."""
    rng = np.random.default_rng(N + half)
    plain = np.abs(rng.normal(size=N)) * 3.0
    ties = np.round(rng.uniform(0, 3, size=N))
    zeros = np.array([-0.0, 0.0, 0.0, 1.0])[rng.integers(0, 4, size=N)]
    nan = plain.copy()
    nan[N // 2] = np.nan
    both = zeros.copy()
    both[N // 3] = np.nan
    x = np.stack([plain, ties, zeros, nan, both, -plain], axis=1)
    assert N < 7 or np.signbit(zeros[zeros == 0]).any()
    got = running_max(x, half)
    assert got.tobytes() == _shifted_max(x, half).tobytes()
    i = N // 2
    assert got[i, 0] == plain[max(0, i - half):i + half + 1].max() and np.isnan(got[i, 3])
