"""How far the skin is from the hand's primitives: in its bind pose, and in depth.

:func:`collision_gap` measures the skin against the colliding primitives it is built around (in the
simulation's world, where contacts act); :func:`hand_depth_difference` compares two renders of the
same frames, one of the skin and one of a method's hand model, over the pixels where both show the
hand, and counts the pixels where only one does (the silhouettes differ): the mismatch a tracker
meets. Measurements, not the world: the world's code never imports this module.
"""

from __future__ import annotations

import numpy as np

from benchmark.camera.scene import LABEL_PALM
from benchmark.errors import BenchmarkError
from benchmark.world.skin import Skin, skin_of
from fsv import HandModel
from fsv.track.capsules import closest_on_capsules


def hand_depth_difference(skin_depth, skin_labels, model_depth, model_labels) -> dict:
    """Depth of the skin minus depth of the model, over hand pixels.

    Args:
        skin_depth, model_depth: Exact depth, (T, H, W) [m] (0 where nothing is drawn).
        skin_labels, model_labels: Label images, (T, H, W) uint8 (9 and up: the hand).

    Returns:
        ``{"median_mm", "median_abs_mm", "p90_abs_mm"}`` over pixels that are hand in both, and
        ``"silhouette_frac"``: the pixels that are hand in only one, over those that are hand in either.
    """
    a, b = np.asarray(skin_depth, dtype=np.float64), np.asarray(model_depth, dtype=np.float64)
    if a.shape != b.shape or np.shape(skin_labels) != a.shape or np.shape(model_labels) != a.shape:
        raise BenchmarkError(f"depth and labels must share one shape, got {a.shape}, {b.shape}, "
                             f"{np.shape(skin_labels)}, {np.shape(model_labels)}")
    hand_a, hand_b = np.asarray(skin_labels) >= LABEL_PALM, np.asarray(model_labels) >= LABEL_PALM
    both = hand_a & hand_b
    if not both.any():
        raise BenchmarkError("no pixel shows the hand in both renders")
    d = (a - b)[both] * 1e3
    either = hand_a | hand_b
    return {"median_mm": float(np.median(d)), "median_abs_mm": float(np.median(np.abs(d))),
            "p90_abs_mm": float(np.percentile(np.abs(d), 90)),
            "silhouette_frac": float(np.sum(hand_a ^ hand_b) / np.sum(either))}


def collision_gap(hand: HandModel, skin: Skin | None = None) -> dict:
    """How far the skin lies from the hand's colliding primitives, in the bind pose.

    For each skin vertex of a pulp's palmar half below the pad's centre, and of the palm's palmar
    face, the signed distance to the nearest colliding primitive's surface (positive outside).

    Returns:
        ``{"pulp_mm": (median |gap|, max |gap|), "palm_mm": (median |gap|, max |gap|), "skin_mm":
        (median, 90th percentile) of every vertex's distance to the nearest primitive of its segment}``.
    """

    skin = skin_of(hand) if skin is None else skin
    geom_seg = np.asarray(hand.geom_segment)
    fromto = np.asarray(hand.geom_fromto)
    radius = np.asarray(hand.geom_radius)

    def distance(points, geoms):  # signed distance to the nearest of these primitives' surfaces
        return closest_on_capsules(points, fromto[geoms, :3], fromto[geoms, 3:], radius[geoms])[1]

    pulp_gap = []
    for k, seg in enumerate(hand.fingertip_segment):
        v = skin.local[skin.segment == seg]
        centre = np.asarray(hand.fingertip_offset[k], dtype=float)
        below = (v[:, 2] < -0.5 * radius.max()) & (np.abs(v[:, 1] - centre[1]) < 0.35 * hand.fingertip_radius[k])
        pulp_gap.append(np.linalg.norm(v[below] - centre, axis=1) - hand.fingertip_radius[k])
    pulp_gap = np.abs(np.concatenate(pulp_gap))
    palm_v = skin.local[(skin.segment == 0)]
    palm_g = np.flatnonzero(geom_seg == 0)
    d = distance(palm_v, palm_g)
    meta_line = palm_v[:, 2] < -0.8 * radius[palm_g].min()
    palm_gap = np.abs(d[meta_line])
    every = np.empty(skin.vertices)
    for s in range(len(hand.segment_names)):
        sel = skin.segment == s
        every[sel] = distance(skin.local[sel], np.flatnonzero(geom_seg == s))
    mm = lambda x, q: float(np.percentile(x, q) * 1e3)  # noqa: E731
    return {"pulp_mm": (mm(pulp_gap, 50), mm(pulp_gap, 100)), "palm_mm": (mm(palm_gap, 50), mm(palm_gap, 100)),
            "skin_mm": (mm(every, 50), mm(every, 90))}
