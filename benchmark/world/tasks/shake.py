"""shake: lift the box, then move it up and down at 1-2 Hz (Flanagan & Wing 1995), then hold.

The vertical oscillation changes the load force by tens of percent of the weight (peak
accelerations of 2.5-5 m/s^2 against g = 9.81 m/s^2), the condition in which a person's grip force
follows the load force in phase. Each half cycle is a minimum-jerk stroke between the two
extremes (close to a sinusoid: its peak acceleration is 46 A f^2 against 39.5 A f^2 for a sine of
amplitude A and frequency f).
"""

from __future__ import annotations

import numpy as np

from benchmark.world.tasks.human import MIN_JERK_PEAK_ACC, SHAKE_FREQUENCY_HZ, SHAKE_PEAK_ACC, Plan
from benchmark.world.tasks.motion import Phases
from benchmark.world.tasks.task import Task

CENTRE_M = 0.16
"""Height of the oscillation's centre above the start, [m]."""
OSCILLATION_S = 4.0
"""Length of the oscillation (whole cycles), [s]."""


def keyframes(phases: Phases, rng: np.random.Generator) -> list:
    """Lift to 16 cm, oscillate +-A for ~4 s (f, peak acceleration drawn per trial), back to centre, hold."""
    f = SHAKE_FREQUENCY_HZ.draw(rng)
    a = SHAKE_PEAK_ACC.draw(rng)
    half = 0.5 / f
    amp = a * half**2 / (MIN_JERK_PEAK_ACC * 2.0)  # a stroke of 2 A in half a period peaks at a
    centre = np.array([0.0, 0.0, CENTRE_M])
    plan = Plan(rng).move(centre).hold()
    plan.move(centre + [0, 0, amp], duration=half / 2**0.5)  # half the distance: the same peak
    for i in range(max(2, int(round(OSCILLATION_S * f)) * 2)):
        plan.move(centre + [0, 0, amp if i % 2 else -amp], duration=half, optional=True)
    plan.move(centre, duration=half / 2**0.5, optional=True)
    return plan.keyframes(phases.load_end, phases.move_end)


TASK = Task(name="shake", description="lift, then move up and down at 1-2 Hz, then hold", default_duration_s=10.0,
            lifts=True, releases=False, keyframes=keyframes, min_duration_s=3.0)
