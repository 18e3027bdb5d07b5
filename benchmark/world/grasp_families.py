"""Drawn grasps: candidate grasps of several families, for ``--grasp N`` beyond the named ones.

Grasps 0-3 are ``sim_assets/grasps.yaml``'s (the paper's family: the thumb on the -y face, the
fingers on the +y face). Grasp N >= 4 is drawn for the scenario's person from a generator seeded
with N (:func:`draw_candidate`, one candidate per call); ``benchmark.world.grasp_plan`` fits each
candidate to the person's hand and redraws, from the same generator, until one is feasible, so
grasp N is a grasp that this person's hand can make. The families (:data:`FAMILIES`, drawn with
equal probability):

- ``width-four``: thumb opposing index, middle and ring across the box's width (111 mm), the
  paper's family;
- ``width-five``: the same with the little finger;
- ``width-tripod``: a three-digit pinch, thumb against index and middle.

Opposition across the box's length (171 mm), the hand turned a quarter turn about the vertical
(``length-four``, drawn here with ``palm_yaw``), is not drawn: the model hand cannot make it (the
planned pads end 13-17 mm short even for 205 mm hands: the thumb's reach from above is too short),
so every candidate would be redrawn. It stays in :data:`LENGTH_FAMILIES` for a hand that can.

Within a family the spots are drawn, all uniformly (the ranges are choices that keep every pad
on its face and reproduce the named grasps' spread): the fingers' row is centred anywhere within
:data:`ROW_CENTRE_M` of the face's centre, neighbouring fingers lie a pad breadth apart plus a gap
of up to :data:`FINGER_GAP_M`, each pad's height on the face is within :data:`PAD_HEIGHT_M`, and
the thumb faces the point between the index and the middle finger, shifted by up to
:data:`THUMB_SHIFT_M` along the row.
"""

from __future__ import annotations

import math

import numpy as np

FAMILIES = ("width-four", "width-five", "width-tripod")
"""The grasp families a drawn grasp comes from."""
LENGTH_FAMILIES = ("length-four",)
"""Families this module can draw (``draw_candidate(..., family=...)``) that the model hand cannot make."""
_DIGITS = {"width-four": ("index", "middle", "ring"), "width-five": ("index", "middle", "ring", "little"),
           "width-tripod": ("index", "middle"), "length-four": ("index", "middle", "ring")}
ROW_CENTRE_M = {"width": 0.030, "length": 0.010}
"""Half-range of the fingers' row centre along the face, per opposition axis, [m]."""
FINGER_GAP_M = (0.0, 0.004)
"""Range of the gap between neighbouring pads along the row, [m]."""
PAD_HEIGHT_M = (-0.010, 0.008)
"""Range of a pad's height on its face, from the box's mid-height, [m] (the box is 60 mm tall)."""
THUMB_SHIFT_M = 0.010
"""Half-range of the thumb's shift along the row, [m]."""


def draw_candidate(rng: np.random.Generator, index: int, hand, half_extents, family: str | None = None) -> dict:
    """One candidate grasp, in ``grasps.yaml``'s form plus ``family`` and ``palm_yaw``.

    Args:
        rng: The grasp's generator (seeded with its index; each call draws the next candidate).
        index: The grasp's index (its name is ``d<index>-<family>``).
        hand: The person's ``fsv.HandModel`` (its pad radii space the fingers).
        half_extents: The box's half sizes, (3,), [m].
        family: Draw from this family (of :data:`FAMILIES` or :data:`LENGTH_FAMILIES`); None: the
            family is drawn first, uniformly over :data:`FAMILIES`.

    Returns:
        A grasp spec: ``name``, ``family``, ``palm_x`` (the palm's offset along the fingers' row,
        in the hand-aligned frame), ``palm_yaw`` [rad] and ``spots`` (face and point per digit,
        object frame).
    """
    if family is None:
        family = FAMILIES[int(rng.integers(len(FAMILIES)))]
    elif family not in FAMILIES + LENGTH_FAMILIES:
        raise ValueError(f"grasp family {family!r}: accepted: {', '.join(FAMILIES + LENGTH_FAMILIES)}")
    axis = family.split("-")[0]
    fingers = _DIGITS[family]
    radius = {f: float(hand.fingertip_radius[hand.finger_names.index(f)]) for f in ("thumb",) + fingers}
    centre = float(rng.uniform(-ROW_CENTRE_M[axis], ROW_CENTRE_M[axis]))
    row = [0.0]
    for a, b in zip(fingers[:-1], fingers[1:]):
        row.append(row[-1] + radius[a] + radius[b] + float(rng.uniform(*FINGER_GAP_M)))
    row = np.array(row) - np.mean(row) + centre  # in the hand-aligned frame: index most radial (-x)
    heights = rng.uniform(*PAD_HEIGHT_M, size=len(fingers) + 1)
    thumb_row = 0.5 * (row[0] + row[1]) + float(rng.uniform(-THUMB_SHIFT_M, THUMB_SHIFT_M))
    hx, hy, _ = (float(v) for v in half_extents)
    spots = {}
    if axis == "width":  # hand frame = object frame: row along x, thumb on -y, fingers on +y
        spots["thumb"] = {"face": "-y", "point": [thumb_row, -hy, float(heights[0])]}
        for f, x, z in zip(fingers, row, heights[1:]):
            spots[f] = {"face": "+y", "point": [float(x), hy, float(z)]}
        yaw = 0.0
    else:  # a quarter turn: the hand's +y along the object's +x, its +x along the object's -y
        spots["thumb"] = {"face": "-x", "point": [-hx, -thumb_row, float(heights[0])]}
        for f, x, z in zip(fingers, row, heights[1:]):
            spots[f] = {"face": "+x", "point": [hx, -float(x), float(z)]}
        yaw = -math.pi / 2
    return {"name": f"d{index}-{family}", "family": family, "palm_x": float(np.mean(row)), "palm_yaw": yaw,
            "spots": spots}
