"""excite-tx ... excite-rz: six-axis excitation motions (the paper's section 4.1).

Each lifts the box and then moves it back and forth along one world axis (translations tx, ty,
tz) or turns it back and forth about one axis (rotations rx, ry, rz), so that one coordinate of
the translational acceleration or of the rotational velocity dominates, as in the paper's
comparison of vision-based kinematics with the AHRS.
"""

from __future__ import annotations

import functools

import numpy as np

from benchmark.world.tasks.motion import Phases, timed
from benchmark.world.tasks.task import Task

AMPLITUDE_M = 0.04
AMPLITUDE_RAD = 0.3
HALF_PERIOD_S = 0.5


def keyframes(axis: int, rotation: bool, phases: Phases, rng: np.random.Generator) -> list:
    """Lift 14 cm, then as many back-and-forth strokes of ~0.5 s as fit, back to centre, hold."""
    zero = np.zeros(3)
    up = np.array([0.0, 0.0, 0.14])
    t0, t1 = phases.load_end, phases.move_end
    lift_s = max(0.6, 0.15 * (t1 - t0))
    strokes = max(2, int((t1 - t0 - lift_s - 0.3) / HALF_PERIOD_S) - 1)
    amp = (AMPLITUDE_RAD if rotation else AMPLITUDE_M) * (1.0 + 0.15 * rng.uniform(-1, 1))
    e = np.eye(3)[axis]
    way, weights = [(zero, zero), (up, zero)], [lift_s]
    sign = 1.0
    for i in range(strokes):
        off = amp * sign * e * (0.5 if i == 0 else 1.0)
        way.append((up, off) if rotation else (up + off, zero))
        weights.append(HALF_PERIOD_S * (0.5 if i == 0 else 1.0))
        sign = -sign
    way += [(up, zero), (up, zero)]
    weights += [HALF_PERIOD_S * 0.5, 0.3]
    return timed(t0, t1, way, weights)


TASKS = [
    Task(name=f"excite-{kind}{'xyz'[axis]}",
         description=f"lift, then {'turn' if kind == 'r' else 'move'} back and forth {'about' if kind == 'r' else 'along'} "
                     f"the {'xyz'[axis]} axis",
         default_duration_s=10.0, lifts=True, releases=False,
         keyframes=functools.partial(keyframes, axis, kind == "r"))
    for kind in ("t", "r") for axis in range(3)
]
