"""A person's skin: a smooth, closed hand surface built around the simulation's capsules.

The simulated hand collides through capsules and pad spheres (:mod:`benchmark.world.hand`); a real
hand is not a chain of capsules. :func:`skin_of` builds, per person (from the same
:class:`fsv.HandModel` the simulation is written from), the surface the depth camera sees:

- **Digits**: one closed piece per phalanx (and the thumb's metacarpal), around the phalanx's
  capsule axis, with cross-sections wider than deep (:data:`LATERAL`, :data:`DORSAL`, after the
  breadth-to-depth ratios of finger cross-sections, about 1.1-1.2, in Vergara et al. 2018, Int. J.
  Ind. Ergon. 68), tapered along the phalanx (:data:`TAPER`), with a knuckle over each joint's
  head (:data:`KNUCKLE`), a flattened nail over the distal phalanx (:data:`NAIL`) and the fingertip
  pulp below it.
- **Palm**: a rounded slab over the four metacarpal capsules, with a hypothenar eminence on the
  little-finger side (:data:`HYPOTHENAR`) and the thenar eminence over the palm's thenar capsule.

**Fitted collision geometry.** Only the pad spheres and the palm's capsules collide. The skin is
built so that its palmar side *is* that collision geometry where contacts happen: each fingertip
pulp reaches exactly the pad sphere's surface below the pad's centre and the palm's palmar face
lies on the metacarpal capsules' palmar line. Elsewhere the skin departs from the primitives (wider,
shallower, tapered, nails, knuckles, eminences); :func:`benchmark.camera.skin_stats.collision_gap`
measures by how much.

**Skinning.** Each vertex belongs to one segment (its *body*), with the child's vertices near a joint
blended with the parent's pose (linear blend skinning, weight up to :data:`BLEND_AT_JOINT` at the
joint, over :data:`BLEND_LENGTH` radii), so a flexed joint bends its skin instead of breaking it.

**Pulps under load** (:func:`pulp_indentation_m`): MuJoCo's contacts are nearly rigid, a fingertip is
not. A pulp pressed with a normal force F compresses by δ(F) (the exponential force-displacement law
of Serina, Mote & Rempel 1997, J. Biomech. 30(10):1035-1040); the renderer pushes the pulp δ(F)
into the face it presses and flattens whatever skin would pass through the box onto the face, so the
flat patch grows with force as a fingertip's does (:mod:`benchmark.camera.skin_kernels`).

All lengths are in metres, in the segments' frames (``fsv.hand`` conventions: +y along the bone,
+z dorsal).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from benchmark.world.anatomy import hand_spec
from fsv import HandModel
from fsv.hand import finger_of_segment, forward_kinematics
from fsv.linalg import norm

LATERAL = 1.12
"""Half-width of a digit's cross-section over its capsule's radius (finger breadth / depth about
1.1-1.2, Vergara et al. 2018); the palmar half-depth is the capsule's radius."""
DORSAL = 0.88
"""Dorsal half-depth of a digit over its capsule's radius: the bones lie nearer the back of a digit."""
TAPER = 0.12
"""Relative decrease of a phalanx's cross-section from its proximal to its distal end (its mean is
the capsule's, so the capsule is the least-squares fit of the palmar line)."""
KNUCKLE = 0.18
"""Height of the knuckle over a joint's head, on the dorsal side, in radii of the proximal segment."""
NAIL = 0.72
"""Dorsal half-depth of the distal phalanx under the nail, in radii: the nail bed is flat (the
cross-section's dorsal half is a superellipse of exponent :data:`NAIL_EXPONENT`)."""
NAIL_EXPONENT = 3.0
"""Superellipse exponent of the nail's cross-section (2 is an ellipse, larger is flatter)."""
PULP_SHAFT = 0.86
"""Palmar half-depth of the distal phalanx's shaft (towards the joint), in pad radii: the pulp
bulges from it to the full pad radius below the pad's centre."""
HYPOTHENAR = 0.30
"""Palmar bulge of the hypothenar eminence, in metacarpal radii, on the little finger's side of the
palm's proximal half."""
PALM_MARGIN = 0.12
"""Palm skin beyond the outer metacarpal capsules on either side, in metacarpal radii."""
PALM_EXPONENT = 2.6
"""Superellipse exponent of the palm's cross-section: a rounded slab."""
BLEND_AT_JOINT = 0.5
"""Weight of the parent's pose on a child's skin at the joint (linear blend skinning)."""
BLEND_LENGTH = 0.8
"""Length, in the child's radii, over which the parent's weight falls from :data:`BLEND_AT_JOINT` to 0."""
AROUND = 20
"""Vertices around a cross-section."""
CAP_RINGS = 5
"""Rings in each rounded end of a piece."""
PULP_AROUND = 32
"""Vertices around a distal phalanx's cross-section (finer: its pulp flattens on faces)."""
PULP_CAP_RINGS = 10
"""Rings in a distal phalanx's rounded ends."""
SHAFT_RINGS = 8
"""Rings along a piece between its ends."""

PULP_STIFFNESS_N_PER_MM = 0.25
"""``b`` of Serina et al. (1997)'s law F = (b / m)(exp(m δ) - 1): the pulp's stiffness at first touch."""
PULP_EXPONENT_PER_MM = 1.4
"""``m`` of that law: how fast the pulp stiffens. With ``b`` it gives δ = 1.3 mm at 1 N and 2.2 mm at
5 N, in the ranges Serina et al. report for index fingertips (a choice within them)."""
PULP_REACH = 2.0
"""Radius, in pad radii, around the centre of pressure within which the pulp is pushed into the face
(the push falls as (1 - d^2 / reach^2)^2 with the distance d: 84 % of it at 1 N's patch radius)."""

LABEL_PALM, LABEL_FINGER0 = 9, 10
"""The label image's values of the palm and of finger k (``benchmark.camera.scene``'s)."""


@dataclass(frozen=True)
class Skin:
    """A hand's skin in its bind pose (every joint angle 0), ready for skinning.

    Attributes:
        local: Each vertex in its segment's frame, (V, 3), [m].
        segment: Hand segment of each vertex, (V,) int64.
        parent_local: Each vertex in the parent segment's frame at the bind pose, (V, 3), [m]
            (equal to ``local`` where the segment is the palm).
        parent: Parent segment of each vertex's segment, (V,) int64 (0 for the palm's own).
        parent_weight: Weight of the parent's pose, (V,) in [0, 0.5].
        faces: Triangles, counter-clockwise seen from outside, (F, 3) int64.
        face_label: Label of each triangle (9 palm, 10 + k finger k), (F,) uint8.
        finger: Finger of each vertex, -1 on the palm, (V,) int64.
        pulp: Whether the vertex belongs to a distal phalanx (may be pressed into a face), (V,) bool.
        pad_radius: Pad radius of each finger, (K,), [m].
    """

    local: np.ndarray
    segment: np.ndarray
    parent_local: np.ndarray
    parent: np.ndarray
    parent_weight: np.ndarray
    faces: np.ndarray
    face_label: np.ndarray
    finger: np.ndarray
    pulp: np.ndarray
    pad_radius: np.ndarray

    @property
    def vertices(self) -> int:
        return len(self.local)

    def bind_pose(self, hand: HandModel) -> np.ndarray:
        """The vertices in the palm's frame with every joint at 0, (V, 3), [m]."""
        R, t = _bind_frames(hand)
        return np.einsum("vij,vj->vi", R[self.segment], self.local) + t[self.segment]


def pulp_indentation_m(force_n):
    """How far a fingertip pulp is compressed by a normal force: δ = ln(1 + m F / b) / m.

    Args:
        force_n: Normal force, scalar or array, [N] (negative is taken as 0).

    Returns:
        Compression δ, same shape, [m].
    """
    f = np.maximum(np.asarray(force_n, dtype=float), 0.0)
    return np.log1p(PULP_EXPONENT_PER_MM * f / PULP_STIFFNESS_N_PER_MM) / PULP_EXPONENT_PER_MM * 1e-3


def _smoothstep(x):
    x = np.clip(x, 0.0, 1.0)
    return x * x * (3 - 2 * x)


def _bind_frames(hand: HandModel) -> tuple[np.ndarray, np.ndarray]:
    """Each segment's rotation (B, 3, 3) and origin (B, 3) in the palm's frame at zero joint angles."""
    pose = forward_kinematics(hand, np.zeros(3), np.eye(3), np.zeros(hand.num_joints))
    return pose.rot, pose.pos


def _grid_faces(rings: int, around: int, first: int) -> list:
    """Quads between consecutive rings of ``around`` vertices, split into two triangles each."""
    faces = []
    for i in range(rings - 1):
        for j in range(around):
            a, b = first + i * around + j, first + i * around + (j + 1) % around
            c, d = a + around, b + around
            faces += [(a, c, b), (b, c, d)]
    return faces


def _closed_piece(y: np.ndarray, rho: np.ndarray, section, around: int = AROUND) -> tuple[np.ndarray, np.ndarray]:
    """A closed surface of revolution-like piece along +y.

    Args:
        y: Axial station of each ring, increasing, (R,); the first and last rings are the poles.
        rho: Profile radius of each ring (0 at the poles), (R,).
        section: ``section(y, rho, theta) -> (x, z)`` the cross-section's points at angle theta
            (0 lateral +x, pi/2 dorsal +z, 3 pi/2 palmar -z).
        around: Vertices per ring.

    Returns:
        ``(vertices (V, 3), faces (F, 3))``, outward counter-clockwise.
    """
    theta = 2 * np.pi * np.arange(around) / around
    inner = range(1, len(y) - 1)
    verts = [np.array([0.0, y[0], 0.0])]
    for i in inner:
        x, z = section(y[i], rho[i], theta)
        verts += list(np.stack([x, np.full(around, y[i]), z], axis=1))
    verts.append(np.array([0.0, y[-1], 0.0]))
    n = len(inner)
    faces = [(0, 1 + j, 1 + (j + 1) % around) for j in range(around)]
    faces += _grid_faces(n, around, 1)
    last, base = 1 + n * around, 1 + (n - 1) * around
    faces += [(last, base + (j + 1) % around, base + j) for j in range(around)]
    verts, faces = np.array(verts), np.array(faces, dtype=np.int64)
    return verts, _outward(verts, faces)


def _outward(verts: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """The faces wound counter-clockwise seen from outside (flipped as a whole if the volume is negative)."""
    a, b, c = verts[faces[:, 0]], verts[faces[:, 1]], verts[faces[:, 2]]
    volume = np.sum(np.einsum("ij,ij->i", a, np.cross(b, c))) / 6
    return faces if volume > 0 else faces[:, ::-1].copy()


def _capsule_profile(y0: float, y1: float, r: float, cap_rings: int = CAP_RINGS) -> tuple[np.ndarray, np.ndarray]:
    """Stations and profile radii of a capsule of radius r between axial stations y0 and y1."""
    cap = np.linspace(0.0, np.pi / 2, cap_rings + 1)
    ys = [y0 - r * np.cos(cap)]
    rs = [r * np.sin(cap)]
    shaft = np.linspace(y0, y1, SHAFT_RINGS + 2)[1:-1]
    ys.append(shaft)
    rs.append(np.full(len(shaft), r))
    ys.append(y1 + r * np.cos(cap[::-1]))
    rs.append(r * np.sin(cap[::-1]))
    return np.concatenate(ys), np.concatenate(rs)


def _superellipse(c, s, a, b, n):
    """Points of |x/a|^n + |z/b|^n = 1 at the angles whose cosine and sine are c and s."""
    return a * np.sign(c) * np.abs(c) ** (2 / n), b * np.sign(s) * np.abs(s) ** (2 / n)


def _digit_piece(length: float, radius: float, *, distal: bool, pad_centre: float, knuckle: bool):
    """The skin of one phalanx in its segment frame (``knuckle``: a joint's head at its distal end)."""
    r = radius
    y1 = pad_centre if distal else length

    def section(y, rho, theta):
        c, s = np.cos(theta), np.sin(theta)
        u = np.clip(y / max(y1, 1e-9), 0.0, 1.0)  # 0 at the joint, 1 at the distal station
        taper = 1.0 + TAPER * (0.5 - u)
        lateral = LATERAL * taper
        if distal:
            pulp = _smoothstep((y - 0.25 * pad_centre) / max(0.75 * pad_centre, 1e-9))
            palmar = PULP_SHAFT + (1.0 - PULP_SHAFT) * pulp  # the pulp reaches the pad sphere below its centre
            nail = _smoothstep((y - 0.2 * pad_centre) / max(0.5 * pad_centre, 1e-9))
            dorsal = DORSAL * taper * (1 - nail) + NAIL * nail
            exponent = 2.0 + (NAIL_EXPONENT - 2.0) * nail
            lateral = LATERAL * (1.0 - 0.5 * TAPER * u)
        else:
            palmar = taper
            dorsal = DORSAL * taper
            exponent = 2.0
            if knuckle:  # the knuckle over the joint's head
                dorsal = dorsal + KNUCKLE * np.exp(-0.5 * ((y - length) / (0.45 * r)) ** 2)
        x = rho * lateral * c
        z_palmar = rho * palmar * s
        xd, zd = _superellipse(c, s, rho * lateral, rho * dorsal, exponent)
        x = np.where(s > 0, xd, x)
        z = np.where(s > 0, zd, z_palmar)
        return x, z

    y, rho = _capsule_profile(0.0, y1, r, PULP_CAP_RINGS if distal else CAP_RINGS)
    return _closed_piece(y, rho, section, PULP_AROUND if distal else AROUND)


def _palm_piece(hand: HandModel):
    """The palm's skin in the palm frame: a rounded slab over the metacarpals, plus the thenar eminence."""
    names = [g["name"] for g in hand_spec()["palm"]["geoms"]]
    palm = np.flatnonzero(np.asarray(hand.geom_segment) == 0)
    fromto = np.asarray(hand.geom_fromto)[palm]
    radius = np.asarray(hand.geom_radius)[palm]
    meta = [i for i, n in enumerate(names) if n.startswith("meta_")]
    thenar = names.index("thenar")
    r = float(np.max(radius[meta]))
    xs = np.concatenate([fromto[meta][:, [0, 3]].ravel() - radius[meta].repeat(2),
                         fromto[meta][:, [0, 3]].ravel() + radius[meta].repeat(2)])
    x_lo, x_hi = float(xs.min()) - PALM_MARGIN * r, float(xs.max()) + PALM_MARGIN * r
    y_lo, y_hi = float(fromto[meta][:, [1, 4]].min()), float(fromto[meta][:, [1, 4]].max())
    xc, half_w = 0.5 * (x_lo + x_hi), 0.5 * (x_hi - x_lo)
    y, rho = _capsule_profile(y_lo, y_hi, r)
    rho = rho / r  # 0..1 scale of the cross-section

    def section(yy, s_, theta):
        c, s = np.cos(theta), np.sin(theta)
        x, z = _superellipse(c, s, s_ * half_w, s_ * r, PALM_EXPONENT)
        hypo = HYPOTHENAR * r * _smoothstep((x / max(half_w, 1e-9) - 0.1) / 0.6) * _smoothstep(
            (0.6 * y_hi - yy) / max(y_hi - y_lo, 1e-9) * 2.0)
        z = np.where(s < 0, z - s_ * hypo * np.abs(s), z)
        knuckles = KNUCKLE * r * np.exp(-0.5 * ((yy - y_hi) / (0.45 * r)) ** 2)
        z = np.where(s > 0, z + s_ * knuckles * s, z)
        return x + xc, z

    slab = _closed_piece(y, rho, section)
    a, b, rt = fromto[thenar, :3], fromto[thenar, 3:], float(radius[thenar])
    axis = b - a
    length = float(np.linalg.norm(axis))
    yy, rr = _capsule_profile(0.0, length, rt)

    def thenar_section(y_, rho_, theta):
        return rho_ * LATERAL * np.cos(theta), rho_ * np.sin(theta)

    v, f = _closed_piece(yy, rr, thenar_section)
    e_y = axis / length
    e_z = np.array([0.0, 0.0, 1.0]) - e_y[2] * e_y
    e_z /= norm(e_z)
    e_x = np.cross(e_y, e_z)
    v = a + v[:, :1] * e_x + v[:, 1:2] * e_y + v[:, 2:] * e_z
    return [slab, (v, _outward(v, f))]


def skin_of(hand: HandModel) -> Skin:
    """The skin of a hand model.

    Args:
        hand: The hand the simulation is written from (:func:`benchmark.world.hand.hand_model`).

    Returns:
        Its :class:`Skin`.
    """
    R, t = _bind_frames(hand)
    finger_of_seg = finger_of_segment(hand)
    parents = {int(p) for b, p in enumerate(hand.parent) if b > 0}
    geom_seg = np.asarray(hand.geom_segment)
    locs, segs, faces, labels, count = [], [], [], [], 0

    def add(v, f, seg):
        nonlocal count
        locs.append(v)
        segs.append(np.full(len(v), seg, dtype=np.int64))
        faces.append(f + count)
        k = finger_of_seg[seg]
        labels.append(np.full(len(f), LABEL_PALM if k < 0 else LABEL_FINGER0 + k, dtype=np.uint8))
        count += len(v)

    for v, f in _palm_piece(hand):
        add(v, f, 0)
    tips = {int(s): k for k, s in enumerate(hand.fingertip_segment)}
    for b in range(1, len(hand.segment_names)):
        mine = np.flatnonzero(geom_seg == b)
        fromto = np.asarray(hand.geom_fromto)[mine]
        radius = float(np.max(np.asarray(hand.geom_radius)[mine]))
        distal = b in tips
        if distal:
            pad_centre = float(hand.fingertip_offset[tips[b]][1])
            length = pad_centre + radius
        else:
            pad_centre = 0.0
            length = float(np.max(fromto[:, [1, 4]]))
        v, f = _digit_piece(length, radius, distal=distal, pad_centre=pad_centre, knuckle=b in parents)
        add(v, f, b)
    local = np.concatenate(locs)
    segment = np.concatenate(segs)
    parent = np.array([int(hand.parent[s]) if s > 0 else 0 for s in segment], dtype=np.int64)
    radius_of = np.array([float(np.max(np.asarray(hand.geom_radius)[geom_seg == s])) for s in range(len(R))])
    weight = np.where(segment > 0, BLEND_AT_JOINT * (1 - _smoothstep(local[:, 1] / (BLEND_LENGTH * radius_of[segment]))), 0.0)
    # the vertex in the parent's frame at the bind pose: p_parent = R_p^T (R_s p + t_s - t_p)
    world = np.einsum("vij,vj->vi", R[segment], local) + t[segment]
    parent_local = np.einsum("vji,vj->vi", R[parent], world - t[parent])
    finger = finger_of_seg[segment]
    pulp = np.isin(segment, np.asarray(hand.fingertip_segment))
    return Skin(local=np.ascontiguousarray(local), segment=segment, parent_local=np.ascontiguousarray(parent_local),
                parent=parent, parent_weight=weight, faces=np.concatenate(faces), face_label=np.concatenate(labels),
                finger=finger, pulp=pulp, pad_radius=np.asarray(hand.fingertip_radius, dtype=float))
