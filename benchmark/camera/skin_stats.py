"""How far the rendered skin is from the hand's primitives in depth: the mismatch a tracker meets.

:func:`hand_depth_difference` compares two renders of the same frames, one of the skin and one of
the primitives (the model a method is given under exact knowledge), over the pixels where both
show the hand, and counts the pixels where only one does (the silhouettes differ).
"""

from __future__ import annotations

import numpy as np

from benchmark.camera.scene import LABEL_PALM
from benchmark.errors import BenchmarkError


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
