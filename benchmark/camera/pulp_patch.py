"""The flat patch a pressed pulp makes on a face: what the renderer draws, measured on the skin.

:func:`patch_area_m2` presses one fingertip of a skin (in its bind pose) on a flat face below its
pad with a normal force, through the renderer's own kernels (:mod:`benchmark.camera.skin_kernels`),
and measures the area of the skin that lies on the face. It is how the docs and the tests check
that the patch grows with force as a fingertip's does.
"""

from __future__ import annotations

import numpy as np

from benchmark.camera import skin_kernels as sk
from benchmark.errors import BenchmarkError
from benchmark.world.skin import PULP_REACH, Skin, pulp_indentation_m, skin_of
from fsv import HandModel

_FACE_HALF_M = 0.05
"""Half size of the cube whose top face the pulp presses on (larger than any fingertip)."""


def pressed_fingertip(hand: HandModel, finger: int, force_n: float, skin: Skin | None = None, *,
                      flatten: bool = True) -> tuple:
    """One fingertip's skin pressed with a normal force on a face below its pad, in its segment frame.

    The face is the plane ``z = c_z - r`` (c the pad's centre, r its radius; +z dorsal), the box
    below it; the centre of pressure is the pad's lowest point.

    Args:
        flatten: Move what passes through the face onto it, as the renderer does; False leaves the
            pushed pulp passing through (to measure where it crosses the face).

    Returns:
        ``(vertices (V, 3), faces (F, 3), face height)``: the pressed fingertip's skin, [m].
    """

    if not 0 <= int(finger) < len(hand.fingertip_segment):
        raise BenchmarkError(f"finger must be in 0..{len(hand.fingertip_segment) - 1}, got {finger!r}")
    if not (np.isfinite(force_n) and force_n >= 0):
        raise BenchmarkError(f"force_n must be a finite force >= 0 [N], got {force_n!r}")
    skin = skin_of(hand) if skin is None else skin
    seg = int(hand.fingertip_segment[finger])
    sel = np.flatnonzero(skin.segment == seg)
    index = -np.ones(skin.vertices, dtype=np.int64)
    index[sel] = np.arange(len(sel))
    faces = index[skin.faces[np.all(np.isin(skin.faces, sel), axis=1)]]
    verts = np.ascontiguousarray(skin.local[sel])
    centre = np.asarray(hand.fingertip_offset[finger], dtype=float)
    r = float(hand.fingertip_radius[finger])
    face_z = centre[2] - r
    K = len(hand.fingertip_segment)
    contact = np.zeros((K, 3))
    contact[finger] = centre - np.array([0.0, 0.0, r])
    push = np.zeros((K, 3))
    push[finger, 2] = -float(pulp_indentation_m(force_n))
    sk.press_pulps(verts, np.full(len(verts), finger, dtype=np.int64), np.ones(len(verts), dtype=np.bool_), contact,
                   push, np.ascontiguousarray(PULP_REACH * skin.pad_radius))
    if flatten:
        box_centre = np.array([centre[0], centre[1], face_z - _FACE_HALF_M])
        sk.flatten_on_box(verts, np.eye(3), box_centre, np.full(3, _FACE_HALF_M))
    return verts, faces, face_z


def _clipped_area(p: np.ndarray, h: np.ndarray) -> float:
    """Area, projected on the face, of the part of triangle p (3, 3) where the height h (3,) is <= 0."""
    poly = []
    for i in range(3):
        j = (i + 1) % 3
        if h[i] <= 0:
            poly.append(p[i, :2])
        if (h[i] <= 0) != (h[j] <= 0):
            s = h[i] / (h[i] - h[j])
            poly.append(p[i, :2] + s * (p[j, :2] - p[i, :2]))
    if len(poly) < 3:
        return 0.0
    q = np.asarray(poly)
    return 0.5 * abs(float(np.sum(q[:, 0] * np.roll(q[:, 1], -1) - np.roll(q[:, 0], -1) * q[:, 1])))


def patch_area_m2(hand: HandModel, finger: int, force_n: float, skin: Skin | None = None) -> float:
    """Area of the flat patch of :func:`pressed_fingertip`, [m^2].

    The part of the pushed pulp that passes through the face is what the renderer flattens onto it;
    its area on the face is summed triangle by triangle, each clipped where the skin crosses the
    face (linear along its edges), so the measure does not step with the mesh's vertices.
    """
    verts, faces, face_z = pressed_fingertip(hand, finger, force_n, skin, flatten=False)
    h = verts[:, 2] - face_z
    crossing = faces[np.any(h[faces] <= 0, axis=1)]
    return float(sum(_clipped_area(verts[f], h[f]) for f in crossing))
