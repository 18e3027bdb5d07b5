"""Minimum-jerk motions of the box and the phases of a prehension (reach, grasp, load, move, release).

A task describes what happens to the box as keyframes (time, displacement, rotation) relative to
its start pose; :class:`Motion` interpolates them with minimum-jerk profiles (Flash & Hogan 1985),
so positions, velocities and accelerations are smooth and known in closed form; a keyframe may
instead end a constant-speed segment with smooth ramps (:func:`cruise`: the guarded final approach
of a set-down, :meth:`benchmark.world.tasks.human.Plan.approach`). The hand follows the box's
planned pose with the grasp's palm offset.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fsv.linalg import mm, norm
from fsv.rotation import axis_angle_to_rot, log_so3


def min_jerk(s: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The minimum-jerk profile 10 s^3 - 15 s^4 + 6 s^5 and its first two derivatives in s.

    Args:
        s: Normalised time, any shape; clipped to [0, 1].

    Returns:
        ``(p, dp/ds, d2p/ds2)``, each shaped like ``s``.
    """
    s = np.clip(s, 0.0, 1.0)
    return (10 * s**3 - 15 * s**4 + 6 * s**5, 30 * s**2 - 60 * s**3 + 30 * s**4, 60 * s - 180 * s**2 + 120 * s**3)


def cruise(s: np.ndarray, ramp: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A constant-speed profile with smooth ramps and its first two derivatives in s: the speed
    rises along the minimum-jerk step 10 x^3 - 15 x^4 + 6 x^5 over the first ``ramp`` of the
    segment, stays constant, and falls the same way over the last ``ramp``.

    Args:
        s: Normalised time, any shape; clipped to [0, 1].
        ramp: Each ramp's share of the segment, in (0, 1/2].

    Returns:
        ``(p, dp/ds, d2p/ds2)``, each shaped like ``s``; p runs from 0 to 1, and dp/ds is
        1 / (1 - ramp) between the ramps.
    """
    if not 0.0 < ramp <= 0.5:
        raise ValueError(f"ramp must be in (0, 1/2], got {ramp}")
    s = np.clip(s, 0.0, 1.0)
    c = 1.0 / (1.0 - ramp)  # the ramps cover half their length each: p(1) = c (1 - 2 ramp + ramp) = 1
    up = np.clip(s / ramp, 0.0, 1.0)
    down = np.clip((1.0 - s) / ramp, 0.0, 1.0)
    p = np.where(s < ramp, ramp * _ramp_integral(up),
                 np.where(s > 1.0 - ramp, 1.0 - ramp - ramp * _ramp_integral(down), s - 0.5 * ramp))
    step_up, rate_up = _step(up)
    step_down, rate_down = _step(down)
    dp = np.where(s < ramp, step_up, np.where(s > 1.0 - ramp, step_down, 1.0))
    ddp = np.where(s < ramp, rate_up / ramp, np.where(s > 1.0 - ramp, -rate_down / ramp, 0.0))
    return c * p, c * dp, c * ddp


def _step(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The minimum-jerk step 10 x^3 - 15 x^4 + 6 x^5 and its derivative."""
    return 10 * x**3 - 15 * x**4 + 6 * x**5, 30 * x**2 - 60 * x**3 + 30 * x**4


def _ramp_integral(x: np.ndarray) -> np.ndarray:
    """The integral of the minimum-jerk step from 0 to x: 5/2 x^4 - 3 x^5 + x^6 (1/2 at x = 1)."""
    return 2.5 * x**4 - 3 * x**5 + x**6


MIN_GRIP_COMPRESSION = 0.6
"""Short episodes compress the closing and loading phases by at most this factor (the others by
duration / 8 s)."""


@dataclass(frozen=True)
class Phases:
    """Times in [s] that split an episode into the phases of a prehension.

    Attributes:
        reach_end: The palm arrives at the grasp pose (fingers pre-shaped, open).
        close_end: The fingers have closed on the spots; the grip has reached its baseline.
        load_end: The load has moved from the table to the hand; the manipulation starts.
        move_end: The manipulation (the task's keyframes) is over.
        unload_end: After a put-down, the load has gone back to the table (== move_end if the
            hand keeps the box).
        open_end: The fingers have let go (== unload_end if the hand keeps the box).
        duration: End of the episode.
    """

    reach_end: float
    close_end: float
    load_end: float
    move_end: float
    unload_end: float
    open_end: float
    duration: float

    @staticmethod
    def for_duration(duration: float, releases: bool) -> "Phases":
        """Human-like phase lengths, compressed proportionally for short episodes (closing and
        loading by at most :data:`MIN_GRIP_COMPRESSION`)."""
        k = min(1.0, duration / 8.0)
        k_grip = max(k, MIN_GRIP_COMPRESSION)  # the grip needs time to build before a human-speed lift
        reach, close, load = 0.8 * k, 0.35 * k_grip, 0.3 * k_grip
        unload, open_ = (0.3 * k, 0.3 * k) if releases else (0.0, 0.0)
        tail = 0.25 * k if releases else 0.0
        move_end = duration - unload - open_ - tail
        return Phases(reach_end=reach, close_end=reach + close, load_end=reach + close + load, move_end=move_end,
                      unload_end=move_end + unload, open_end=move_end + unload + open_, duration=duration)


class Motion:
    """Piecewise minimum-jerk motion of the box through keyframes, world frame.

    Keyframe i is ``(t_i, d_i, r_i)``: at time t_i the box centre is at ``start_pos + d_i`` and its
    orientation is ``exp(r_i) @ start_rot`` (r_i a rotation vector in the world frame). Between
    keyframes the displacement and the relative rotation (about a fixed axis) follow minimum-jerk
    profiles; before the first and after the last keyframe the box rests. A keyframe with a fourth
    element ``ramp_s`` ends a constant-speed segment instead (:func:`cruise`), whose speed rises and
    falls over ``ramp_s`` [s] at its ends.

    Args:
        start_pos: Box centre at rest, (3,), [m].
        start_rot: Box orientation at rest, (3, 3).
        keyframes: List of ``(t, displacement (3,), rotation vector (3,))`` or ``(t, displacement,
            rotation vector, ramp_s)``, times increasing.
    """

    def __init__(self, start_pos: np.ndarray, start_rot: np.ndarray, keyframes: list):
        self.start_pos = np.asarray(start_pos, dtype=float)
        self.start_rot = np.asarray(start_rot, dtype=float)
        self.t = np.array([k[0] for k in keyframes], dtype=float)
        if np.any(np.diff(self.t) <= 0):
            raise ValueError(f"keyframe times must increase, got {self.t}")
        self.d = np.array([k[1] for k in keyframes], dtype=float).reshape(-1, 3)
        self.R = [mm(axis_angle_to_rot(_unit(k[2]), norm(k[2])), self.start_rot) for k in keyframes]
        # each segment's ramp share (0: minimum jerk), from the keyframe that ends it
        self.ramp = np.zeros(max(len(keyframes) - 1, 0))
        for i, k in enumerate(keyframes[1:]):
            if len(k) > 3:
                self.ramp[i] = min(0.5, float(k[3]) / (self.t[i + 1] - self.t[i]))
        # Relative rotation of each segment as axis * angle, world frame.
        self.seg_axis, self.seg_angle = [], []
        for a, b in zip(self.R[:-1], self.R[1:]):
            w = log_so3(mm(b, a.T))
            angle = norm(w)
            axis = w / angle if angle > 0 else np.array([1.0, 0.0, 0.0])
            self.seg_axis.append(axis)
            self.seg_angle.append(angle)

    def __call__(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The planned box state at time t: :meth:`evaluate` of one time."""
        return tuple(v[0] for v in self.evaluate(np.array([float(t)])))

    def evaluate(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The planned box state at many times.

        Args:
            t: Times, (N,), [s].

        Returns:
            ``(pos (N, 3), rot (N, 3, 3), vel (N, 3), acc (N, 3), omega (N, 3), alpha (N, 3))``,
            world frame, SI units.
        """
        t = np.asarray(t, dtype=float)
        N = t.shape[0]
        pos = np.tile(self.start_pos, (N, 1))
        rot = np.tile(self.start_rot, (N, 1, 1))
        vel, acc, omega, alpha = (np.zeros((N, 3)) for _ in range(4))
        if len(self.t) == 0:
            return pos, rot, vel, acc, omega, alpha
        before, after = t <= self.t[0], t >= self.t[-1]
        pos[before], rot[before] = self.start_pos + self.d[0], self.R[0]
        pos[after], rot[after] = self.start_pos + self.d[-1], self.R[-1]
        seg = np.clip(np.searchsorted(self.t, t, side="right") - 1, 0, len(self.t) - 2)
        inside = ~before & ~after
        for i in np.unique(seg[inside]):
            sel = inside & (seg == i)
            T = self.t[i + 1] - self.t[i]
            s = (t[sel] - self.t[i]) / T
            p, dp, ddp = cruise(s, self.ramp[i]) if self.ramp[i] > 0 else min_jerk(s)
            delta = self.d[i + 1] - self.d[i]
            pos[sel] = self.start_pos + self.d[i] + p[:, None] * delta
            vel[sel] = (dp / T)[:, None] * delta
            acc[sel] = (ddp / T**2)[:, None] * delta
            axis, angle = self.seg_axis[i], self.seg_angle[i]
            rot[sel] = mm(axis_angle_to_rot(axis, p * angle), self.R[i])
            omega[sel] = (angle * dp / T)[:, None] * axis
            alpha[sel] = (angle * ddp / T**2)[:, None] * axis
        return pos, rot, vel, acc, omega, alpha


def _unit(v) -> np.ndarray:
    v = np.asarray(v, dtype=float)
    n = norm(v)
    return v / n if n > 0 else np.array([1.0, 0.0, 0.0])


def timed(t0: float, t1: float, waypoints: list, weights: list) -> list:
    """Spreads waypoints over [t0, t1] with segment durations proportional to ``weights``.

    Args:
        t0: Time of the first waypoint, [s].
        t1: Time of the last waypoint, [s].
        waypoints: ``(displacement (3,), rotation vector (3,))`` pairs, the first at t0.
        weights: Relative duration of each of the ``len(waypoints) - 1`` segments (> 0).

    Returns:
        Keyframes ``(t, displacement, rotation vector)`` for :class:`Motion`.
    """
    if len(weights) != len(waypoints) - 1 or min(weights) <= 0:
        raise ValueError("need one positive weight per segment between waypoints")
    cum = np.concatenate([[0.0], np.cumsum(weights)]) / np.sum(weights)
    return [(t0 + c * (t1 - t0), np.asarray(d, float), np.asarray(r, float)) for c, (d, r) in zip(cum, waypoints)]
