"""Human movement speeds: the ranges a task plan draws its motions from, and a plan builder.

A task plan is a sequence of minimum-jerk movements and holds. Each movement's duration follows
from a peak acceleration drawn per trial from a range of natural manipulation: a minimum-jerk
movement over a distance D in a time T peaks at ``MIN_JERK_PEAK_ACC * D / T**2`` (and at
``MIN_JERK_PEAK_VEL * D / T`` in velocity), so ``T = sqrt(MIN_JERK_PEAK_ACC * D / a)``.

Ranges and their sources (the literature reports them for unloaded reaches and for transports of
hand-held objects of a few hundred grams; we use the part of each range a deliberate manipulation
of our box covers):

* ``TRANSPORT_PEAK_ACC`` 2.5-6 m/s^2: point-to-point arm movements of 10-40 cm at natural speed
  last 0.4-1 s with bell-shaped speed profiles peaking at 0.5-1.5 m/s (Flash & Hogan 1985,
  J. Neurosci. 5(7)); vertical transports of a held object reach peak accelerations of several
  m/s^2 (Flanagan & Wing 1993, Exp. Brain Res. 95; Flanagan & Wing 1997, J. Neurosci. 17(4)).
* ``ROTATION_PEAK_ALPHA`` 8-20 rad/s^2: chosen (we found no single source for turning a held
  box), so that turns of 0.3-0.6 rad take 0.3-0.6 s with peak angular velocities of 2-4 rad/s, the
  time scale of the transports above.
* ``DWELL_S`` 0.2-0.6 s: chosen; the sub-movements of a manipulation are separated by brief
  holds (Johansson et al. 2001, J. Neurosci. 21(17), on the phases of object manipulation).
* ``SHAKE_FREQUENCY_HZ`` 1-2 Hz and ``SHAKE_PEAK_ACC`` 2.5-5 m/s^2: cyclic vertical arm movements
  with a hand-held load, the load force changing by tens of percent of the weight (Flanagan &
  Wing 1995, Exp. Brain Res. 105, "The stability of precision grip forces during cyclic arm
  movements with a hand-held load").
* The set-down (:meth:`Plan.set_down`): people put an object down gently. Movements that end in
  placing an object lengthen their deceleration (Marteniuk, MacKenzie, Jeannerod, Athenes & Dugas
  1987, Can. J. Psychol. 41(3), "Constraints on human arm movement trajectories": placing a disk
  into a tight well against throwing it), and the contact with the support is a sensed event that
  ends the replacement phase before the unloading (Johansson & Westling 1984, Exp. Brain Res. 56;
  Johansson & Flanagan 2009, Nat. Rev. Neurosci. 10; here the unloading keeps its planned time,
  after the approach). The plan lowers the box at human speed to :data:`APPROACH_HEIGHT_M` above
  the table, then approaches at a constant speed drawn from ``APPROACH_SPEED`` 2-3 cm/s (chosen:
  we found no source for a touchdown speed; an order of magnitude below the transports' peaks, so
  that a box stopped by the table within one 30 Hz frame decelerates at most 0.6-0.9 m/s^2, below
  the transports' accelerations) until it is :data:`PRESS_M` into the table. The constant speed
  makes the touchdown speed the same wherever in that band the box meets the table.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fsv.linalg import norm

MIN_JERK_PEAK_ACC = 10.0 / np.sqrt(3.0)
"""Peak of |d2p/ds2| of the minimum-jerk profile 10 s^3 - 15 s^4 + 6 s^5 (at s = 1/2 -+ sqrt(3)/6)."""
MIN_JERK_PEAK_VEL = 1.875
"""Peak of dp/ds of the minimum-jerk profile (at s = 1/2)."""


@dataclass(frozen=True)
class Range:
    """A range of a human movement parameter, drawn uniformly per trial.

    Attributes:
        lo: Lower end.
        hi: Upper end.
        unit: Its unit.
    """

    lo: float
    hi: float
    unit: str

    def draw(self, rng: np.random.Generator) -> float:
        """One uniform draw in [lo, hi] from the scenario's generator."""
        return float(self.lo + (self.hi - self.lo) * rng.uniform())


TRANSPORT_PEAK_ACC = Range(2.5, 6.0, "m/s^2")
ROTATION_PEAK_ALPHA = Range(8.0, 20.0, "rad/s^2")
DWELL_S = Range(0.2, 0.6, "s")
SHAKE_FREQUENCY_HZ = Range(1.0, 2.0, "Hz")
SHAKE_PEAK_ACC = Range(2.5, 5.0, "m/s^2")

APPROACH_SPEED = Range(0.02, 0.03, "m/s")
"""The set-down's guarded approach speed, drawn per trial (see the module's notes)."""
APPROACH_HEIGHT_M = 0.025
"""The set-down's guarded approach starts with the plan's box this far above its place on the table,
[m] (a choice: the slow band covers where the box can meet the table: the box hangs about a
millimetre below the plan under the person's grip and lags it by about 20 ms, and a carry can turn
it in the grasp: 15 degrees about its short axis lower an end of its 171 mm length by 85.5 mm x sin
15 degrees = 22 mm; smoke's `place`, so turned, met the table with the plan 19 mm above its end)."""
APPROACH_RAMP_S = 0.1
"""An approach reaches and leaves its speed along minimum-jerk ramps this long, [s] (a choice: at
2-3 cm/s the ramps peak at 0.4-0.6 m/s^2, below the transports' accelerations)."""
APPROACH_HURRIED_M_S = 0.06
"""An episode too short for its plan at human speed speeds up its set-down's approach up to this,
[m/s], before it hurries the other movements (a choice: twice the drawn range's top, still an
order of magnitude below the transports' speeds; a person in a hurry feels for the table faster
rather than jerk the box about)."""
PRESS_M = 0.002
"""The set-down ends this far below the box's place on the table, [m]: the hand's compliance presses
the box on."""

MIN_MOVE_S = 0.25
"""No movement is planned shorter than this, [s] (a tiny displacement does not make a twitch)."""
MIN_DWELL_S = 0.1
"""A plan too long for its episode first shortens its holds down to this, [s], then leaves out
optional movements (it moves faster than planned only when its required movements do not fit)."""


def move_duration(distance: float, peak: float) -> float:
    """Duration of a minimum-jerk movement over ``distance`` (m or rad) peaking at ``peak``
    (m/s^2 or rad/s^2), [s]; at least :data:`MIN_MOVE_S`."""
    return max(MIN_MOVE_S, float(np.sqrt(MIN_JERK_PEAK_ACC * abs(distance) / peak)))


class Plan:
    """Builds a task's keyframes as movements and holds, from the box's start pose.

    Args:
        rng: The scenario's "task" generator (every duration is drawn from it).
    """

    def __init__(self, rng: np.random.Generator):
        self.rng = rng
        self.way = [(np.zeros(3), np.zeros(3))]
        self.durations = []
        self.optional = []
        self.moves = []
        self.ramps = []
        self.shortest = []

    @property
    def pose(self) -> tuple[np.ndarray, np.ndarray]:
        """The displacement and rotation vector the plan has reached."""
        return self.way[-1]

    def move(self, displacement, rotation=None, *, duration: float | None = None, optional: bool = False) -> "Plan":
        """A minimum-jerk movement to ``displacement`` (3,) [m] and ``rotation`` (3,) [rad] (box
        start frame), lasting ``duration`` [s] if given, else the longer of the translation's and
        the rotation's durations at peaks drawn from :data:`TRANSPORT_PEAK_ACC` and
        :data:`ROTATION_PEAK_ALPHA`. An ``optional`` movement is left out of a short episode
        that has no time for it."""
        d0, r0 = self.pose
        d1 = np.asarray(displacement, float)
        r1 = r0 if rotation is None else np.asarray(rotation, float)
        if duration is None:
            a, alpha = TRANSPORT_PEAK_ACC.draw(self.rng), ROTATION_PEAK_ALPHA.draw(self.rng)
            T = max(move_duration(norm(d1 - d0), a), move_duration(norm(r1 - r0), alpha))
        else:
            T = float(duration)
        self.way.append((d1, r1))
        self.durations.append(T)
        self.optional.append(bool(optional))
        self.moves.append(True)
        self.ramps.append(0.0)
        self.shortest.append(T)
        return self

    def approach(self, displacement, speed: float, ramp_s: float = APPROACH_RAMP_S) -> "Plan":
        """A guarded approach: a straight movement to ``displacement`` (3,) [m] (box start frame,
        the rotation kept) at the constant ``speed`` [m/s], which it reaches and leaves along
        minimum-jerk ramps of ``ramp_s`` [s] (:func:`benchmark.world.tasks.motion.cruise`).
        Its duration is distance / speed + ramp_s (shorter only in an episode too short for its
        plan: :meth:`keyframes`, :data:`APPROACH_HURRIED_M_S`)."""
        if not speed > 0 or not ramp_s > 0:
            raise ValueError(f"an approach needs a positive speed and ramp, got {speed} m/s, {ramp_s} s")
        d0, r0 = self.pose
        d1 = np.asarray(displacement, float)
        self.way.append((d1, r0))
        distance = norm(d1 - d0)
        self.durations.append(distance / speed + ramp_s)
        self.optional.append(False)
        self.moves.append(True)
        self.ramps.append(float(ramp_s))
        self.shortest.append(distance / max(speed, APPROACH_HURRIED_M_S) + ramp_s)
        return self

    def set_down(self, place) -> "Plan":
        """Puts the box down at ``place`` (3,) [m] (box start frame; its z the table's, 0): a
        movement at human speed (:meth:`move`) to :data:`APPROACH_HEIGHT_M` above it, then a guarded
        :meth:`approach` at a speed drawn from :data:`APPROACH_SPEED` to :data:`PRESS_M` below it."""
        place = np.asarray(place, float)
        self.move(place + [0.0, 0.0, APPROACH_HEIGHT_M])
        return self.approach(place - [0.0, 0.0, PRESS_M], APPROACH_SPEED.draw(self.rng))

    def hold(self, seconds: float | None = None) -> "Plan":
        """Stays still for ``seconds`` (default: a dwell drawn from :data:`DWELL_S`)."""
        self.way.append(self.pose)
        self.durations.append(DWELL_S.draw(self.rng) if seconds is None else float(seconds))
        self.optional.append(False)
        self.moves.append(False)
        self.ramps.append(0.0)
        self.shortest.append(0.0)
        return self

    def keyframes(self, t0: float, t1: float) -> list:
        """The keyframes from ``t0``, the last pose held until ``t1``. A plan longer than the
        window [t0, t1] first shortens its holds (down to :data:`MIN_DWELL_S`), then leaves out
        its optional movements from the last one back (each with the hold after it), then speeds
        up its guarded approaches (:meth:`approach`, up to :data:`APPROACH_HURRIED_M_S`); only if
        the required movements alone do not fit do they all speed up to fit, in proportion.

        Returns:
            ``(t, displacement, rotation vector)`` keyframes for :class:`~benchmark.world.tasks.motion.Motion`,
            ``(t, displacement, rotation vector, ramp_s)`` for one that ends an approach.
        """
        way, optional, moves, ramps = list(self.way), list(self.optional), list(self.moves), list(self.ramps)
        shortest = list(self.shortest)
        window = t1 - t0
        d = np.asarray(self.durations, float)
        if d.sum() > window:  # shorten the holds
            excess = d.sum() - window
            room = np.where(moves, 0.0, np.maximum(d - MIN_DWELL_S, 0.0))
            if room.sum() > 0:
                d = d - room * min(1.0, excess / room.sum())
        d = list(d)
        while sum(d) > window + 1e-12 and any(optional):
            i = len(optional) - 1 - optional[::-1].index(True)  # the last optional segment
            drop = [i]
            if i + 1 < len(d) and not moves[i + 1]:
                drop.append(i + 1)  # and the hold after it
            for j in reversed(drop):
                del way[j + 1], d[j], optional[j], moves[j], ramps[j], shortest[j]
        room = [x - s if r > 0 else 0.0 for x, s, r in zip(d, shortest, ramps)]
        if sum(d) > window and sum(room) > 0:  # the approaches hurry first
            cut = min(1.0, (sum(d) - window) / sum(room))
            d = [x - q * cut for x, q in zip(d, room)]
        if sum(d) > window:  # only in an episode too short for the required movements: faster
            d = [x * window / sum(d) for x in d]
        times = t0 + np.concatenate([[0.0], np.cumsum(d)])
        frames = []
        for i, (t, (dd, rr)) in enumerate(zip(times, way)):
            frame = (float(t), np.asarray(dd, float), np.asarray(rr, float))
            frames.append(frame + (ramps[i - 1],) if i > 0 and ramps[i - 1] > 0 else frame)
        return frames
