"""The paper's sample rules and the decomposition settings behind training targets and their scores.

Used by the learned-force scores (:mod:`benchmark.scores.learned`) and by dataset generation
(:mod:`benchmark.paper.dataset`, a floor above), without the dataset's file machinery (pandas, pyarrow).
"""

from __future__ import annotations

import numpy as np

from fsv import Contacts, Kinematics
from fsv.forces import ForceSettings


def sample_mask(kin: Kinematics, con: Contacts, feats, truth, min_fingers: int = 2, max_gap_n: float = 1.5):
    """The paper's sample rule, per frame.

    Args:
        kin, con: The kinematics and contacts behind ``feats``.
        feats: :class:`fsv.features.Features` (its ``net_force`` is the vision net force, object frame).
        truth: The episode's truth (its finger forces are the tactile net force).
        min_fingers: Fewest fingers in contact for an internal force to exist.
        max_gap_n: Largest accepted |vision - tactile net force|, [N].

    Returns:
        ``(usable, keep, gap)``: frames with valid kinematics and enough fingers, shape (T,);
        those of them whose net forces agree within ``max_gap_n``, shape (T,); and the gap, (T,), [N].
    """
    tactile_net = np.sum(np.asarray(truth.contact_force), axis=1)  # object frame, like feats.net_force
    gap = np.linalg.norm(feats.net_force - tactile_net, axis=1)
    usable = kin.valid & (con.active.sum(axis=1) >= min_fingers)
    return usable, usable & (gap <= max_gap_n), gap


DATASET_FORCE_SETTINGS = ForceSettings(static_retry=False, feasibility_tol=0.0, repair_gap_m=0.0)
"""Settings of the decomposition that makes the training targets: a frame whose program with the
tracked contacts and sliding flags is infeasible is dropped as unsolved, without the static-friction
retry, the contacts added from nearby fingers or the feasibility tolerance of the method's own
programs: a training sample's features and targets come from the same contacts."""

MAX_EXCESS_N = 1.5
"""Default of the plausibility rule (:func:`nominal_excess_n`), [N]: the paper's 1.5 N threshold."""


def nominal_excess_n(nominal_normal, measured, active) -> np.ndarray:
    """How far vision's nominal forces exceed the tactile readings, per frame (a plausibility rule).

    The nominal forces are the least forces that explain the motion (eq. 4-6; here the nominal part of
    the decomposition, eq. 9), and the paper found them individually below the tactile readings
    (§4.2, Fig. 5): people grip harder than the minimum. A finger whose nominal normal force
    exceeds its reading (0 where its sensor reads nothing) by more than a threshold means vision's
    contacts cannot be right at that frame (e.g. a point on the wrong side of the centre of mass,
    or a finger in contact for vision but not for touch). This is our reading of the paper's
    "samples where FSV or tactile sensors are not reliable"; its 1.5 N rule on the net forces
    (:func:`sample_mask`) only tests the kinematics here. Training and scoring drop frames above
    ``MAX_EXCESS_N`` unless told otherwise, and say so.

    Args:
        nominal_normal: Nominal normal force per finger, shape (N, K), [N].
        measured: Tactile readings, shape (N, K), [N]; NaN or 0 where the sensor reads nothing.
        active: Finger in contact for vision, shape (N, K).

    Returns:
        max over vision's fingers of (nominal - reading), shape (N,), [N]; -inf without fingers.
    """
    f_nom, meas = np.asarray(nominal_normal, float), np.nan_to_num(np.asarray(measured, float), nan=0.0)
    return np.max(np.where(np.asarray(active, bool), f_nom - meas, -np.inf), axis=1)


def take_kinematics(kin: Kinematics, idx) -> Kinematics:
    """The frames ``idx`` of kinematics."""
    return Kinematics(kin.t[idx], kin.pos[idx], kin.rot[idx], kin.vel[idx], kin.acc[idx], kin.omega[idx],
                      kin.alpha[idx], kin.valid[idx], kin.method, kin.delay_s)


def take_contacts(con: Contacts, idx) -> Contacts:
    """The frames ``idx`` of contacts."""
    return Contacts(con.finger_names, con.active[idx], con.sliding[idx], con.point[idx], con.normal[idx], con.slide_dir[idx])
