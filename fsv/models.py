"""Known models the method may use: the object (geometry, mass, inertia, friction) and the hand.

These are plain descriptions, the same a user would write down for a real box and a real hand;
the benchmark exports them from its simulated world, and the method never sees anything else of it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fsv._check import as_array, finite, positive
from fsv.errors import InputError


@dataclass(frozen=True)
class ObjectModel:
    """A rigid box with known physical properties.

    Attributes:
        size_m: Full edge lengths along the object frame's x, y, z, shape (3,), [m].
        mass_kg: Mass in [kg].
        inertia: Inertia matrix about the centre of mass in the object frame, shape (3, 3), [kg m^2].
        friction: Coulomb friction coefficient between a finger and the object's surface.
        table_friction: Coulomb friction coefficient between the object and the table.
    """

    size_m: np.ndarray
    mass_kg: float
    inertia: np.ndarray
    friction: float
    table_friction: float = 0.5

    def __post_init__(self):
        size = as_array("ObjectModel.size_m", self.size_m, (3,))
        inertia = as_array("ObjectModel.inertia", self.inertia, (3, 3))
        finite("ObjectModel.size_m", size)
        finite("ObjectModel.inertia", inertia)
        if np.any(size <= 0):
            raise InputError(f"ObjectModel.size_m must be positive, got {size}")
        positive("ObjectModel.mass_kg", self.mass_kg, "> 0")
        if not np.allclose(inertia, inertia.T) or np.any(np.linalg.eigvalsh(inertia) <= 0):
            raise InputError("ObjectModel.inertia must be symmetric positive definite")
        for name in ("friction", "table_friction"):
            mu = getattr(self, name)
            if not (np.isfinite(mu) and mu >= 0):
                raise InputError(f"ObjectModel.{name} must be >= 0, got {mu!r}")
            object.__setattr__(self, name, float(mu))
        object.__setattr__(self, "size_m", size)
        object.__setattr__(self, "inertia", inertia)
        object.__setattr__(self, "mass_kg", float(self.mass_kg))

    @property
    def half_extents(self) -> np.ndarray:
        """Half edge lengths, shape (3,), [m]."""
        return self.size_m / 2

    @staticmethod
    def solid_box_inertia(size_m, mass_kg: float) -> np.ndarray:
        """Inertia of a homogeneous box about its centre, shape (3, 3), [kg m^2]."""
        x, y, z = np.asarray(size_m, dtype=float)
        return mass_kg / 12.0 * np.diag([y * y + z * z, x * x + z * z, x * x + y * y])


@dataclass(frozen=True)
class HandModel:
    """An articulated hand made of capsules and spheres: a kinematic tree of rigid segments.

    Segment b has one parent (``parent[b] < b``, -1 for the palm, which is the root). Its frame at
    zero joint angles sits at ``offset_pos[b]`` / ``offset_quat[b]`` in the parent's frame; its
    hinge joints (if any) rotate it about axes given in its own frame, applied in order.

    Attributes:
        segment_names: Names of the B segments, shape (B,).
        parent: Parent index per segment, shape (B,), -1 for the root.
        offset_pos: Segment origin in the parent frame at zero joint angles, shape (B, 3), [m].
        offset_quat: Segment orientation in the parent frame (w, x, y, z), shape (B, 4).
        joint_names: Names of the n hinge joints, shape (n,).
        joint_segment: Segment each joint moves, shape (n,).
        joint_axis: Hinge axis in the segment frame, shape (n, 3), unit vectors.
        joint_range: Lower and upper limits, shape (n, 2), [rad].
        geom_segment: Segment each collision primitive belongs to, shape (G,).
        geom_fromto: Capsule end points in the segment frame, shape (G, 6), [m]; a sphere has
            both ends equal.
        geom_radius: Radius per primitive, shape (G,), [m].
        finger_names: The K fingers, thumb first, shape (K,).
        fingertip_segment: Distal segment of each finger, shape (K,).
        fingertip_offset: Fingertip centre (centre of the distal pad sphere) in that segment's
            frame, shape (K, 3), [m].
        fingertip_radius: Radius of each fingertip pad, shape (K,), [m].
    """

    segment_names: tuple
    parent: np.ndarray
    offset_pos: np.ndarray
    offset_quat: np.ndarray
    joint_names: tuple
    joint_segment: np.ndarray
    joint_axis: np.ndarray
    joint_range: np.ndarray
    geom_segment: np.ndarray
    geom_fromto: np.ndarray
    geom_radius: np.ndarray
    finger_names: tuple
    fingertip_segment: np.ndarray
    fingertip_offset: np.ndarray
    fingertip_radius: np.ndarray

    def __post_init__(self):
        seg = tuple(str(s) for s in self.segment_names)
        jn = tuple(str(s) for s in self.joint_names)
        fn = tuple(str(s) for s in self.finger_names)
        B, n, K = len(seg), len(jn), len(fn)
        arrays = dict(
            parent=as_array("HandModel.parent", self.parent, (B,), np.int64),
            offset_pos=as_array("HandModel.offset_pos", self.offset_pos, (B, 3)),
            offset_quat=as_array("HandModel.offset_quat", self.offset_quat, (B, 4)),
            joint_segment=as_array("HandModel.joint_segment", self.joint_segment, (n,), np.int64),
            joint_axis=as_array("HandModel.joint_axis", self.joint_axis, (n, 3)),
            joint_range=as_array("HandModel.joint_range", self.joint_range, (n, 2)),
            geom_segment=as_array("HandModel.geom_segment", self.geom_segment, (None,), np.int64),
            geom_fromto=as_array("HandModel.geom_fromto", self.geom_fromto, (None, 6)),
            geom_radius=as_array("HandModel.geom_radius", self.geom_radius, (None,)),
            fingertip_segment=as_array("HandModel.fingertip_segment", self.fingertip_segment, (K,), np.int64),
            fingertip_offset=as_array("HandModel.fingertip_offset", self.fingertip_offset, (K, 3)),
            fingertip_radius=as_array("HandModel.fingertip_radius", self.fingertip_radius, (K,)),
        )
        p = arrays["parent"]
        if B == 0 or p[0] != -1 or np.any(p[1:] >= np.arange(1, B)) or np.any(p[1:] < 0):
            raise InputError("HandModel.parent must list the root first (-1) and each parent before its child")
        if np.any(arrays["joint_range"][:, 0] > arrays["joint_range"][:, 1]):
            raise InputError("HandModel.joint_range must have lower <= upper for every joint")
        G = arrays["geom_segment"].shape[0]
        if arrays["geom_fromto"].shape[0] != G or arrays["geom_radius"].shape[0] != G:
            raise InputError("HandModel geom arrays must share their length")
        object.__setattr__(self, "segment_names", seg)
        object.__setattr__(self, "joint_names", jn)
        object.__setattr__(self, "finger_names", fn)
        for k, v in arrays.items():
            object.__setattr__(self, k, v)

    @property
    def num_joints(self) -> int:
        return len(self.joint_names)
