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

Opposition across the box's length (171 mm), the hand turned a quarter turn about the vertical, is
not a family: the model hand cannot make it (with the hand turned, the planned pads ended 13-17 mm
short even for 205 mm hands; the thumb's reach from above is too short).

Within a family the spots are drawn, all uniformly (the ranges are choices that keep every pad
on its face): neighbouring fingers lie a pad breadth apart plus a gap of up to
:data:`FINGER_GAP_M`, each finger pad's height on the face is within :data:`PAD_HEIGHT_M`, and the
thumb faces the fingers' centre (their mean position along the row and in height), so that the
fingers' resultant is opposite the thumb; that grip axis passes within :data:`ROW_CENTRE_M` of the
box's centre of mass. People place their digits by an object's centre of mass where they can
predict it (Lukos, Ansuini & Santello 2007, J. Neurosci. 27), so that the load needs no torque
about the grip axis; the box's is at its centre. (Grasps off the centre of mass, as the named
grasps are by 10-15 mm, must hold that torque with a couple of the fingers' tangential forces,
which the grip must squeeze against: docs/findings.md, "How hard the simulated people squeeze".)
"""

from __future__ import annotations

import numpy as np

_DIGITS = {"width-four": ("index", "middle", "ring"), "width-five": ("index", "middle", "ring", "little"),
           "width-tripod": ("index", "middle")}
FAMILIES = tuple(_DIGITS)
"""The grasp families a drawn grasp comes from (with the fingers each opposes to the thumb)."""
ROW_CENTRE_M = 0.005
"""Half-range of the grip axis's offset from the box's centre along the face, [m] (a choice: the
grasp's scatter about the centre of mass)."""
FINGER_GAP_M = (0.0, 0.004)
"""Range of the gap between neighbouring pads along the row, [m]."""
PAD_HEIGHT_M = (-0.010, 0.008)
"""Range of a finger pad's height on its face, from the box's mid-height, [m] (the box is 60 mm tall)."""


def draw_candidate(rng: np.random.Generator, index: int, hand, half_extents) -> dict:
    """One candidate grasp, in ``grasps.yaml``'s form.

    Args:
        rng: The grasp's generator (seeded with its index; each call draws the next candidate).
        index: The grasp's index (its name is ``d<index>-<family>``).
        hand: The person's ``fsv.HandModel`` (its pad radii space the fingers).
        half_extents: The box's half sizes, (3,), [m].

    Returns:
        A grasp spec: ``name``, ``family``, ``palm_x`` (the palm centre's offset along the box's
        x axis: the fingers' row centre) and ``spots`` (face and point per digit, object frame).
    """
    family = FAMILIES[int(rng.integers(len(FAMILIES)))]
    fingers = _DIGITS[family]
    radius = {f: float(hand.fingertip_radius[hand.finger_names.index(f)]) for f in ("thumb",) + fingers}
    centre = float(rng.uniform(-ROW_CENTRE_M, ROW_CENTRE_M))
    row = [0.0]
    for a, b in zip(fingers[:-1], fingers[1:]):
        row.append(row[-1] + radius[a] + radius[b] + float(rng.uniform(*FINGER_GAP_M)))
    row = np.array(row) - np.mean(row) + centre  # along the box's x: the index most radial (-x)
    heights = rng.uniform(*PAD_HEIGHT_M, size=len(fingers))
    hy = float(half_extents[1])
    spots = {"thumb": {"face": "-y", "point": [float(np.mean(row)), -hy, float(np.mean(heights))]}}
    for f, x, z in zip(fingers, row, heights):
        spots[f] = {"face": "+y", "point": [float(x), hy, float(z)]}
    return {"name": f"d{index}-{family}", "family": family, "palm_x": float(np.mean(row)), "spots": spots}
