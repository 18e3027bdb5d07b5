"""People: the named cohort of ``sim_assets/users.yaml`` and a population drawn around it.

User 0-4 are the named cohort (``users.yaml``): Table 1 and Table 2 keep their protocols on them.
User N >= 5 is a person drawn from a generator seeded with N (the same person for every scenario
that names N): sex, then a hand (:func:`benchmark.world.anatomy.draw_anatomy`), then a grip style,
each quantity independently from the spreads below:

- **safety margin** (:data:`SAFETY_MARGIN`): the relative safety margin (G - G_slip) / G, the part
  of the grip force G above the slip limit G_slip, log-normal around 25 %: Johansson & Westling
  (1984, Exp. Brain Res. 56) and Westling & Johansson (1984, Exp. Brain Res. 53) measured 10-40 %
  for fingertip grips, more for cautious and older people (Cole 1991, J. Neurophysiol. 65);
- **baseline grip** (:data:`BASELINE_GRIP_N`): the squeeze kept without load, uniform;
- **anticipation** (:data:`ANTICIPATION_S`): how far the grip leads the load, uniform; the grip
  leads or coincides with the load in self-paced moves (Flanagan & Wing 1995, Exp. Brain Res. 105);
- **response** (:data:`RESPONSE_S`): the grip's first-order time constant, uniform;
- **finger shares** (:data:`FINGER_SHARE_MEAN`, :data:`FINGER_SHARE_CONCENTRATION`): a Dirichlet
  around Radwin et al.'s (1992, Ergonomics 35) index/middle/ring/little shares of 33/33/17/15 %;
- **finger stiffness** (:data:`STIFFNESS_NM_PER_RAD`): the posture PD gain, uniform.

Ranges without a citation are choices that span the named cohort. A drawn person has no shipped
grip calibration: the method meets them blind.
"""

from __future__ import annotations

import functools
import importlib.resources

import numpy as np
import yaml

from benchmark.world.anatomy import (
    TEMPLATE_HAND_BREADTH_M,
    TEMPLATE_HAND_LENGTH_M,
    draw_anatomy,
    draw_proportions,
    sized,
)

SAFETY_MARGIN = (0.25, 0.40, (0.10, 0.60))
"""Median, log-standard deviation and the range it is clipped to of the relative safety margin (a
fraction of the grip force): the median is the middle of Johansson & Westling's 10-40 %; the spread
(95 % of people within 11-55 %) and the upper clip (a grip 2.5 times the slip limit) are choices that
keep a cautious tail."""
BASELINE_GRIP_N = (0.5, 3.5)
"""Range of the baseline grip, [N]."""
ANTICIPATION_S = (0.0, 0.10)
"""Range of the grip's lead over the load, [s]."""
RESPONSE_S = (0.04, 0.09)
"""Range of the grip's response time constant, [s]."""
FINGER_SHARE_MEAN = {"index": 0.33, "middle": 0.33, "ring": 0.17, "little": 0.15}
"""Radwin et al. (1992): mean share of each finger in the fingers' force (normalised to sum 1)."""
FINGER_SHARE_CONCENTRATION = 100.0
"""Dirichlet concentration of the finger shares (a choice: an index share of 0.34 +- 0.05)."""
STIFFNESS_NM_PER_RAD = (0.4, 0.9)
"""Range of the finger joints' stiffness, [N m/rad]."""
SEXES = ("female", "male")
"""Drawn with equal probability."""


@functools.lru_cache(maxsize=None)
def _named() -> tuple:
    return tuple(yaml.safe_load(importlib.resources.files("sim_assets").joinpath("users.yaml").read_text()))


def users() -> list[dict]:
    """``sim_assets/users.yaml``: the named cohort (hand scale and grip style), in index order."""
    return list(_named())


def named_count() -> int:
    """How many named users ``users.yaml`` holds (users 0 to this minus one)."""
    return len(_named())


@functools.lru_cache(maxsize=256)
def person(user: int) -> dict:
    """User ``user``: the ``users.yaml`` entry or a drawn person, with its ``anatomy``.

    Args:
        user: A non-negative integer.

    Returns:
        A dict with ``name``, ``drawn`` (bool), ``sex`` (None for the named cohort), ``anatomy``
        (an :class:`Anatomy`) and the grip style (``safety_margin``, ``baseline_grip_n``,
        ``anticipation_s``, ``response_s``, ``finger_share``, ``stiffness_nm_per_rad``). Treat
        it as read-only (it is cached).
    """
    user = int(user)
    named = _named()
    if user < len(named):
        entry = dict(named[user])
        scale = float(entry["hand_scale"])
        shape = draw_proportions(np.random.default_rng(np.random.SeedSequence([int(entry["anatomy_seed"]), *b"anatomy"])))
        anatomy = sized(shape, scale * TEMPLATE_HAND_LENGTH_M, scale * TEMPLATE_HAND_BREADTH_M)
        return {**entry, "drawn": False, "sex": None, "anatomy": anatomy}
    rng = np.random.default_rng(np.random.SeedSequence([user, *b"person"]))
    sex = SEXES[int(rng.integers(2))]
    anatomy = draw_anatomy(rng, sex)
    median, log_sd, (lo, hi) = SAFETY_MARGIN
    margin = float(np.clip(median * np.exp(log_sd * rng.standard_normal()), lo, hi))
    fingers = tuple(FINGER_SHARE_MEAN)
    mean = np.array([FINGER_SHARE_MEAN[f] for f in fingers])
    share = rng.dirichlet(FINGER_SHARE_CONCENTRATION * mean / mean.sum())
    return {
        "name": f"p{user}-{sex[0]}", "drawn": True, "sex": sex, "anatomy": anatomy,
        "hand_scale": float(np.sqrt(anatomy.length_scale * anatomy.breadth_scale)),
        "safety_margin": margin,
        "baseline_grip_n": float(rng.uniform(*BASELINE_GRIP_N)),
        "anticipation_s": float(rng.uniform(*ANTICIPATION_S)),
        "response_s": float(rng.uniform(*RESPONSE_S)),
        "finger_share": {f: float(s) for f, s in zip(fingers, share)},
        "stiffness_nm_per_rad": float(rng.uniform(*STIFFNESS_NM_PER_RAD)),
    }


def person_record(user: int) -> dict:
    """JSON of a user: name, whether drawn, sex, anatomy and grip style (for ``summary.json``)."""
    p = person(user)
    out = {k: v for k, v in p.items() if k != "anatomy"}
    out["user"] = int(user)
    out["anatomy"] = p["anatomy"].record()
    return out
