"""Checks that a written figure shows something: a PNG of the expected shape with its plotted colours."""

from __future__ import annotations

import numpy as np
from PIL import Image


def colour_share(path, rgb, tol: int = 40) -> float:
    """Fraction of the image's pixels within ``tol`` (per channel) of the colour ``rgb`` (0-255)."""
    img = np.asarray(Image.open(path).convert("RGB")).astype(int)
    return float(np.mean(np.all(np.abs(img - np.array(rgb)) <= tol, axis=-1)))


def assert_figure(path, *, colours: dict, min_width: int = 400, min_height: int = 300, min_share: float = 2e-4):
    """Asserts that ``path`` is a PNG of at least the given size in which every named colour covers at
    least ``min_share`` of the pixels (lines and markers actually drawn, not an empty axes)."""
    with open(path, "rb") as fh:
        assert fh.read(8) == b"\x89PNG\r\n\x1a\n", f"{path} is not a PNG"
    w, h = Image.open(path).size
    assert w >= min_width and h >= min_height, (w, h)
    missing = {name: colour_share(path, rgb) for name, rgb in colours.items() if colour_share(path, rgb) < min_share}
    assert not missing, f"{path}: colours not drawn (share of pixels): {missing}"
