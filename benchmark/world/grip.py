"""The synthetic human: how hard each finger squeezes, and the hand it moves.

:class:`GripPolicy` turns the load the hand must carry into fingertip forces, following the
motor-control literature: the grip (normal) force tracks the load force with a user-specific
relative safety margin over the slip limit, (G - G_slip) / G (Johansson & Westling 1984),
anticipating the planned load rather than reacting to it (Flanagan & Wing 1995), digit by digit
(Burstedt, Flanagan & Johansson 1999) with a per-finger share of the internal force (Radwin et al.
1992), varying within a hold and from trial to trial (:mod:`benchmark.world.living`). The forces
become joint torques through the fingertip Jacobians, tau = J^T f; MuJoCo's contact solver then
produces the true contact forces. Where the hand goes for a grasp is
:mod:`benchmark.world.grasp_plan`; how the grip is scaled, the scenario's ``grip_control``:
"per-digit" (:meth:`GripPolicy.grasp_hold`, the world's) or "whole-hand"
(:meth:`GripPolicy.whole_hand`, the world of earlier versions)."""

from __future__ import annotations

from dataclasses import dataclass, replace

import mujoco
import numpy as np

from benchmark.world.assets import World, user_of
from benchmark.world.grip_kernels import (
    commanded_forces,
    contact_loads,
    correct_feedback,
    finger_torques,
    first_order_response,
    hold_passes,
    running_max,
)
from benchmark.world.living import MOVING_ACC, MOVING_ALPHA, LivingGrip
from benchmark.world.scenario import Scenario
from fsv.linalg import dot, inv, mm, mv, rows_mt, solve, vm


@dataclass(frozen=True)
class GripPolicy:
    """How one user distributes and scales fingertip forces.

    Attributes:
        friction: Skin-box friction coefficient the user expects.
        safety_margin: The relative safety margin (G - G_slip) / G: the fraction of the grip force
            above the slip limit (Johansson & Westling 1984), in [0, 1).
        baseline_grip_n: Internal force kept without load, [N] (thumb-side normal force).
        anticipation_s: The grip follows the load planned this far ahead, [s].
        response_s: Time constant of the grip force's first-order response, [s].
        share: Per finger share of the internal force, thumb first, (K,); the thumb opposes the
            fingers (its share is 1, the active fingers' shares are renormalised to sum to 1).
        min_finger_force_n: Every digit in contact presses with at least this normal force, [N]
            (a choice, the floor both controls have always used: people keep each digit of a grasp
            in firm contact; as a lower bound on the digit's requirement, not added to it, it binds
            only where a digit carries little load. With 0.5-0.75 N a digit's force fell below the
            task contract's 0.5 N where the table took the box's weight before the hand let go).
    """

    friction: float
    safety_margin: float
    baseline_grip_n: float
    anticipation_s: float
    response_s: float
    share: np.ndarray
    min_finger_force_n: float = 1.0

    @staticmethod
    def for_scenario(scenario: Scenario, world: World) -> "GripPolicy":
        user = user_of(scenario)
        share = np.array([1.0] + [float(user["finger_share"][f]) for f in world.hand.finger_names[1:]])
        return GripPolicy(friction=world.obj.friction, safety_margin=float(user["safety_margin"]),
                          baseline_grip_n=float(user["baseline_grip_n"]), anticipation_s=float(user["anticipation_s"]),
                          response_s=float(user["response_s"]), share=share)

    def nominal_and_compressions(self, wrench: np.ndarray, points: np.ndarray, normals_in: np.ndarray,
                                 active: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The nominal forces of a wrench, and the internal forces that press each digit.

        All vectors in one frame (world or object), about the centre of mass.

        Args:
            wrench: Force and torque the hand must apply to the box, (6,) or (N, 6), [N], [N m].
            points: Contact points relative to the centre of mass, (K, 3), [m].
            normals_in: Unit normals into the box, (K, 3).
            active: Digits in contact, (K,) bool.

        Returns:
            ``(f_nom, press)``: the forces producing the wrench with the least norm weighted by
            the inverse grip shares (a digit carries load in proportion to its grip), (K, 3) or
            (N, K, 3); and per digit j the internal (workless) forces that press it with a unit
            normal force, (K, K, 3): ``press[0]`` is the squeeze of the grasp as a whole (the thumb
            against the fingers in their shares, moved so that the fingers' normal forces balance
            the thumb's moment: :func:`centred_shares`), ``press[j]`` for a finger the internal forces
            nearest to finger j pressing alone (the thumb and the others react), zero rows for
            digits not in contact.
        """
        wrench = np.asarray(wrench, dtype=float)
        single = wrench.ndim == 1
        wrench = np.atleast_2d(wrench)
        K = len(active)
        idx = np.flatnonzero(active)
        G = np.zeros((6, 3 * len(idx)))
        for i, k in enumerate(idx):
            r = points[k]
            G[:3, 3 * i : 3 * i + 3] = np.eye(3)
            G[3:, 3 * i : 3 * i + 3] = [[0, -r[2], r[1]], [r[2], 0, -r[0]], [-r[1], r[0], 0]]
        share = self.share[idx].copy()
        share[1:] /= share[1:].sum()
        # Weighted least norm: every pad works at a similar fraction of its friction cone.
        W = np.repeat(share, 3)
        Gp = mm(W[:, None] * G.T, inv(mm(G * W, G.T)))
        f_nom = np.zeros((len(wrench), K, 3))
        f_nom[:, idx] = rows_mt(wrench, Gp).reshape(len(wrench), -1, 3)
        press = np.zeros((K, K, 3))
        weights = centred_shares(share, points[idx], normals_in[idx])
        for i, k in enumerate(idx):
            d = np.zeros((len(idx), 3))
            if i == 0:
                d[:] = weights[:, None] * normals_in[idx]
            else:
                d[i] = normals_in[k]
            d = d.ravel()
            d_int = (d - mv(Gp, mv(G, d))).reshape(-1, 3)
            press[k, idx] = d_int / dot(d_int[i], normals_in[k])
        return (f_nom[0] if single else f_nom), press

    @property
    def slip_slope(self) -> float:
        """The normal force per newton of tangential load at which a digit works with the person's
        safety margin: 1 / (mu (1 - margin)) (the margin is Johansson & Westling's relative one,
        (G - G_slip) / G)."""
        return 1.0 / (self.friction * (1.0 - self.safety_margin))

    def hold(self, f_nom: np.ndarray, press: np.ndarray, normals_in: np.ndarray, active: np.ndarray,
             baseline_n, slope=None, held_load=None) -> np.ndarray:
        """How hard each digit presses: each digit pressed until it works inside its friction cone
        shrunk by the safety margin, and with at least ``min_finger_force_n``; the thumb at least
        with the baseline grip.

        A person controls the grip digit by digit (Burstedt, Flanagan & Johansson 1999): a digit that
        carries more of the load presses harder, and the others react, instead of the whole hand
        squeezing harder. Each pass adds to each digit short of its requirement
        ``max(slip_slope (1 + boost) t, min_finger_force_n)`` (t its tangential load) the press that
        brings its own normal force to it, one digit after the other, the fingers first and then the
        thumb (whose normal force is mostly their reaction: it presses for its own load only where
        their reactions fall short); the passes repeat (:data:`HOLD_PASSES`) because a press also
        moves the digits' tangential forces. The floor and the baseline are lower bounds, not added
        to the load's requirement: the grip's relative safety margin over the slip limit is the
        person's wherever the load needs more than them (Johansson & Westling 1984 measured it on
        the whole grip force).

        Args:
            f_nom: Nominal forces, (N, K, 3) [N].
            press: Unit presses per digit, (K, K, 3) (:meth:`nominal_and_compressions`).
            normals_in: Unit normals into the box, (K, 3).
            active: Digits in contact, (K,) bool.
            baseline_n: The thumb's least normal force, scalar or (N,) [N].
            slope: Each digit's normal force per newton of its tangential load, per tick, (N,);
                None: :attr:`slip_slope`.
            held_load: A tangential load each digit is pressed for at least, per tick, (N, K) [N]
                (:func:`load_envelope`); None: its own.

        Returns:
            The press of each digit, (N, K) [N]: the forces are ``f_nom + sum_j c[:, j] press[j]``.
        """
        N, K = f_nom.shape[:2]
        c = np.zeros((N, K))
        f = np.array(f_nom, dtype=np.float64, order="C")
        slope = np.full(N, self.slip_slope) if slope is None else np.broadcast_to(np.asarray(slope, dtype=float), (N,))
        order = [*np.flatnonzero(active[1:]) + 1, 0] if active[0] else list(np.flatnonzero(active))
        # one digit at a time, the fingers before the thumb that opposes them, pass after pass
        hold_passes(f, c, slope, held_load, press, normals_in, np.asarray(order, dtype=np.int64),
                    self.min_finger_force_n, HOLD_PASSES, HOLD_TOLERANCE_N)
        if active[0]:
            n0 = np.einsum("nd,d->n", f[:, 0], normals_in[0])
            c[:, 0] += np.maximum(np.asarray(baseline_n, dtype=float) - n0, 0.0)
        return c

    @property
    def digit_margin(self) -> float:
        """The least relative safety margin a digit works with under :meth:`grasp_hold`: the person's
        times :data:`DIGIT_MARGIN_FRACTION`, at least :data:`DIGIT_MARGIN_MIN` (and at most the person's)."""
        return min(max(DIGIT_MARGIN_FRACTION * self.safety_margin, DIGIT_MARGIN_MIN), self.safety_margin)

    def grasp_hold(self, f_nom: np.ndarray, press: np.ndarray, normals_in: np.ndarray, active: np.ndarray,
                   baseline_n, boost=None, held_load=None) -> tuple[np.ndarray, np.ndarray]:
        """How hard each digit presses for the grasp to hold with the person's safety margin: the
        digit-by-digit presses of :meth:`hold`, at the slope (normal force per newton of a digit's
        tangential load) at which the grasp as a whole works with the person's relative margin,
        1 - L / (mu sum N) = margin (L the digits' summed tangential force, sum N their summed
        normal force; Johansson & Westling 1984 measured the margin on the grip as a whole).

        Each digit's normal force follows its own load (Burstedt, Flanagan & Johansson 1999), but
        the digits' normal forces must balance across the grasp: the thumb opposes the fingers, so a
        side that carries less tangential load than the other works with a larger margin than its
        requirement. Pressing every digit at the person's margin would put the grasp's margin above
        it; the slope is lowered until the grasp's margin is the person's (:data:`GRASP_ITERATIONS`
        corrections, each scaling the slope by the summed normal force wanted over the one pressed),
        but never so far that a digit works with less than :data:`DIGIT_MARGIN_FRACTION` of the
        person's margin. The floor and the baseline keep the grip above that at light loads.

        Args:
            f_nom: Nominal forces, (N, K, 3) [N].
            press: Unit presses per digit, (K, K, 3) (:meth:`nominal_and_compressions`).
            normals_in: Unit normals into the box, (K, 3).
            active: Digits in contact, (K,) bool.
            baseline_n: The thumb's least normal force, scalar or (N,) [N].
            boost: The grip's relative raise per tick (the lift-off overshoot), (N,); None: 0.
            held_load: As :meth:`hold`'s.

        Returns:
            ``(c (N, K), slope (N,))``: the presses (as :meth:`hold`'s) and the digits' slope per tick.
        """
        N = len(f_nom)
        raise_ = np.ones(N) if boost is None else 1.0 + np.asarray(boost, dtype=float)
        person = self.slip_slope * raise_
        lowest = raise_ / (self.friction * (1.0 - self.digit_margin))
        idx = np.flatnonzero(active)
        nrm = normals_in[idx]
        slope = person
        for _ in range(GRASP_ITERATIONS):
            c = self.hold(f_nom, press, normals_in, active, baseline_n, slope, held_load)
            f = (f_nom + np.einsum("nj,jkd->nkd", c, press))[:, idx]
            n = np.einsum("nkd,kd->nk", f, nrm)
            tang = f - n[..., None] * nrm
            load = np.sqrt(np.einsum("nkd,nkd->nk", tang, tang)).sum(axis=1)
            wanted = person * load
            slope = np.clip(slope * wanted / np.maximum(n.sum(axis=1), 1e-9), lowest, person)
        return self.hold(f_nom, press, normals_in, active, baseline_n, slope, held_load), slope

    def whole_hand(self, f_nom: np.ndarray, squeeze: np.ndarray, normals_in: np.ndarray,
                   active: np.ndarray) -> tuple[np.ndarray, float]:
        """The whole-hand grip (``grip_control="whole-hand"``): how far the grasp's squeeze must be
        scaled for every pad to work inside its friction cone shrunk by the safety margin, and for
        every digit to press with ``min_finger_force_n`` without load.

        The squeeze scales as one pattern, so the digit closest to slipping sets every digit's
        force (docs/findings.md, "How hard the simulated people squeeze").

        Args:
            f_nom: Nominal forces, (N, K, 3) [N].
            squeeze: The internal forces of the grasp per newton of the thumb's normal force,
                (K, 3): ``press[0]`` of :meth:`nominal_and_compressions`.
            normals_in: Unit normals into the box, (K, 3).
            active: Digits in contact, (K,) bool.

        Returns:
            ``(grip_slip (N,), grip_floor)``: the thumb-side grip that keeps every pad from
            slipping, and the one at which every digit presses with ``min_finger_force_n`` with
            no load, [N].
        """
        idx = np.flatnonzero(active)
        mu = self.friction * (1.0 - self.safety_margin)
        nrm = normals_in[idx]
        d_int = squeeze[idx]
        n0 = np.einsum("nkj,kj->nk", f_nom[:, idx], nrm)
        n1 = np.einsum("kj,kj->k", d_int, nrm)
        t0 = f_nom[:, idx] - n0[..., None] * nrm
        t1 = d_int - n1[:, None] * nrm
        a = mu**2 * n1**2 - np.einsum("kj,kj->k", t1, t1)
        b = 2 * (mu**2 * n0 * n1 - np.einsum("nkj,kj->nk", t0, t1))
        c = mu**2 * n0**2 - np.einsum("nkj,nkj->nk", t0, t0)
        ok = (c >= 0) & (n0 >= 0)
        root = (-b + np.sqrt(np.maximum(b * b - 4 * a * c, 0.0))) / (2 * np.maximum(a, 1e-9))
        grip = np.max(np.where(ok, 0.0, np.maximum(root, -n0 / np.maximum(n1, 1e-9))), axis=1)
        grip = np.maximum(grip, np.max(-n0 / np.maximum(n1, 1e-9), axis=1))
        grip = np.maximum(grip, 0.0)
        floor = float(np.max(self.min_finger_force_n / np.maximum(n1, 1e-9)))
        return grip, floor

def centred_shares(share: np.ndarray, points: np.ndarray, normals_in: np.ndarray) -> np.ndarray:
    """The weights of the grasp's squeeze: the thumb's 1 and the fingers' shares of its opposing
    force, moved as little as needed for the squeeze's normal forces to exert no moment on the box.

    People share the fingers' normal forces so that their moments balance the thumb's (Zatsiorsky,
    Gregory & Latash 2002, Biol. Cybern. 87; Zatsiorsky & Latash 2008, J. Mot. Behav. 40): pressed
    in the person's own shares, fingers whose resultant is not opposite the thumb turn the box, and
    friction along the faces must hold it with a couple that grows with the squeeze. The fingers'
    weights w minimise sum_j (w_j - s_j)^2 / s_j + CENTRING_WEIGHT |m_0 + sum_j w_j m_j|^2 (m the
    moment about the centre of mass of a digit's unit normal force, [m], its components about the
    horizontal axes weighted by :data:`HORIZONTAL_MOMENT_WEIGHT`) with the thumb's force
    balanced along its normal and every w_j at least :data:`CENTRING_MIN_SHARE` of s_j: where the
    thumb faces a point well between the fingers' pads the moment vanishes; elsewhere it is the
    least the fingers can make it.

    Args:
        share: The thumb's 1 and the fingers' shares (summing to 1), thumb first, (A,).
        points: The digits' contact points relative to the centre of mass, thumb first, (A, 3), [m].
        normals_in: Their unit normals into the box, (A, 3).

    Returns:
        The weights, thumb first (1), (A,).
    """
    A = len(share)
    out = np.ones(A)
    if A < 2:
        return out
    s = np.asarray(share[1:], dtype=float)
    moment = np.stack([_cross3(points[k], normals_in[k]) for k in range(A)])
    m0, M = moment[0], moment[1:]
    a = -np.einsum("kj,j->k", normals_in[1:], normals_in[0])  # each finger's force opposing the thumb's
    axes = np.array([HORIZONTAL_MOMENT_WEIGHT, HORIZONTAL_MOMENT_WEIGHT, 1.0])  # the box's z is up
    lo = CENTRING_MIN_SHARE * s
    free = np.ones(A - 1, bool)
    w = s.copy()
    for _ in range(A):  # active set: fingers whose weight would fall below their bound are held at it
        i, fixed = np.flatnonzero(free), np.flatnonzero(~free)
        F = len(i)
        held = m0 + (np.einsum("k,kd->d", lo[fixed], M[fixed]) if len(fixed) else 0.0)
        H = np.zeros((F + 1, F + 1))
        rhs = np.zeros(F + 1)
        for p in range(F):
            H[p, p] += 2.0 / s[i[p]]
            rhs[p] += 2.0
            for q in range(F):
                H[p, q] += 2.0 * CENTRING_WEIGHT * dot(M[i[p]] * axes, M[i[q]])
            rhs[p] -= 2.0 * CENTRING_WEIGHT * dot(M[i[p]] * axes, held)
            H[p, F] = H[F, p] = a[i[p]]
        rhs[F] = 1.0 - (dot(a[fixed], lo[fixed]) if len(fixed) else 0.0)
        x = solve(H, rhs)
        w = lo.copy()
        w[i] = x[:F]
        if np.all(w[i] >= lo[i]) or F == 1:
            break
        free[i[int(np.argmin(w[i] - lo[i]))]] = False
    out[1:] = np.maximum(w, lo)
    return out


def _cross3(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


CENTRING_WEIGHT = 1e6
"""Cost of the squeeze's moment about the box's vertical per newton of the thumb, [1/m^2], against the
fingers' departure from their shares: 1 mm of unbalanced lever costs about as much as moving a
finger's share by its own size (a choice: the moment vanishes wherever the geometry allows)."""
CENTRING_MIN_SHARE = 0.5
"""No finger's weight falls below this fraction of its own share (a choice: the fingers' forces keep
their proportions, Radwin et al. 1992; a finger pressed with almost nothing leaves the box to pivot
about the line from the thumb to the others)."""
HORIZONTAL_MOMENT_WEIGHT = 0.01
"""... and about the horizontal axes, relative to it (a choice): a moment about the vertical must be
held by a horizontal couple along the faces, which adds to the digits' tangential forces; one about
a horizontal axis (the thumb above or below the fingers) by a vertical couple, which only shifts
load between the thumb and the fingers."""
GRASP_ITERATIONS = 2
"""Corrections of the digits' slope in :meth:`GripPolicy.grasp_hold`."""
DIGIT_MARGIN_FRACTION = 0.75
"""No digit works with less than this fraction of the person's safety margin (a choice: the grasp's
margin is the person's, and none of its digits comes close to slipping)."""
DIGIT_MARGIN_MIN = 0.1
"""... and never less than this (the least relative margin Johansson & Westling 1984 measured)."""
HOLD_PASSES = 30
"""Passes of :meth:`GripPolicy.hold` at most (each digit's press moves the others' forces a little)."""
HOLD_TOLERANCE_N = 1e-6
"""A digit within this of its requirement needs no further press, [N]."""

MAX_FINGER_FORCE_N = 35.0  # commanded fingertip forces are capped here (human range of such grips: < 40 N)
REFLEX_LATENCY_S = 0.07
"""Delay from a digit's load to its grip correction: the grip responses to load and slips start
60-80 ms after them (Johansson & Westling 1984; Cole & Abbs 1988)."""
REFLEX_TIME_S = 0.1
"""Time constant of a digit's correction of its realized deficit (a choice: slow enough against the
latency to stay stable, fast enough to catch a lift's load within a few hundred milliseconds)."""
RELAX_TIME_S = 0.5
"""Time constant with which a digit's correction relaxes once its load is met (a choice: grip
forces relax over about a second in static holds, Johansson & Westling 1984)."""
LIFT_OFF_OVERSHOOT = 0.25
"""The digits' requirement is raised by this fraction of itself while the load comes onto the hand
and just after lift-off: the grip force peaks shortly after lift-off and then declines to its static
level (Johansson & Westling 1984, Exp. Brain Res. 56; the peak is a choice within the overshoots
they show)."""
ENVELOPE_FRACTION = 0.7
"""A digit is pressed for at least this fraction of its peak load nearby (a choice, :func:`load_envelope`:
with 0.4-0.6 the index of the named grasps 0 and 1, 12 mm off the centre of mass, lost its contact
at the load's minima in a `shake` or a `free` of the cohort suite and the box turned into the palm;
Flanagan & Wing 1995's grip fell to about half its peak at the load's minima)."""
ENVELOPE_S = 0.5
"""... within this before or after, [s] (a choice: a cycle of the 1-2 Hz movements Flanagan & Wing studied)."""
LIFT_OFF_HOLD_S = 0.3
"""The raise is kept this long after lift-off, [s]."""
LIFT_OFF_DECAY_S = 0.5
"""Then it decays with this time constant, [s]."""
CONTROL_PERIOD_FALLBACK_S = 0.004
STOP_AT_TOUCH = True
REPLAN_EVERY = 12
"""While the load comes on, the forces are planned again for the sensed contacts every this many
control ticks (48 ms)."""
REPLAN_AFTER_LOAD_S = 0.3
"""... until this long after the load phase ends, [s] (the pads settle as the box leaves the table)."""
"""The control period assumed for a single control tick, [s]."""


def _quat_of(R: np.ndarray) -> np.ndarray:
    q = np.zeros(4)
    mujoco.mju_mat2Quat(q, np.ascontiguousarray(R).ravel())
    return q


class Human:
    """The synthetic human acting in a world: moves the palm's mocap target and sets finger torques.

    The human plans ahead (its motor plan is the task's motion): :meth:`__init__` computes, for
    every physics step, the palm's target pose and the fingers' posture targets, and for every
    control tick the fingertip forces of the grip policy in the object frame, anticipating the
    planned load by the user's anticipation time and low-pass filtered by the user's response
    time. At run time :meth:`act` writes ``data.mocap_pos/quat``, ``data.ctrl`` (position
    actuators of the fingers) and, on control ticks, ``data.qfrc_applied`` on the finger joints:
    tau = J^T (R f), with R the box's actual orientation. Under the "per-digit" control it also
    senses the grasp: a closing digit stops where it touches (:meth:`_stop_at_touch`), the forces
    are planned again for the pads' sensed contacts while the load comes on (:meth:`_replan`,
    :data:`REPLAN_EVERY`, :data:`REPLAN_AFTER_LOAD_S`), and each digit's grip-load ratio is
    corrected from the load it carries (:meth:`_correct`). All of it is read from the simulation's
    own state, so the world stays the same bits on every machine.

    Args:
        scenario: The scenario (its user's grip style and its seed).
        world: Its compiled world.
        plan: The grasp's ``benchmark.world.grasp_plan.GraspPlan`` for this hand.
        motion: The planned box motion (world frame).
        phases: The prehension phases.
        releases: Whether the hand lets go at the end.
        times: Times of the physics steps, (N,), [s].
        ctrl_every: Control tick every this many steps.
    """

    def __init__(self, scenario: Scenario, world: World, plan, motion, phases, releases: bool, times: np.ndarray,
                 ctrl_every: int):
        self.world, self.motion, self.phases, self.releases = world, motion, phases, releases
        self.plan = plan
        grip_rng = scenario.rng("grip")
        self.living = living = LivingGrip.draw(grip_rng)
        pol = GripPolicy.for_scenario(scenario, world)  # this trial's: margin and baseline scaled
        self.policy = pol = replace(pol, safety_margin=pol.safety_margin * living.trial_scale,
                                    baseline_grip_n=pol.baseline_grip_n * living.trial_scale)
        self.ctrl_every = ctrl_every
        self.R_palm_obj = _rot(plan.palm_quat)
        self.approach = np.array([0.0, -0.06, 0.12])
        t = np.asarray(times, dtype=float)
        self.palm_pos, self.palm_quat, q = _palm_and_posture(t, motion, plan, phases, releases, self.R_palm_obj,
                                                             self.approach)
        self.ctrl = q[:, world.actuator_joint]
        # the digits' closing stops at touch (see act): each digit's actuators and the times
        self._t, self._touched = t, np.zeros(len(plan.active), bool)
        self._opening = (_mj((t - phases.unload_end) / max(phases.open_end - phases.unload_end, 1e-9))
                         * (t >= phases.unload_end)) if releases else np.zeros(len(t))
        names = world.hand.joint_names
        self._digit_actuators = [np.flatnonzero([names[j].startswith(f + "_") for j in world.actuator_joint])
                                 for f in world.hand.finger_names]
        tk = t[::ctrl_every]
        self.control = scenario.grip_control
        self._planned = planned_load(tk, world, motion, pol, living, phases, releases)
        target, f_nom, press, self._slope = _grip_target(self._planned, plan, pol, phases, releases, self.control)
        self.grip_target = target
        self._keep = np.exp(-(tk[1] - tk[0]) / pol.response_s) if len(tk) > 1 else 0.0
        self._modulation = living.modulation(tk, grip_rng)
        self._filtered = np.zeros_like(target)
        self.grip = np.zeros_like(target)
        self.forces_obj = np.zeros(f_nom.shape)
        off = (tk < phases.reach_end) | ((tk >= phases.open_end) if releases else False)
        self.on = ~off
        self._set_forces(0, target, f_nom, press)
        # the grasp as it landed: the forces are planned again from the sensed contacts (see act)
        window = np.flatnonzero((tk >= phases.close_end) & (tk < phases.load_end + REPLAN_AFTER_LOAD_S))
        self._replan_ticks = set(window[::REPLAN_EVERY].tolist()) if self.control == "per-digit" else set()
        self._sensed = np.asarray(plan.spot, dtype=float).copy()
        # tactile feedback (see act): each digit's realized load, delayed, presses it further
        self.active = np.asarray(plan.active, bool)
        self.normals = np.asarray(plan.normal_in, dtype=float)
        self.feedback = np.zeros(len(plan.active))
        dt = float(tk[1] - tk[0]) if len(tk) > 1 else CONTROL_PERIOD_FALLBACK_S
        self._delay = max(1, int(round(REFLEX_LATENCY_S / dt)))
        self._gain = dt / REFLEX_TIME_S
        self._leak = float(np.exp(-dt / RELAX_TIME_S))
        self._deficits = np.zeros((self._delay, len(plan.active)))
        self._tick = 0
        self._views = None
        # the digits in contact: their fingertip sites, and (digit, its Jacobian, dof) per torque
        touching = np.flatnonzero(plan.active)
        self._tip_sites = [int(world.tip_site[k]) for k in touching]
        self._jacs = np.zeros((len(touching), 3, world.model.nv))
        self._torque_rows = np.array([(k, a, dof) for a, k in enumerate(touching) for dof in world.finger_dofs[k]],
                                     dtype=np.int64).reshape(-1, 3)

    def _set_forces(self, start: int, target: np.ndarray, f_nom: np.ndarray, press: np.ndarray) -> None:
        """The commanded forces from control tick ``start`` on: the target through the grip's
        first-order response (continuing from the tick before), times the living modulation,
        capped at MAX_FINGER_FORCE_N, zero while the hand is off the box."""
        first_order_response(target, self._filtered, start, self._keep)
        grip = self._filtered[start:] * self._modulation[start:, None]
        if self.control == "per-digit":
            forces = f_nom[start:] + np.einsum("nj,jkd->nkd", grip, press)
        else:  # the squeeze alone (the same operations as a scalar grip times its pattern)
            forces = f_nom[start:] + grip[:, 0, None, None] * press[0]
        norm = np.linalg.norm(forces, axis=2, keepdims=True)
        forces *= np.minimum(1.0, MAX_FINGER_FORCE_N / np.maximum(norm, 1e-12))
        forces[~self.on[start:]] = 0.0
        self.grip[start:] = grip
        self.forces_obj[start:] = forces
        self.press = press

    def _stop_at_touch(self, data: mujoco.MjData, step: int) -> None:
        """A closing digit stops where it touches the box: its posture target becomes its posture at
        touch for the rest of the grasp (opening from there on release). People close the digits
        onto an object and stop at contact, signalled by the fingertips' tactile afferents
        (Johansson & Westling 1984's contact responses); without it a digit that touches first
        pushes the box on the table toward the plan's spot, moving it under the others."""
        _, touching = _digit_points(self.world, data, None)
        new = touching & self.active & ~self._touched
        if not new.any():
            return
        w, plan = self.world, self.plan
        later = self._t[step:] < self.phases.close_end
        for k in np.flatnonzero(new):
            self._touched[k] = True
            acts = self._digit_actuators[k]
            joints = w.actuator_joint[acts]
            q_touch = data.qpos[w.joint_qadr[joints]]
            shift = q_touch - plan.q_grasp[joints]
            moved = self.ctrl[step:, acts] + shift[None, :] * (1.0 - self._opening[step:, None])
            self.ctrl[step:, acts] = np.where(later[:, None], q_touch[None, :], moved)

    def _replan(self, data: mujoco.MjData, box_rot: np.ndarray, tick: int) -> None:
        """Plans the forces again from the ticks on, for the contacts as they landed: a digit's
        sensed centre of pressure (box frame) replaces its planned spot (people feel where each pad
        touches and share the forces for that grasp; a pad lands millimetres from its plan, the
        thumb's about 8 mm, as the digits close under their soft posture control)."""
        points, touching = _digit_points(self.world, data, box_rot)
        self._sensed = np.where((touching & self.active)[:, None], points, self._sensed)  # a digit off for a tick keeps its last
        spot = self._sensed
        target, f_nom, press, slope = _grip_target(self._planned, self.plan, self.policy, self.phases, self.releases,
                                                   self.control, spot=spot)
        self.grip_target[tick:] = target[tick:]
        self._slope[tick:] = slope[tick:]
        self._set_forces(tick, target, f_nom, press)

    def palm_start(self) -> tuple[np.ndarray, np.ndarray]:
        """Palm pose at the first step."""
        return self.palm_pos[0].copy(), self.palm_quat[0].copy()

    def act(self, data: mujoco.MjData, step: int) -> None:
        """Writes the palm target, posture targets and (on control ticks) finger torques of a step."""
        if self._views is None or self._views[0] is not data:
            w = self.world
            self._views = (data, data.mocap_pos[w.mocap], data.mocap_quat[w.mocap], data.ctrl, data.qfrc_applied,
                           data.xmat[w.box_body].reshape(3, 3))
        _, mocap_pos, mocap_quat, ctrl, qfrc, box_rot = self._views
        mocap_pos[:] = self.palm_pos[step]
        mocap_quat[:] = self.palm_quat[step]
        ctrl[:] = self.ctrl[step]
        if step % self.ctrl_every:
            return
        tick = step // self.ctrl_every
        if STOP_AT_TOUCH and self.control == "per-digit" and self.phases.reach_end <= self._t[step] < self.phases.close_end:
            self._stop_at_touch(data, step)
        if tick in self._replan_ticks:
            self._replan(data, box_rot, tick)
        if self.on[tick] and self.control == "per-digit":
            self._correct(data, box_rot, tick)
            # the feedback raises each digit's press in proportion to its planned normal force
            f = commanded_forces(self.forces_obj[tick], box_rot, self.normals, self.feedback, self.press)
        else:
            self.feedback[:] = 0.0
            f = commanded_forces(self.forces_obj[tick], box_rot)
        m, jacs = self.world.model, self._jacs
        for a, site in enumerate(self._tip_sites):
            mujoco.mj_jacSite(m, data, jacs[a], None, site)
        finger_torques(f, jacs, self._torque_rows, qfrc)

    def _correct(self, data: mujoco.MjData, box_rot: np.ndarray, tick: int) -> None:
        """Tactile feedback on each digit's grip-load ratio: a digit's relative shortfall (how far its
        tangential load times the tick's slope exceeds its normal force, over that requirement),
        sensed :data:`REFLEX_LATENCY_S` ago, raises the digit's press as a fraction of its planned
        normal force (integrated with the time constant :data:`REFLEX_TIME_S`); a met load lets it
        relax (:data:`RELAX_TIME_S`).

        Digit by digit, as people adjust each digit's grip to its own load (Burstedt, Flanagan &
        Johansson 1999): the feedforward grip follows the planned load, this follows the load the
        digit actually carries, which a statically indeterminate grasp shares among the digits by
        their compliance, not by the plan. The correction is of the ratio (the grip-load ratio that
        Johansson & Westling 1984 saw raised after slips and kept), so it rises and falls with the
        planned load instead of lagging it as an added force would."""
        n, t = _digit_loads(self.world, data, box_rot, self.normals)
        write = self._tick % self._delay
        self._tick += 1
        # touch senses only contact: a digit off the box or not touching it senses no shortfall
        correct_feedback(n, t, self._slope[tick], self.policy.min_finger_force_n, self.active, self._deficits, write,
                         self._tick % self._delay, self.feedback, self._gain, self._leak)


def _digit_box_contacts(world: World, data: mujoco.MjData):
    """The active contacts between a digit and the box now: ``(i, k, f6, sign)`` per contact, i its
    index in ``data.contact``, k the digit, f6 its force and torque in the contact frame (one array,
    refilled for each contact: read it before the next), sign +1 where the box is geom2 (the force
    on the box), -1 where it is geom1."""
    f6 = np.zeros(6)
    con = data.contact
    for i in range(data.ncon):
        g1, g2 = int(con.geom1[i]), int(con.geom2[i])
        if world.box_geom not in (g1, g2) or con.efc_address[i] < 0:
            continue
        k = int(world.geom_finger[g1 if g2 == world.box_geom else g2])
        if k < 0:
            continue
        mujoco.mj_contactForce(world.model, data, i, f6)
        yield i, k, f6, (1.0 if g2 == world.box_geom else -1.0)


def _digit_loads(world: World, data: mujoco.MjData, box_rot: np.ndarray, normals_obj: np.ndarray) -> tuple:
    """Each digit's normal and tangential force on the box now, along its planned normal, [N], (K,) each."""
    fingers, signs, forces, rows = [], [], [], []
    for i, k, f6, sign in _digit_box_contacts(world, data):
        fingers.append(k)
        signs.append(sign)
        forces.append(f6[:3].copy())
        rows.append(i)
    frames = data.contact.frame[rows].reshape(-1, 3, 3) if rows else np.zeros((0, 3, 3))
    return contact_loads(np.array(fingers, dtype=np.int64), np.array(signs), np.array(forces).reshape(-1, 3), frames,
                         box_rot, normals_obj)


def _digit_points(world: World, data: mujoco.MjData, box_rot: np.ndarray) -> tuple:
    """Each digit's centre of pressure on the box now, relative to its centre, box frame, (K, 3) [m],
    and whether it touches, (K,) bool."""
    K = len(world.hand.finger_names)
    weighted, total = np.zeros((K, 3)), np.zeros(K)
    for i, k, f6, _ in _digit_box_contacts(world, data):
        if f6[0] > 0:
            weighted[k] += f6[0] * data.contact.pos[i]
            total[k] += f6[0]
    touching = total > 0
    if box_rot is None:
        return None, touching
    centre = data.xpos[world.box_body]
    world_points = weighted / np.where(touching, total, 1.0)[:, None]
    return rows_mt(world_points - centre, box_rot.T), touching


def _palm_and_posture(t: np.ndarray, motion, plan, ph, releases: bool, R_palm_obj: np.ndarray, approach: np.ndarray):
    """The palm's target pose and the fingers' posture targets at the times ``t``:
    ``(palm position (N, 3), palm quaternion (N, 4), joint targets (N, J))``."""
    pos, rot, *_ = motion.evaluate(t)
    palm_pos = pos + mv(rot, plan.palm_pos)
    palm_rot = mm(rot, R_palm_obj)
    reach = _mj(t / ph.reach_end)
    palm_pos += ((1 - reach) * (t < ph.reach_end))[:, None] * approach
    closing = _mj((t - ph.reach_end) / (ph.close_end - ph.reach_end))
    q = plan.q_open + closing[:, None] * (plan.q_grasp - plan.q_open)
    if releases:
        opening = _mj((t - ph.unload_end) / max(ph.open_end - ph.unload_end, 1e-9))
        q = np.where((t >= ph.unload_end)[:, None], plan.q_grasp + opening[:, None] * (plan.q_open - plan.q_grasp), q)
        leave = _mj((t - ph.open_end) / max(ph.duration - ph.open_end, 1e-9))
        palm_pos += (leave * (t >= ph.open_end))[:, None] * approach
    return palm_pos, np.array([_quat_of(R) for R in palm_rot]), q


@dataclass(frozen=True)
class PlannedLoad:
    """The load the hand plans for on every control tick, whatever the contacts: what
    :func:`_grip_target` scales (computed once per episode, :func:`planned_load`).

    Attributes:
        tk: The control ticks' times, (N,) [s].
        wrench: The wrench the hand must apply to the box, object frame, anticipated and scaled by
            the load's ramp, (N, 6) [N], [N m].
        load: The fraction of the box's load on the hand, (N,), in [0, 1].
        baseline_n: The person's baseline grip, relaxing in holds, (N,) [N].
        boost: The grip's relative raise around lift-off, (N,).
    """

    tk: np.ndarray
    wrench: np.ndarray
    load: np.ndarray
    baseline_n: np.ndarray
    boost: np.ndarray


def planned_load(tk: np.ndarray, world: World, motion, pol, living, ph, releases: bool) -> PlannedLoad:
    """The load planned on the control ticks ``tk``: the grip follows the load planned
    anticipation_s ahead of its own response (an internal model of the grip's lag), so that it
    leads or matches the load."""
    m = world.model
    mass = float(m.body_mass[world.box_body])
    inertia = np.diag(m.body_inertia[world.box_body])
    gravity = m.opt.gravity.copy()
    ta = tk + pol.anticipation_s + pol.response_s
    _, rot_a, _, acc, omega, alpha = motion.evaluate(ta)
    load = np.ones_like(ta)
    load = np.where(ta < ph.close_end, 0.0, load)
    load = np.where((ta >= ph.close_end) & (ta < ph.load_end), _mj((ta - ph.close_end) / (ph.load_end - ph.close_end)), load)
    if releases:
        load = np.where(ta >= ph.move_end, 1 - _mj((ta - ph.move_end) / max(ph.unload_end - ph.move_end, 1e-9)), load)
    # wrench in the object frame: R^T m (a - g), and J_box R^T alpha + w_b x J_box w_b
    force_obj = np.einsum("nji,nj->ni", rot_a, mass * (acc - gravity))
    w_b = np.einsum("nji,nj->ni", rot_a, omega)
    a_b = np.einsum("nji,nj->ni", rot_a, alpha)
    torque_obj = vm(a_b, inertia) + np.cross(w_b, vm(w_b, inertia))
    wrench = load[:, None] * np.concatenate([force_obj, torque_obj], axis=1)
    moving = (norm_rows(acc) > MOVING_ACC) | (norm_rows(alpha) > MOVING_ALPHA)
    baseline = pol.baseline_grip_n * living.relaxation(tk, moving)
    return PlannedLoad(tk=tk, wrench=wrench, load=load, baseline_n=baseline, boost=LIFT_OFF_OVERSHOOT * _lift_off(ta, ph))


def _grip_target(planned: PlannedLoad, plan, pol, ph, releases: bool, control: str, spot=None) -> tuple:
    """How hard each digit aims to press on every control tick of ``planned``, the per-finger
    nominal forces and unit presses (object frame) it scales, and the digits' slope: ``(target
    (N, K), f_nom (N, K, 3), press (K, K, 3), slope (N,))``.

    Under ``control`` "per-digit" the digits press for their own loads, the grasp as a whole at the
    person's margin (raised around lift-off, :func:`_lift_off`; :meth:`GripPolicy.grasp_hold`),
    each for at least part of its nearby peak load (:func:`load_envelope`), the thumb at least the
    baseline before the load comes on. Under "whole-hand" only the grasp's squeeze (column 0) is
    set: the sum of the baseline (relaxing in holds), the grip at which every digit presses with
    min_finger_force_n without load, and the grip the load's slip limit needs
    (:meth:`GripPolicy.whole_hand`). ``spot``: the contact points to plan for, (K, 3) [m]; None:
    the plan's.
    """
    tk = planned.tk
    f_nom, press = pol.nominal_and_compressions(planned.wrench, plan.spot if spot is None else spot, plan.normal_in,
                                                plan.active)
    if control == "per-digit":
        # the baseline is the grip before the load comes on (the preload, Johansson & Westling 1984):
        # a lower bound on the thumb that fades as the load comes onto the hand
        target, slope = pol.grasp_hold(f_nom, press, plan.normal_in, plan.active, planned.baseline_n * (1.0 - planned.load),
                                       boost=planned.boost, held_load=load_envelope(f_nom, plan.normal_in, tk))
    else:
        grip_slip, grip_floor = pol.whole_hand(f_nom, press[0], plan.normal_in, plan.active)
        target = np.zeros((len(tk), len(plan.active)))
        target[:, 0] = planned.baseline_n + grip_floor + grip_slip
        slope = np.full(len(tk), pol.slip_slope)
    ramp = _mj((tk - ph.reach_end) / (ph.close_end - ph.reach_end))
    closing = tk < ph.close_end
    target[closing] = 0.0
    target[closing, 0] = pol.baseline_grip_n * ramp[closing]
    if releases:
        fade = 1 - _mj((tk - ph.unload_end) / max(ph.open_end - ph.unload_end, 1e-9))
        opening = tk >= ph.unload_end
        target[opening] = 0.0
        target[opening, 0] = pol.baseline_grip_n * fade[opening]
    return target, f_nom, press, slope


def load_envelope(f_nom: np.ndarray, normals_in: np.ndarray, t: np.ndarray) -> np.ndarray:
    """The tangential load each digit is pressed for at least: :data:`ENVELOPE_FRACTION` of the
    largest planned load it carries within :data:`ENVELOPE_S` before or after, (N, K) [N].

    In cyclic movements the grip follows the load in phase but falls less than the load at its
    minima, where the grip-load ratio is highest (Flanagan & Wing 1993, Exp. Brain Res. 95; 1995):
    people do not relax a digit to nothing between the load's peaks."""
    n = np.einsum("nkd,kd->nk", f_nom, normals_in)
    tang = f_nom - n[..., None] * normals_in
    load = np.sqrt(np.einsum("nkd,nkd->nk", tang, tang))
    if len(t) < 2:
        return ENVELOPE_FRACTION * load
    half = max(1, int(round(ENVELOPE_S / (t[1] - t[0]))))
    return ENVELOPE_FRACTION * running_max(load, half)


def _lift_off(t: np.ndarray, ph) -> np.ndarray:
    """1 while the load moves onto the hand and for LIFT_OFF_HOLD_S after lift-off, then decaying
    with LIFT_OFF_DECAY_S; 0 before the load phase."""
    after = np.exp(-np.maximum(t - ph.load_end - LIFT_OFF_HOLD_S, 0.0) / LIFT_OFF_DECAY_S)
    return np.where(t < ph.close_end, 0.0, after)


def norm_rows(v: np.ndarray) -> np.ndarray:
    """Euclidean norm of each row of (N, 3)."""
    return np.sqrt(np.einsum("ni,ni->n", v, v))


def _mj(s: np.ndarray) -> np.ndarray:
    s = np.clip(s, 0.0, 1.0)
    return s * s * s * (10 - 15 * s + 6 * s * s)


def _rot(quat: np.ndarray) -> np.ndarray:
    R = np.zeros(9)
    mujoco.mju_quat2Mat(R, np.asarray(quat, dtype=float))
    return R.reshape(3, 3)
