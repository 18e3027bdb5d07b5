"""A person's hand anatomy: the template of ``sim_assets/hand.yaml`` reshaped per digit and phalanx.

An :class:`Anatomy` stretches the template hand (``hand.yaml``, a hand 190 mm long and 85 mm broad)
along the hand (palm lengths, phalanx lengths) by ``length_scale`` and across it (palm widths,
thicknesses, every radius) by ``breadth_scale``, then each digit's length, each phalanx's length and
each digit's girth by its own factor. :func:`draw_anatomy` draws one from a generator:

- **Hand length and breadth** from the adult distributions of Pheasant & Haslegrave (2006),
  *Bodyspace*, 3rd ed., British adults aged 19-65 (:data:`HAND_SIZE`): sex first (one half each),
  then length and breadth as a bivariate normal with correlation :data:`LENGTH_BREADTH_CORRELATION`,
  each cut at :data:`TRUNCATE_SD` standard deviations (redrawn beyond).
- **Digit lengths**: one factor per digit of standard deviation :data:`DIGIT_LENGTH_SD`, which gives
  a second-to-fourth digit ratio (2D:4D) of standard deviation about 0.035, the spread Manning et
  al. (1998, Hum. Reprod. 13) report (0.03-0.04).
- **Phalanx lengths**: one factor per phalanx of standard deviation :data:`PHALANX_LENGTH_SD` (a
  choice, of the order of the spread of phalanx-to-hand-length ratios in Buryanov & Kotiuk 2010,
  the source of the template's proportions).
- **Digit girth**: one factor per digit of standard deviation :data:`DIGIT_RADIUS_SD` (a choice,
  of the order of the coefficients of variation of finger breadths and depths in Vergara et al.
  2018, Int. J. Ind. Ergon. 68, about 5-7 %, less the part explained by hand breadth).

The hand length that results (wrist crease to the middle fingertip) is the drawn one exactly:
``length_scale`` is solved for it after the middle digit's factors are drawn (:func:`sized`). The
named users of ``users.yaml`` have proportions drawn the same way (:func:`draw_proportions`, from
their ``anatomy_seed``) at the size their ``hand_scale`` gives the template.
"""

from __future__ import annotations

import functools
import importlib.resources
from dataclasses import dataclass, replace

import numpy as np
import yaml

from benchmark.errors import ScenarioError

TEMPLATE_HAND_LENGTH_M = 0.190
"""Hand length (wrist crease to the middle fingertip) of the template, ``hand.yaml`` at scale 1, [m]."""
TEMPLATE_HAND_BREADTH_M = 0.085
"""Hand breadth (across the metacarpal heads) of the template, [m]."""
DIGITS = 5
"""Thumb, index, middle, ring, little: the order of every per-digit tuple."""
PHALANGES = 3
"""Segments per digit (the thumb's metacarpal counts as its first)."""

HAND_SIZE = {"male": {"length_m": (0.189, 0.010), "breadth_m": (0.087, 0.005)},
             "female": {"length_m": (0.174, 0.009), "breadth_m": (0.076, 0.004)}}
"""Mean and standard deviation of hand length and breadth per sex, [m] (Pheasant & Haslegrave 2006,
British adults 19-65: 5th/50th/95th percentiles 173/189/205 mm and 159/174/189 mm long, 78/87/95 mm
and 69/76/83 mm broad)."""
LENGTH_BREADTH_CORRELATION = 0.6
"""Correlation of hand length and breadth within a sex (a choice: hand surveys report 0.5-0.7)."""
TRUNCATE_SD = 2.5
"""Draws beyond this many standard deviations are redrawn (no 3-sigma giants in a small cohort)."""
DIGIT_LENGTH_SD = 0.025
"""Relative standard deviation of one digit's length beyond the hand's."""
PHALANX_LENGTH_SD = 0.03
"""Relative standard deviation of one phalanx's length beyond its digit's."""
DIGIT_RADIUS_SD = 0.04
"""Relative standard deviation of one digit's girth beyond the hand breadth's."""
FACTOR_RANGE = (0.8, 1.2)
"""Accepted range of every per-digit and per-phalanx factor."""
SCALE_RANGE = (0.5, 2.0)
"""Accepted range of the length and breadth scales."""


@functools.lru_cache(maxsize=None)
def hand_spec() -> dict:
    """The parsed ``sim_assets/hand.yaml``, the template (cached; treat as read-only)."""
    return yaml.safe_load(importlib.resources.files("sim_assets").joinpath("hand.yaml").read_text())


@functools.lru_cache(maxsize=1)
def _middle_lengths() -> tuple:
    finger = next(f for f in hand_spec()["fingers"] if f["name"] == "middle")
    return tuple(float(s["length"]) for s in finger["segments"])


@dataclass(frozen=True)
class Anatomy:
    """A hand's shape relative to the template (every tuple in digit order, thumb first).

    Attributes:
        length_scale: Factor of every length along the hand (palm lengths, phalanx lengths).
        breadth_scale: Factor of every length across the hand (palm widths and thicknesses, radii).
        digit_length: Per digit, a factor of its phalanx lengths, (5,).
        phalanx_length: Per digit and phalanx, a further factor of its length, (5, 3).
        digit_radius: Per digit, a factor of its radii (girth), (5,).
    """

    length_scale: float
    breadth_scale: float
    digit_length: tuple = (1.0,) * DIGITS
    phalanx_length: tuple = ((1.0,) * PHALANGES,) * DIGITS
    digit_radius: tuple = (1.0,) * DIGITS

    def __post_init__(self):
        lo, hi = SCALE_RANGE
        for name in ("length_scale", "breadth_scale"):
            v = getattr(self, name)
            if not (isinstance(v, float) and np.isfinite(v) and lo <= v <= hi):
                raise ScenarioError(f"anatomy {name} must be a float within [{lo}, {hi}], got {v!r}")
        flo, fhi = FACTOR_RANGE
        shapes = {"digit_length": (DIGITS,), "phalanx_length": (DIGITS, PHALANGES), "digit_radius": (DIGITS,)}
        for name, shape in shapes.items():
            v = np.asarray(getattr(self, name), dtype=float)
            if v.shape != shape or not np.all((v >= flo) & (v <= fhi)):
                raise ScenarioError(f"anatomy {name} must be {shape} factors within [{flo}, {fhi}], got {getattr(self, name)!r}")

    @staticmethod
    def template(scale: float = 1.0) -> "Anatomy":
        """The template hand at a uniform size (every factor 1)."""
        return Anatomy(length_scale=float(scale), breadth_scale=float(scale))

    @property
    def hand_length_m(self) -> float:
        """Wrist crease to the middle fingertip, [m] (the palm's part scales with ``length_scale``)."""
        k = 2  # the middle digit; its factors lengthen the hand by this much at length scale 1
        extra = sum(m * (self.digit_length[k] * f - 1.0) for m, f in zip(_middle_lengths(), self.phalanx_length[k]))
        return self.length_scale * (TEMPLATE_HAND_LENGTH_M + extra)

    @property
    def hand_breadth_m(self) -> float:
        """Across the metacarpal heads, [m]."""
        return self.breadth_scale * TEMPLATE_HAND_BREADTH_M

    def record(self) -> dict:
        """JSON of the anatomy: the two scales, the factors and the hand's length and breadth."""
        return {"hand_length_m": float(self.hand_length_m), "hand_breadth_m": float(self.hand_breadth_m),
                "length_scale": float(self.length_scale), "breadth_scale": float(self.breadth_scale),
                "digit_length": [float(v) for v in self.digit_length],
                "phalanx_length": [[float(v) for v in row] for row in self.phalanx_length],
                "digit_radius": [float(v) for v in self.digit_radius]}


def _truncated_normal(rng: np.random.Generator, size) -> np.ndarray:
    """Standard normal draws, each redrawn until within :data:`TRUNCATE_SD`."""
    z = rng.standard_normal(size)
    while np.any(bad := np.abs(z) > TRUNCATE_SD):
        z[bad] = rng.standard_normal(int(bad.sum()))
    return z


def draw_anatomy(rng: np.random.Generator, sex: str) -> Anatomy:
    """Draws a hand of one sex from the module's distributions.

    Args:
        rng: The generator to draw from (the person's).
        sex: "male" or "female" (a key of :data:`HAND_SIZE`).

    Returns:
        The :class:`Anatomy`; its ``hand_length_m`` and ``hand_breadth_m`` are the drawn ones.

    Raises:
        ScenarioError: If ``sex`` is not a key of :data:`HAND_SIZE`.
    """
    if sex not in HAND_SIZE:
        raise ScenarioError(f"sex {sex!r}: accepted: {', '.join(HAND_SIZE)}")
    (ml, sl), (mb, sb) = HAND_SIZE[sex]["length_m"], HAND_SIZE[sex]["breadth_m"]
    zl, zo = _truncated_normal(rng, 2)
    r = LENGTH_BREADTH_CORRELATION
    zb = r * zl + np.sqrt(1.0 - r * r) * zo
    length, breadth = ml + sl * zl, mb + sb * np.clip(zb, -TRUNCATE_SD, TRUNCATE_SD)
    return sized(draw_proportions(rng), float(length), float(breadth))


def draw_proportions(rng: np.random.Generator) -> Anatomy:
    """Draws a hand's proportions: the per-digit length and girth and per-phalanx length factors of
    the module's distributions, at the template's size (both scales 1)."""
    digit = 1.0 + DIGIT_LENGTH_SD * _truncated_normal(rng, DIGITS)
    phalanx = 1.0 + PHALANX_LENGTH_SD * _truncated_normal(rng, (DIGITS, PHALANGES))
    girth = 1.0 + DIGIT_RADIUS_SD * _truncated_normal(rng, DIGITS)
    return Anatomy(length_scale=1.0, breadth_scale=1.0, digit_length=tuple(float(v) for v in digit),
                   phalanx_length=tuple(tuple(float(v) for v in row) for row in phalanx),
                   digit_radius=tuple(float(v) for v in girth))


def sized(shape: Anatomy, length_m: float, breadth_m: float) -> Anatomy:
    """``shape``'s proportions at a hand length and breadth, [m] (the length scale solved from
    :attr:`Anatomy.hand_length_m`, which is linear in it)."""
    shape = replace(shape, length_scale=1.0, breadth_scale=float(breadth_m / TEMPLATE_HAND_BREADTH_M))
    return replace(shape, length_scale=float(length_m / shape.hand_length_m))
