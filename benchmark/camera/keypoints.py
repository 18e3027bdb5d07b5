"""The 21 hand keypoints of the simulated hand, in the OpenPose / FreiHAND order, and MANO's order.

Order (:data:`KEYPOINT_NAMES`): 0 the wrist, then four per digit from the thumb to the little finger,
each from its base joint to its tip (thumb: CMC, MCP, IP, tip; fingers: MCP, PIP, DIP, tip).

What each keypoint is on the simulated hand (:mod:`benchmark.world.hand`: three capsule segments per
digit, each segment's frame at the joint that turns it, +y along the bone):

- **a joint** (CMC, MCP, IP, PIP, DIP): the origin of the segment the joint turns (MuJoCo's
  ``data.xpos`` of ``hand_<finger>_<segment>``), the point the hinge axes pass through. It lies on
  the capsules' axes, inside the digit, about a capsule radius under the skin;
- **a tip**: the distal end of the distal phalanx, the point of the fingertip's pad sphere furthest
  along the bone: the pad centre (``Truth.fingertip_pos``, the MJCF site ``hand_<finger>_tip``)
  plus one pad radius along the distal segment's +y axis. It lies on the surface;
- **the wrist**: the proximal end of the middle metacarpal capsule's axis in the palm frame (the
  base of the third metacarpal, where the wrist's flexion axis crosses the hand's midline),
  ``hand.yaml``'s ``meta_middle`` start scaled by the anatomy: (-8, -42, 0) mm in the template's palm
  frame, 4 mm distal of the wrist crease the hand length is measured from, on the palm's mid-plane,
  inside the palm under about a metacarpal radius of skin. The simulated hand has no forearm.

:data:`OPENPOSE_TO_MANO` and :data:`MANO_TO_OPENPOSE` convert to and from MANO's 21-joint order
(MANO's 16 joints, then the five tips thumb, index, middle, ring, little: the order of HO-3D's
annotations and of manopth's ``ManoLayer`` before its final reordering). docs/camera.md has the table.
"""

from __future__ import annotations

import mujoco
import numpy as np

from benchmark.errors import BenchmarkError
from benchmark.world.anatomy import hand_spec
from benchmark.world.assets import set_frame
from fsv import HandModel

DIGITS = ("thumb", "index", "middle", "ring", "little")
"""The digits in keypoint order (the hand model's ``finger_names``)."""
_JOINTS = {"thumb": ("cmc", "mcp", "ip"), "finger": ("mcp", "pip", "dip")}

KEYPOINT_NAMES = ("wrist",) + tuple(
    f"{d}_{j}" for d in DIGITS for j in (*_JOINTS["thumb" if d == "thumb" else "finger"], "tip")
)
"""The 21 keypoints in the OpenPose / FreiHAND order: wrist, then thumb_cmc, thumb_mcp, thumb_ip,
thumb_tip, index_mcp, index_pip, index_dip, index_tip, ... little_tip."""

MANO_NAMES = ("wrist", "index1", "index2", "index3", "middle1", "middle2", "middle3", "little1", "little2",
              "little3", "ring1", "ring2", "ring3", "thumb1", "thumb2", "thumb3", "thumb_tip", "index_tip",
              "middle_tip", "ring_tip", "little_tip")
"""MANO's 21-joint order: its 16 joints (wrist, index, middle, little, ring, thumb; 1 to 3 from the
palm outwards), then the tips thumb, index, middle, ring, little (HO-3D's order; manopth's
``th_jtr`` before its reorder)."""

OPENPOSE_TO_MANO = np.array([0, 5, 6, 7, 9, 10, 11, 17, 18, 19, 13, 14, 15, 1, 2, 3, 4, 8, 12, 16, 20])
"""``mano = openpose[..., OPENPOSE_TO_MANO, :]``: entry j is the OpenPose index of MANO's joint j."""

MANO_TO_OPENPOSE = np.argsort(OPENPOSE_TO_MANO)
"""``openpose = mano[..., MANO_TO_OPENPOSE, :]``: entry i is the MANO index of keypoint i
([0, 13, 14, 15, 16, 1, 2, 3, 17, 4, 5, 6, 18, 10, 11, 12, 19, 7, 8, 9, 20], manopth's reorder)."""

KEYPOINT_FINGER = np.array([-1] + [k for k in range(len(DIGITS)) for _ in range(4)], dtype=np.int64)
"""Digit of each keypoint (its index in :data:`DIGITS`, thumb first), -1 for the wrist, (21,)."""

KEYPOINT_ON_PALM = np.isin(np.arange(21), [0, 1, 5, 9, 13, 17])
"""Keypoints inside the palm's skin as well as (or instead of) their digit's: the wrist and each
digit's base joint (thumb CMC under the thenar eminence, the fingers' MCPs at the metacarpal heads), (21,)."""

TOLERANCE_RADII = 1.5
"""How far in front of a keypoint (along the optical axis), in local radii, its own part's surface
may lie and the keypoint still count as seen (:func:`keypoint_tolerance`). A joint sits on its
capsules' axes: its own surface lies one radius in front where the bones run across the line of
sight (the skin: 0.9-1.1 radii dorsally and laterally, ``benchmark.world.skin``) and r / sin(θ) in
front where a bone runs at an angle θ to it; 1.5 keeps a joint seen down to θ = 42° (a choice) and
counts a joint seen along its own phalanx as occluded by the hand."""


def digit_segments(hand: HandModel) -> np.ndarray:
    """Each digit's three segments from its base to its tip, (5, 3) segment indices.

    Raises:
        BenchmarkError: If the hand's fingers are not :data:`DIGITS` with three segments each.
    """
    if tuple(hand.finger_names) != DIGITS:
        raise BenchmarkError(f"keypoints need the digits {DIGITS}, got {tuple(hand.finger_names)}")
    out = []
    for k, tip in enumerate(hand.fingertip_segment):
        chain, b = [], int(tip)
        while b > 0:
            chain.append(b)
            b = int(hand.parent[b])
        if len(chain) != 3:
            raise BenchmarkError(f"digit {DIGITS[k]} has {len(chain)} segments; keypoints need 3")
        out.append(chain[::-1])
    return np.array(out, dtype=np.int64)


def _palm_geom(hand: HandModel, name: str) -> int:
    names = [g["name"] for g in hand_spec()["palm"]["geoms"]]
    palm = np.flatnonzero(np.asarray(hand.geom_segment) == 0)
    if len(palm) != len(names):
        raise BenchmarkError(f"the hand's palm has {len(palm)} primitives, hand.yaml {len(names)}")
    return int(palm[names.index(name)])


def wrist_in_palm(hand: HandModel) -> np.ndarray:
    """The wrist keypoint in the palm frame, (3,), [m]: the middle metacarpal capsule's proximal end."""
    return np.array(hand.geom_fromto[_palm_geom(hand, "meta_middle"), :3], dtype=np.float64)


def keypoint_radius(hand: HandModel) -> np.ndarray:
    """The local radius at each keypoint, (21,), [m].

    A joint: the largest radius of the capsules of its segment and of the parent's capsule nearest
    to it (for a base joint, the nearest palm capsule: the metacarpal or, for the thumb's CMC, the
    thenar eminence). A tip: its pad's radius. The wrist: the middle metacarpal capsule's radius.
    """
    seg = digit_segments(hand)
    geom_seg = np.asarray(hand.geom_segment)
    radius = np.asarray(hand.geom_radius, dtype=np.float64)
    fromto = np.asarray(hand.geom_fromto, dtype=np.float64)
    out = np.empty(21)
    out[0] = radius[_palm_geom(hand, "meta_middle")]
    for d in range(len(DIGITS)):
        for i, b in enumerate(seg[d]):
            own = float(radius[geom_seg == b].max())
            parent = int(hand.parent[b])
            joint = np.asarray(hand.offset_pos[b], dtype=np.float64)  # in the parent's frame
            cand = np.flatnonzero(geom_seg == parent)
            a, e = fromto[cand, :3], fromto[cand, 3:]
            ab = e - a
            s = np.clip(((joint - a) * ab).sum(1) / np.maximum((ab * ab).sum(1), 1e-30), 0.0, 1.0)
            dist = np.sqrt((((a + s[:, None] * ab) - joint) ** 2).sum(1))
            out[1 + 4 * d + i] = max(own, float(radius[cand[np.argmin(dist)]]))
        out[4 + 4 * d] = float(hand.fingertip_radius[d])
    return out


def keypoint_tolerance(hand: HandModel) -> np.ndarray:
    """Visibility tolerance per keypoint, :data:`TOLERANCE_RADII` local radii, (21,), [m]."""
    return TOLERANCE_RADII * keypoint_radius(hand)


def _in_body(pos, mat, local) -> np.ndarray:
    """pos + mat @ local in a fixed order (mat row-major, 9 entries)."""
    x, y, z = float(local[0]), float(local[1]), float(local[2])
    return np.array([pos[0] + ((mat[0] * x + mat[1] * y) + mat[2] * z),
                     pos[1] + ((mat[3] * x + mat[4] * y) + mat[5] * z),
                     pos[2] + ((mat[6] * x + mat[7] * y) + mat[8] * z)])


def keypoints_world(world, truth) -> np.ndarray:
    """The 21 keypoints of every frame of a simulated episode, in the world frame.

    Poses the world from each truth frame (:func:`benchmark.world.assets.set_frame`, MuJoCo's
    kinematics) and reads the segments' origins, the palm's pose and the fingertip sites; the few
    offsets are applied in a fixed order of scalar operations (no BLAS).

    Args:
        world: The episode's :class:`benchmark.world.assets.World` (``build_world(scenario)``).
        truth: Its :class:`benchmark.world.truth.Truth` (``hand_qpos`` (T, 7 + n), box pose).

    Returns:
        Keypoints in :data:`KEYPOINT_NAMES` order, (T, 21, 3) float64, [m].
    """

    hand = world.hand
    seg = digit_segments(hand)
    body = np.asarray(world.segment_body, dtype=np.int64)
    palm = int(world.palm_body)
    wrist = wrist_in_palm(hand)
    pad = np.asarray(hand.fingertip_radius, dtype=np.float64)
    tip_body = body[np.asarray(hand.fingertip_segment, dtype=np.int64)]
    tip_site = np.asarray(world.tip_site, dtype=np.int64)
    T = len(truth.t)
    out = np.empty((T, 21, 3))
    data = mujoco.MjData(world.model)
    for k in range(T):
        set_frame(world, data, truth.box_pos[k], truth.box_quat[k], truth.hand_qpos[k])
        out[k, 0] = _in_body(data.xpos[palm], data.xmat[palm], wrist)
        for d in range(len(DIGITS)):
            out[k, 1 + 4 * d : 4 + 4 * d] = data.xpos[body[seg[d]]]
            m = data.xmat[tip_body[d]]  # row-major: the segment's +y axis is (m[1], m[4], m[7])
            c = data.site_xpos[tip_site[d]]
            out[k, 4 + 4 * d] = (c[0] + pad[d] * m[1], c[1] + pad[d] * m[4], c[2] + pad[d] * m[7])
    return out
