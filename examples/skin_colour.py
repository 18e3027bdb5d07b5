"""A method that reads the colour stream: the reference, with each contact confirmed by skin colour.

    fsv-bench export --suite smoke --streams depth,colour --out runs/smoke-colour-inputs
    python examples/skin_colour.py runs/smoke-colour-inputs runs/smoke-colour-estimates
    fsv-bench score --suite smoke --estimates runs/smoke-colour-estimates --out runs/smoke-colour-scores

or in process: ``fsv-bench eval --suite smoke --method examples/skin_colour.py:method`` (the method
declares ``streams = ("depth", "colour")``, so the benchmark renders the colour for it).

The tracker is the reference's (depth only); afterwards each finger the tracker put in contact keeps
its contact only where the colour image shows skin around the contact point: the point, carried by
the tracked box pose into the world and projected through the colour camera's own calibration,
must have skin-coloured pixels within :data:`SEARCH_PX` pixels. Skin is the classic fixed rule in
YCbCr (Chai & Ngan 1999, "Face segmentation using skin-color map in videophone applications",
IEEE TCSVT 9(4): 77 <= Cb <= 127 and 133 <= Cr <= 173), known to miss darker and very light skin
under coloured light: an example of what a colour method meets, not a recommended detector.
"""

from __future__ import annotations

import argparse
import dataclasses
import pathlib
import sys

import numpy as np

from fsv.method import make_method
from fsv.method.reference import ReferenceTracker

SEARCH_PX = 6
"""Half-width of the window around a contact's pixel that must hold skin, [px] (a fingertip's pad
is about 15 mm across: about 15-25 px at 0.5 m in a 640 x 480 image)."""
MIN_SKIN_PIXELS = 3
"""Skin pixels the window must hold to confirm a contact."""


def skin_mask(rgb: np.ndarray) -> np.ndarray:
    """Chai & Ngan's skin rule on sRGB images.

    Args:
        rgb: Images (..., H, W, 3) uint8.

    Returns:
        (..., H, W) bool: True where Cb and Cr (ITU-R BT.601, full range) lie in the skin box.
    """
    x = np.asarray(rgb, dtype=np.float64)
    r, g, b = x[..., 0], x[..., 1], x[..., 2]
    cb = 128.0 - 0.168736 * r - 0.331264 * g + 0.5 * b
    cr = 128.0 + 0.5 * r - 0.418688 * g - 0.081312 * b
    return (cb >= 77) & (cb <= 127) & (cr >= 133) & (cr <= 173)


def project(points_world: np.ndarray, calib) -> np.ndarray:
    """Pixels (..., 2) of world points through an ``fsv.Calibration`` (OpenCV, zero distortion)."""
    R, t = calib.T_world_cam[:3, :3], calib.T_world_cam[:3, 3]
    p = np.einsum("ji,...j->...i", R, points_world - t)  # R^T (p - t): camera frame
    z = np.where(p[..., 2] > 1e-6, p[..., 2], np.nan)
    return np.stack([calib.K[0, 0] * p[..., 0] / z + calib.K[0, 2], calib.K[1, 1] * p[..., 1] / z + calib.K[1, 2]], -1)


@dataclasses.dataclass(frozen=True)
class SkinConfirmedTracker:
    """The reference tracker, its contacts kept only where the colour shows skin at them."""

    inner: ReferenceTracker = dataclasses.field(default_factory=ReferenceTracker)
    name: str = "reference tracker, contacts confirmed by skin colour"
    streams: tuple = ("depth", "colour")

    def __call__(self, inputs, rng):
        tracking = self.inner(inputs, rng)
        if inputs.colour is None:
            raise ValueError("this tracker reads the colour stream: export or evaluate with --streams depth,colour")
        c, box = tracking.contacts, tracking.box
        world = np.einsum("tij,tkj->tki", box.rot, c.point) + box.pos[:, None, :]
        uv = np.rint(project(world, inputs.colour.calib))
        H, W = inputs.colour.rgb.shape[1:3]
        active = np.array(c.active)
        for k, f in zip(*np.nonzero(active)):
            u, v = uv[k, f]
            if not (np.isfinite(u) and np.isfinite(v)):
                continue
            u0, u1 = int(max(u - SEARCH_PX, 0)), int(min(u + SEARCH_PX + 1, W))
            v0, v1 = int(max(v - SEARCH_PX, 0)), int(min(v + SEARCH_PX + 1, H))
            if u0 >= u1 or v0 >= v1 or skin_mask(inputs.colour.rgb[k, v0:v1, u0:u1]).sum() < MIN_SKIN_PIXELS:
                active[k, f] = False
        contacts = dataclasses.replace(c, active=active, sliding=np.asarray(c.sliding) & active)
        return dataclasses.replace(tracking, contacts=contacts)


method = make_method(tracker=SkinConfirmedTracker())
"""The whole method: the reference with the skin-confirmed tracker (``--method examples/skin_colour.py:method``)."""


def main(argv=None) -> int:
    sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
    from estimates_from_files import write_estimates  # lazy: after sys.path has its folder

    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("inputs", help="folder written by fsv-bench export --streams depth,colour")
    p.add_argument("out", help="folder for the estimates files")
    args = p.parse_args(argv)
    files = write_estimates(args.inputs, args.out, method, SkinConfirmedTracker.name)
    print(f"{len(files)} estimates files in {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
