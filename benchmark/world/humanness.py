"""How human the world is: motion peaks, grip fluctuations and grip-load coupling of the truth.

    python -m benchmark.commands.humanness [--suite standard] [--out results/world]

simulates every episode of a suite (no rendering); the command writes ``humanness.md``,
``humanness.json`` and ``humanness_margins.png``: per task the distribution of the box's peak
acceleration and angular velocity while lifted beside the ranges of
:mod:`benchmark.world.tasks.human`, the thumb's grip-force coefficient of variation in holds, the
grip-load correlation and lead on ``shake``, the effective safety margin and the thumb's force per
weight, and the largest Newton-Euler residual of the truth; per episode the person's drawn margin
against the realised one, and the grip in holds against the slip limit.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from tqdm import tqdm

from benchmark.world.living import LivingGrip
from benchmark.world.people import person
from benchmark.world.simulate import simulate
from fsv.linalg import norm

STILL_ACC = 0.3
"""A lifted box moves less than this during a hold, [m/s^2]."""
STILL_OMEGA = 0.2
"""... and turns slower than this, [rad/s]."""
MIN_HOLD_S = 1.0
"""Holds shorter than this are not scored, [s]."""
MAX_LAG_S = 0.2
"""The grip-load lag is searched within +- this, [s]."""
LIFT_OFF_TRANSIENT_S = 1.0
"""The grip-load coupling is measured from this long after each lift-off, [s]: the grip overshoots
at lift-off and declines to its static level over about a second (Johansson & Westling 1984,
Exp. Brain Res. 56), a transient apart from the coupling of grip to load in movement, which
Flanagan & Wing (1993, 1995) measured in the steady state of cyclic movements."""


@dataclass(frozen=True)
class EpisodeHumanness:
    """The statistics of one episode's truth.

    Attributes:
        peak_acc: Largest |box acceleration| while lifted (held, no table contact), [m/s^2].
        peak_omega: Largest |box angular velocity| while lifted, [rad/s].
        grip_cv: Median over holds (>= MIN_HOLD_S, lifted, still, from LIFT_OFF_TRANSIENT_S after
            lift-off: :func:`coupling_frames`) of the thumb normal force's coefficient of variation;
            nan without such a hold.
        grip_load_corr: Largest correlation of the thumb normal force with the load force |m (a - g)|
            over lags within +- MAX_LAG_S while lifted, from LIFT_OFF_TRANSIENT_S after each
            lift-off (:func:`coupling_frames`).
        grip_lead_s: The lag of that correlation: > 0 when the grip leads the load, [s].
        newton_euler_n: Largest Newton-Euler force residual over all frames, [N].
        effective_margin: Median over lifted frames of the grip's effective safety margin
            1 - L / (mu sum N), L the digits' summed tangential force and sum N their summed normal
            force (for a thumb opposing the fingers, Johansson & Westling's (G - G_slip) / G); nan
            without a lifted frame or a friction coefficient.
        thumb_per_weight: Median over lifted frames of the thumb's normal force over the box's
            weight m |g|.
        hold_grip_n: Median over the holds' frames (those of ``grip_cv``) of the thumb's normal force,
            [N]; nan without a hold.
        hold_slip_n: Median over the same frames of the slip limit L / (2 mu), the grip at which the
            digits' summed tangential force L would make the grasp slip (a thumb against the fingers:
            each side's normal force times mu carries its half), [N]; nan without a hold.
        max_slip_mm: Largest drift of a digit's centre of pressure on the box (box frame) while held,
            from where it was at the first held frame, over the digits in contact throughout, [mm].
        drawn_margin: The person's drawn safety margin (``benchmark.world.people``); nan if not given.
        trial_margin: This trial's margin (the drawn one times the living grip's trial factor,
            ``benchmark.world.living``); nan if not given.
    """

    peak_acc: float
    peak_omega: float
    grip_cv: float
    grip_load_corr: float
    grip_lead_s: float
    newton_euler_n: float
    effective_margin: float = float("nan")
    thumb_per_weight: float = float("nan")
    hold_grip_n: float = float("nan")
    hold_slip_n: float = float("nan")
    max_slip_mm: float = float("nan")
    drawn_margin: float = float("nan")
    trial_margin: float = float("nan")


def lifted(truth) -> np.ndarray:
    """Frames held with no table contact, (T,) bool."""
    return truth.held & (np.linalg.norm(truth.env_force, axis=1) == 0)


def coupling_frames(truth, fps: float) -> np.ndarray:
    """Frames lifted (:func:`lifted`) at least LIFT_OFF_TRANSIENT_S after the lift-off that began
    their run, (T,) bool: where the grip-load coupling is measured."""
    up = lifted(truth)
    out = up.copy()
    skip = int(round(LIFT_OFF_TRANSIENT_S * fps))
    for start in np.flatnonzero(np.diff(np.concatenate([[0], up.astype(int)])) == 1):
        out[start : start + skip] = False
    return out


def thumb_normal_force(truth) -> np.ndarray:
    """The thumb's normal force on the box, (T,), [N] (0 without contact)."""
    return np.einsum("tj,tj->t", truth.contact_force[:, 0], truth.contact_normal[:, 0])


def holds(mask: np.ndarray, fps: float) -> list:
    """Runs of True at least MIN_HOLD_S long, as slices."""
    edges = np.flatnonzero(np.diff(np.concatenate([[0], mask.astype(int), [0]])))
    return [slice(a, b) for a, b in zip(edges[::2], edges[1::2]) if (b - a) / fps >= MIN_HOLD_S]


def tangential_load(truth) -> np.ndarray:
    """The digits' summed tangential force L on every frame, (T,), [N]."""
    normal = truth.normal_force()
    return np.linalg.norm(truth.contact_force - normal[..., None] * truth.contact_normal, axis=2).sum(axis=1)


def max_drift_m(truth) -> float:
    """Largest drift of a digit's centre of pressure on the box (box frame) while held, from where it
    was at the first held frame, over the digits in contact throughout the held frames, [m]."""
    held = truth.held if truth.held is not None else np.ones(len(truth.t), bool)
    if not held.any():
        return 0.0
    cp, act = truth.contact_point[held], truth.contact_active[held]
    drift = 0.0
    for k in range(act.shape[1]):
        if act[:, k].all():
            drift = max(drift, float(np.linalg.norm(cp[:, k] - cp[0, k], axis=1).max()))
    return drift


def effective_margin(truth, friction: float) -> np.ndarray:
    """The grip's effective safety margin 1 - L / (mu sum N) on every frame, (T,) (nan where no
    digit presses): L the digits' summed tangential force, sum N their summed normal force."""
    normal = truth.normal_force()
    tangential = np.linalg.norm(truth.contact_force - normal[..., None] * truth.contact_normal, axis=2)
    total = normal.sum(axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(total > 0, 1.0 - tangential.sum(axis=1) / (friction * total), np.nan)


def episode_humanness(truth, fps: float, friction: float = float("nan")) -> EpisodeHumanness:
    """The statistics of one episode's truth (see :class:`EpisodeHumanness`); ``friction`` is the
    finger-box friction coefficient of its world (for the effective margin)."""
    up = lifted(truth)
    acc = np.linalg.norm(truth.box_acc, axis=1)
    omega = np.linalg.norm(truth.box_omega, axis=1)
    grip = thumb_normal_force(truth)
    still = coupling_frames(truth, fps) & (acc < STILL_ACC) & (omega < STILL_OMEGA) & truth.contact_active[:, 0]
    runs = holds(still, fps)
    cvs = [np.std(grip[s]) / np.mean(grip[s]) for s in runs]
    in_holds = np.zeros(len(grip), bool)
    for s in runs:
        in_holds[s] = True
    slip_limit = tangential_load(truth) / (2.0 * friction)
    load = np.linalg.norm(truth.mass * (truth.box_acc - truth.gravity), axis=1)
    corr, lead = _best_lag(grip, load, coupling_frames(truth, fps), int(round(MAX_LAG_S * fps)))
    force, _ = truth.newton_euler_residual()
    margin = float(np.nanmedian(effective_margin(truth, friction)[up])) if up.any() and np.isfinite(friction) else float("nan")
    weight = truth.mass * norm(truth.gravity)
    return EpisodeHumanness(
        peak_acc=float(acc[up].max()) if up.any() else float("nan"),
        peak_omega=float(omega[up].max()) if up.any() else float("nan"),
        grip_cv=float(np.median(cvs)) if cvs else float("nan"),
        grip_load_corr=corr, grip_lead_s=lead / fps,
        newton_euler_n=float(np.max(np.linalg.norm(force, axis=1))),
        effective_margin=margin,
        thumb_per_weight=float(np.median(grip[up]) / weight) if up.any() else float("nan"),
        hold_grip_n=float(np.median(grip[in_holds])) if in_holds.any() else float("nan"),
        hold_slip_n=float(np.median(slip_limit[in_holds])) if in_holds.any() and np.isfinite(friction) else float("nan"),
        max_slip_mm=1000.0 * max_drift_m(truth),
    )


def _best_lag(grip: np.ndarray, load: np.ndarray, mask: np.ndarray, max_lag: int) -> tuple[float, int]:
    """The largest correlation of grip(t) with load(t + lag) over |lag| <= max_lag (lag > 0: the
    grip leads), on frames where both are in ``mask``; and its lag in frames."""
    best, best_lag = -np.inf, 0
    T = len(grip)
    for lag in range(-max_lag, max_lag + 1):
        i = np.arange(max(0, -lag), min(T, T - lag))
        sel = mask[i] & mask[i + lag]
        if sel.sum() < 10:
            continue
        c = float(np.corrcoef(grip[i][sel], load[i + lag][sel])[0, 1])
        if c > best:
            best, best_lag = c, lag
    return (best if np.isfinite(best) else float("nan")), best_lag


def suite_humanness(suite, progress: bool = True) -> list:
    """``(scenario, EpisodeHumanness)`` for every episode of a suite (simulated, not rendered), with the
    person's drawn margin and the trial's."""

    scenarios = suite.scenarios
    if progress:
        scenarios = tqdm(scenarios, desc=f"simulate {suite.name}", unit="episode", leave=False)
    rows = []
    for sc in scenarios:
        ep = simulate(sc)
        h = episode_humanness(ep.truth, sc.fps, ep.object_model.friction)
        drawn = float(person(sc.user)["safety_margin"])
        trial = drawn * LivingGrip.draw(sc.rng("grip")).trial_scale  # the draws the simulation made
        rows.append((sc, replace(h, drawn_margin=drawn, trial_margin=trial)))
    return rows
