"""The synthetic human hand: one YAML description, exported both as MJCF and as `fsv.HandModel`.

``sim_assets/hand.yaml`` describes an anthropometric right hand made of capsules at scale 1.
:func:`hand_model` turns it into the plain kinematic description the method is given (segments,
capsules, hinge axes, limits, fingertip pads), and :func:`hand_mjcf` writes the *same* tree as a
MuJoCo body, so what the tracker knows is exactly what the simulator moves.

Conventions (shared with ``fsv.hand``): segment 0 is the palm, moved by a free joint; every other
segment's frame sits at ``offset_pos``/``offset_quat`` in its parent's frame and is turned by its
hinge joints, all anchored at the segment's origin, applied in order about axes of the segment's
own frame. A fingertip pad is a sphere whose centre lies ``radius`` short of the distal end.
"""

from __future__ import annotations

import functools
import xml.etree.ElementTree as ET

import numpy as np

from benchmark.errors import ScenarioError
from benchmark.world.anatomy import Anatomy, hand_spec
from fsv import HandModel
from fsv.linalg import dot, norm

FINGERS = ("thumb", "index", "middle", "ring", "little")
# Fraction of the pad radius used by the distal shaft, so that the pad sphere alone touches a face.
_SHAFT_RADIUS_RATIO = 0.7


def _base_quat(finger: dict) -> np.ndarray:
    """Orientation of a finger's first segment: +y along ``base_direction``, -z towards ``base_pad``."""
    if "base_direction" not in finger:
        return np.array([1.0, 0.0, 0.0, 0.0])
    y = np.asarray(finger["base_direction"], dtype=float)
    y /= norm(y)
    pad = np.asarray(finger["base_pad"], dtype=float)
    z = -(pad - dot(pad, y) * y)
    z /= norm(z)
    R = np.stack([np.cross(y, z), y, z], axis=1)
    w = np.sqrt(max(1.0 + np.trace(R), 1e-12)) / 2
    q = np.array([w, (R[2, 1] - R[1, 2]) / (4 * w), (R[0, 2] - R[2, 0]) / (4 * w), (R[1, 0] - R[0, 1]) / (4 * w)])
    return q / norm(q)


def hand_model(anatomy: "Anatomy | float" = 1.0) -> HandModel:
    """The hand of ``sim_assets/hand.yaml`` reshaped by an anatomy, as the method's known model.

    Args:
        anatomy: A :class:`benchmark.world.anatomy.Anatomy`, or a uniform size factor (every
            length of the YAML multiplied by it: ``Anatomy.template(scale)``).

    Returns:
        A :class:`fsv.HandModel` with 16 segments (palm, then three per finger, thumb first),
        20 hinge joints, one capsule per segment plus the palm's capsules and one pad sphere per
        finger.

    Raises:
        ScenarioError: If a scale or a factor is out of its range (``benchmark.world.anatomy``).
    """
    if not isinstance(anatomy, Anatomy):
        if isinstance(anatomy, bool) or not isinstance(anatomy, (int, float, np.floating, np.integer)):
            raise ScenarioError(f"hand anatomy must be an Anatomy or a scale, got {anatomy!r}")
        anatomy = Anatomy.template(float(anatomy))
    return _hand_model(anatomy)


@functools.lru_cache(maxsize=256)
def _hand_model(anatomy: Anatomy) -> HandModel:
    spec = hand_spec()
    ls, bs = anatomy.length_scale, anatomy.breadth_scale
    axes = np.array([bs, ls, bs])  # across, along, through the hand (palm frame x, y, z)
    seg_names, parent, off_pos, off_quat = ["palm"], [-1], [np.zeros(3)], [np.array([1.0, 0, 0, 0])]
    j_names, j_seg, j_axis, j_range = [], [], [], []
    g_seg, g_fromto, g_radius = [], [], []
    for g in spec["palm"]["geoms"]:
        g_seg.append(0)
        g_fromto.append(np.tile(axes, 2) * np.asarray(g["fromto"], dtype=float))
        g_radius.append(bs * g["radius"])
    tip_seg, tip_off, tip_rad = [], [], []
    for d, finger in enumerate(spec["fingers"]):
        prev, prev_len = 0, None
        for i, segment in enumerate(finger["segments"]):
            b = len(seg_names)
            seg_names.append(f"{finger['name']}_{segment['name']}")
            parent.append(prev)
            if i == 0:
                off_pos.append(axes * np.asarray(finger["base_pos"], dtype=float))
                off_quat.append(_base_quat(finger))
            else:
                off_pos.append(np.array([0.0, prev_len, 0.0]))
                off_quat.append(np.array([1.0, 0, 0, 0]))
            for j in segment["joints"]:
                j_names.append(f"{finger['name']}_{j['name']}")
                j_seg.append(b)
                axis = np.asarray(j["axis"], dtype=float)
                j_axis.append(axis / norm(axis))
                j_range.append(np.deg2rad(j["range_deg"]))
            length = ls * segment["length"] * anatomy.digit_length[d] * anatomy.phalanx_length[d][i]
            radius = bs * segment["radius"] * anatomy.digit_radius[d]
            last = i == len(finger["segments"]) - 1
            if last:
                centre = length - radius
                g_seg += [b, b]
                g_fromto += [np.array([0, 0, 0, 0, centre, 0.0]), np.array([0, centre, 0, 0, centre, 0.0])]
                g_radius += [_SHAFT_RADIUS_RATIO * radius, radius]
                tip_seg.append(b)
                tip_off.append(np.array([0.0, centre, 0.0]))
                tip_rad.append(radius)
            else:
                g_seg.append(b)
                g_fromto.append(np.array([0, 0, 0, 0, length, 0.0]))
                g_radius.append(radius)
            prev, prev_len = b, length
    return HandModel(
        segment_names=tuple(seg_names), parent=parent, offset_pos=off_pos, offset_quat=off_quat,
        joint_names=tuple(j_names), joint_segment=j_seg, joint_axis=j_axis, joint_range=j_range,
        geom_segment=g_seg, geom_fromto=g_fromto, geom_radius=g_radius,
        finger_names=tuple(f["name"] for f in spec["fingers"]), fingertip_segment=tip_seg,
        fingertip_offset=tip_off, fingertip_radius=tip_rad,
    )


def _fmt(v) -> str:
    return " ".join(repr(float(x)) for x in np.ravel(v))


def pad_geoms(model: HandModel) -> np.ndarray:
    """Mask of the model's primitives that are fingertip pads (the sphere of each distal segment), (G,)."""
    sphere = np.all(np.isclose(model.geom_fromto[:, :3], model.geom_fromto[:, 3:]), axis=1)
    return sphere & np.isin(model.geom_segment, model.fingertip_segment)


def geom_name(model: HandModel, g: int) -> str:
    """MJCF name of the hand model's collision primitive ``g`` (``hand_<segment>_<index>``)."""
    return f"hand_{model.segment_names[model.geom_segment[g]]}_{g}"


def hand_mjcf(model: HandModel, *, pos=(0.0, 0.0, 0.3), quat=(1.0, 0.0, 0.0, 0.0), contype: int = 2,
              conaffinity: int = 0, friction: float = 1.0, colliding=None) -> ET.Element:
    """Writes a hand model as an MJCF ``<body>`` tree (palm with a free joint) for the worldbody.

    Body, joint and site names: ``hand_<segment>``, ``hand_<joint>``, ``hand_<finger>_tip``.
    Joint ranges are written in radians (the world sets ``<compiler angle="radian">``).

    Args:
        model: The hand model to write.
        pos: Initial palm position in the world, (3,), [m].
        quat: Initial palm orientation (w, x, y, z).
        contype: MuJoCo collision type bits of every hand geom.
        conaffinity: MuJoCo collision affinity bits of every hand geom.
        friction: Sliding friction of the skin.
        colliding: Which of the model's primitives collide, (G,) bool; None: all. The others
            are written with contype = conaffinity = 0 (visual and kinematic only).

    Returns:
        The palm's ``<body>`` element.
    """
    spec = hand_spec()
    bodies = []
    for b, name in enumerate(model.segment_names):
        if b == 0:
            el = ET.Element("body", name="hand_palm", pos=_fmt(pos), quat=_fmt(quat), gravcomp="1")
            ET.SubElement(el, "freejoint", name="hand_palm")
        else:
            el = ET.SubElement(bodies[model.parent[b]], "body", name=f"hand_{name}",
                               pos=_fmt(model.offset_pos[b]), quat=_fmt(model.offset_quat[b]), gravcomp="1")
        bodies.append(el)
    for j, name in enumerate(model.joint_names):
        ET.SubElement(bodies[model.joint_segment[j]], "joint", name=f"hand_{name}", type="hinge", pos="0 0 0",
                      axis=_fmt(model.joint_axis[j]), range=_fmt(model.joint_range[j]), limited="true",
                      damping=repr(float(spec["joint_damping"])), armature=repr(float(spec["joint_armature"])))
    common = dict(condim="3", friction=f"{friction} 0.005 0.0001", density=repr(float(spec["density"])), group="1")
    colliding = np.ones(len(model.geom_segment), bool) if colliding is None else np.asarray(colliding, bool)
    for g in range(len(model.geom_segment)):
        bits = dict(contype=str(contype), conaffinity=str(conaffinity)) if colliding[g] else dict(contype="0", conaffinity="0")
        a, b = model.geom_fromto[g, :3], model.geom_fromto[g, 3:]
        body = bodies[model.geom_segment[g]]
        if np.allclose(a, b):
            ET.SubElement(body, "geom", name=geom_name(model, g), type="sphere", pos=_fmt(a),
                          size=_fmt([model.geom_radius[g]]), **common, **bits)
        else:
            ET.SubElement(body, "geom", name=geom_name(model, g), type="capsule", fromto=_fmt(model.geom_fromto[g]),
                          size=_fmt([model.geom_radius[g]]), **common, **bits)
    for k, finger in enumerate(model.finger_names):
        ET.SubElement(bodies[model.fingertip_segment[k]], "site", name=f"hand_{finger}_tip",
                      pos=_fmt(model.fingertip_offset[k]), size=_fmt([0.002]), group="4")
    return bodies[0]
