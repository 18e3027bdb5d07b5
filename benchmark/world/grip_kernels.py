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

import numpy as np

from fsv.jit import kernel


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


@kernel
def _maximum(a, b):  # pragma: no cover - compiled
    # np.maximum of two scalars: NaN if either is NaN, else the larger; of two equal values the first
    # (-0.0 against +0.0 too, where np.maximum gives +0.0)
    if a != a or a >= b:
        return a
    return b


@kernel
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


def first_order_response(target: np.ndarray, filtered: np.ndarray, start: int, keep: float) -> None:
    """The grip's first-order response to its target from tick ``start`` on, in place:
    ``filtered[i] = keep filtered[i - 1] + (1 - keep) target[i]``, from rest before tick 0.

    Args:
        target: The grip's target per tick, (N, K) [N].
        filtered: The response, (N, K) [N], float64, C-contiguous: rows ``start:`` are written.
        start: The first tick written.
        keep: The fraction of the response kept from one tick to the next, exp(-dt / tau).
    """
    _first_order(np.ascontiguousarray(target, dtype=np.float64), filtered, int(start), float(keep))


def running_max(x: np.ndarray, half: int) -> np.ndarray:
    """The largest of ``x`` within ``half`` rows before or after each row, (N, K) -> (N, K), as the
    shifts 1..``half`` find it (each first from after, then from before; a NaN wins, and of two
    equal values the one found first).

    A column without NaN and without -0.0 takes a monotonic queue, one pass over its rows (there the
    largest value of a window is one number, whichever order finds it: 21 times faster on a
    simulation's loads, half = 125); a column with either takes the shifts themselves, as their order
    then decides which NaN or which zero is kept."""
    return _running_max(np.ascontiguousarray(x, dtype=np.float64), int(half))


@kernel
def _first_order(target, filtered, start, keep):  # pragma: no cover - compiled
    K = target.shape[1]
    gain = 1 - keep
    for k in range(K):
        g = filtered[start - 1, k] if start > 0 else 0.0
        for i in range(start, target.shape[0]):
            g = keep * g + gain * target[i, k]
            filtered[i, k] = g


@kernel
def _running_max(x, half):  # pragma: no cover - compiled
    N, K = x.shape
    peak = np.empty_like(x)
    queue = np.empty(N, np.int64)  # rows whose values fall from the front to the back
    for k in range(K):
        plain = True
        for i in range(N):
            v = x[i, k]
            if v != v or (v == 0.0 and math.copysign(1.0, v) < 0.0):
                plain = False
                break
        if not plain:  # _maximum over the shifts in their order, each first from after, then from before
            for i in range(N):
                peak[i, k] = x[i, k]
            for shift in range(1, half + 1):
                for i in range(N - shift):
                    peak[i, k] = _maximum(peak[i, k], x[i + shift, k])
                for i in range(shift, N):
                    peak[i, k] = _maximum(peak[i, k], x[i - shift, k])
            continue
        head, tail = 0, 0
        for j in range(N + half):  # row j enters the window of row j - half
            if j < N:
                while tail > head and x[queue[tail - 1], k] <= x[j, k]:
                    tail -= 1
                queue[tail] = j
                tail += 1
            i = j - half
            if i >= 0:
                while queue[head] < i - half:
                    head += 1
                peak[i, k] = x[queue[head], k]
    return peak


def contact_loads(fingers: np.ndarray, signs: np.ndarray, forces: np.ndarray, frames: np.ndarray,
                  box_rot: np.ndarray, normals_obj: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each digit's normal and tangential force on the box from its contacts' forces.

    Args:
        fingers: The digit of each contact, (C,) int.
        signs: +1 where the contact's force acts on the box, -1 where on the digit, (C,).
        forces: Each contact's force in its contact frame, (C, 3) [N].
        frames: Each contact's frame, rows its axes in the world frame, (C, 3, 3).
        box_rot: The box's rotation, object to world, (3, 3).
        normals_obj: The digits' planned normals into the box, object frame, (K, 3).

    Returns:
        ``(n, t)``: each digit's summed force along its normal and the norm of the rest, (K,) each [N].
    """
    return _contact_loads(np.ascontiguousarray(fingers, dtype=np.int64), np.ascontiguousarray(signs, dtype=np.float64),
                          np.ascontiguousarray(forces, dtype=np.float64), np.ascontiguousarray(frames, dtype=np.float64),
                          np.ascontiguousarray(box_rot, dtype=np.float64), np.ascontiguousarray(normals_obj, dtype=np.float64))


def commanded_forces(forces_obj: np.ndarray, box_rot: np.ndarray, normals_obj: np.ndarray | None = None,
                     feedback: np.ndarray | None = None, press: np.ndarray | None = None) -> np.ndarray:
    """The fingertip forces of a control tick in the world frame, (K, 3) [N]: the planned forces
    (object frame), each digit raised by its feedback times its planned normal force along the
    digits' unit presses where ``feedback`` is given, rotated by the box's rotation.

    Args:
        forces_obj: The tick's planned forces, object frame, (K, 3) [N].
        box_rot: The box's rotation, object to world, (3, 3).
        normals_obj: The digits' normals into the box, (K, 3); with ``feedback`` and ``press``.
        feedback: Each digit's raise as a fraction of its planned normal force, (K,).
        press: Unit presses per digit, (K, K, 3).
    """
    K = len(forces_obj)
    raised = feedback is not None
    return _commanded_forces(np.ascontiguousarray(forces_obj, dtype=np.float64), np.ascontiguousarray(box_rot, dtype=np.float64),
                             np.ascontiguousarray(normals_obj if raised else np.zeros((K, 3)), dtype=np.float64),
                             np.ascontiguousarray(feedback if raised else np.zeros(K), dtype=np.float64),
                             np.ascontiguousarray(press if raised else np.zeros((K, K, 3)), dtype=np.float64), raised)


def finger_torques(forces: np.ndarray, jacobians: np.ndarray, rows: np.ndarray, qfrc: np.ndarray) -> None:
    """The joint torques tau = J^T f of the fingertip forces, written into ``qfrc``.

    Args:
        forces: The fingertip forces, world frame, (K, 3) [N].
        jacobians: Each listed digit's fingertip translation Jacobian, (A, 3, nv).
        rows: ``(digit, jacobian index, dof)`` per torque written, (R, 3) int.
        qfrc: The applied generalised forces, (nv,) [N m]: the rows' dofs are written.
    """
    _finger_torques(forces, jacobians, rows, qfrc)


@kernel
def _contact_loads(fingers, signs, forces, frames, box_rot, normals):  # pragma: no cover - compiled
    K = normals.shape[0]
    force = np.zeros((K, 3))
    for c in range(fingers.shape[0]):
        k = fingers[c]
        for m in range(3):  # vm(f, frame): ((0 + f0 F0m) + f1 F1m) + f2 F2m
            v = ((0.0 + forces[c, 0] * frames[c, 0, m]) + forces[c, 1] * frames[c, 1, m]) + forces[c, 2] * frames[c, 2, m]
            force[k, m] += signs[c] * v
    n = np.empty(K)
    t = np.empty(K)
    for k in range(K):
        f = np.empty(3)
        for m in range(3):  # rows_mt(force, box_rot.T), the transpose a strided view: in order
            f[m] = ((0.0 + force[k, 0] * box_rot[0, m]) + force[k, 1] * box_rot[1, m]) + force[k, 2] * box_rot[2, m]
        u0, u1, u2 = normals[k, 0], normals[k, 1], normals[k, 2]
        nk = (f[0] * u0 + f[2] * u2) + f[1] * u1  # einsum over a contiguous axis of three
        d0, d1, d2 = f[0] - nk * u0, f[1] - nk * u1, f[2] - nk * u2
        n[k] = nk
        t[k] = math.sqrt((d0 * d0 + d2 * d2) + d1 * d1)
    return n, t


@kernel
def _commanded_forces(forces_obj, box_rot, normals, feedback, press, raised):  # pragma: no cover - compiled
    K = forces_obj.shape[0]
    f_obj = forces_obj.copy()
    if raised:
        w = np.empty(K)
        for j in range(K):
            planned = (forces_obj[j, 0] * normals[j, 0] + forces_obj[j, 2] * normals[j, 2]) + forces_obj[j, 1] * normals[j, 1]
            w[j] = feedback[j] * _maximum(planned, 0.0)
        for k in range(K):
            for d in range(3):  # einsum("j,jkd->kd"): in order of j
                s = 0.0
                for j in range(K):
                    s = s + w[j] * press[j, k, d]
                f_obj[k, d] = forces_obj[k, d] + s
    out = np.empty((K, 3))
    for k in range(K):
        for m in range(3):  # rows_mt(f_obj, box_rot), both contiguous: the first and third, then the second
            out[k, m] = (f_obj[k, 0] * box_rot[m, 0] + f_obj[k, 2] * box_rot[m, 2]) + f_obj[k, 1] * box_rot[m, 1]
    return out


@kernel
def _finger_torques(forces, jacobians, rows, qfrc):  # pragma: no cover - compiled
    for r in range(rows.shape[0]):
        k, a, dof = rows[r, 0], rows[r, 1], rows[r, 2]
        # vm(f[k], jac[:, dofs]): ((0 + f0 J0) + f1 J1) + f2 J2
        qfrc[dof] = ((0.0 + forces[k, 0] * jacobians[a, 0, dof]) + forces[k, 1] * jacobians[a, 1, dof]) + forces[k, 2] * jacobians[a, 2, dof]


def correct_feedback(n: np.ndarray, t: np.ndarray, slope: float, min_force_n: float, active: np.ndarray,
                     deficits: np.ndarray, write: int, read: int, feedback: np.ndarray, gain: float, leak: float) -> None:
    """One tick of the digits' tactile feedback on their grip-load ratios, in place.

    Each digit's relative shortfall, ``(need - n) / max(need, min_force_n)`` with ``need = max(slope
    t, min_force_n)`` (0 for a digit off the box or not touching it), is written into row ``write``
    of the delay line ``deficits``; the shortfall sensed, row ``read``, raises the feedback by
    ``gain`` times itself where positive, else the feedback decays by ``leak``.

    Args:
        n: Each digit's normal force now, (K,) [N].
        t: Each digit's tangential force now, (K,) [N].
        slope: The tick's normal force per newton of tangential load.
        min_force_n: Every digit's least normal force, [N].
        active: The digits of the grasp, (K,) bool.
        deficits: The delay line, (D, K): row ``write`` is written.
        write: The row written.
        read: The row sensed (after the write).
        feedback: Each digit's raise, (K,): updated.
        gain: The raise per unit of shortfall and tick.
        leak: The factor a met digit's raise decays by per tick.
    """
    _correct_feedback(n, t, float(slope), float(min_force_n), np.ascontiguousarray(active, dtype=np.bool_), deficits,
                      int(write), int(read), feedback, float(gain), float(leak))


@kernel
def _correct_feedback(n, t, slope, min_force, active, deficits, write, read, feedback, gain, leak):  # pragma: no cover - compiled
    K = n.shape[0]
    for k in range(K):
        need = _maximum(slope * t[k], min_force)
        short = (need - n[k]) / _maximum(need, min_force)
        deficits[write, k] = short if (active[k] and n[k] > 0) else 0.0
    for k in range(K):
        sensed = deficits[read, k]
        feedback[k] = feedback[k] + gain * sensed if sensed > 0 else feedback[k] * leak
