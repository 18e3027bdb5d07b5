"""The trivial stage every method must beat: one per stage, each standing in for the reference's.

A baseline uses the camera inputs no better than a guess would: what it scores says how easy the
world is for that stage, and a method's skill is its margin over it.

* :class:`StaticTracker`: the box at rest at its first-frame pose and the digits touching it in the
  first frame's hand pose, held for every frame (no vision at all).
* :class:`ZeroKinematics`: the poses with zero velocities and accelerations (a box at rest).
* :class:`GravityForces`: the nominal forces that hold the box against gravity alone (the motion ignored).
* :class:`NoInternalForces`: the nominal forces as the final forces (nobody squeezes more than needed).
* :class:`GripLineForces`: internal forces from the user's grip calibration alone: the line's amount
  at the frame's load, shared equally by the digits in contact (no learning).

:data:`BASELINES` builds each as a method (the reference with that one stage replaced).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from fsv.features import grasp_features
from fsv.forces import ForceSettings, ForceSolution, nominal_forces, reconstruct_forces
from fsv.hand import fingertip_centres, forward_kinematics
from fsv.method.estimate import TrackOutput
from fsv.method.method import make_method
from fsv.types import Contacts, Kinematics, Poses

FIRST_FRAME_CONTACT_M = 0.01
"""A digit's pad touches a face in the first frame when its surface is within this of the face's
plane, and its centre over the face [m] (the initialisation is coarse: a few millimetres)."""


@dataclass(frozen=True)
class StaticTracker:
    """The box where the first-frame initialisation puts it, every frame; the first frame's contacts held.

    Attributes:
        contact_m: :data:`FIRST_FRAME_CONTACT_M`.
    """

    contact_m: float = FIRST_FRAME_CONTACT_M
    name: str = "baseline: static box at its first-frame pose, first-frame contacts held (no vision)"

    def __call__(self, inputs, rng: np.random.Generator) -> TrackOutput:
        T, init = inputs.num_frames, inputs.init
        t = np.arange(T) / inputs.depth.fps
        box = Poses(t=t, pos=np.repeat(np.asarray(init.box_pos, float)[None], T, 0),
                    rot=np.repeat(np.asarray(init.box_rot, float)[None], T, 0))
        hand = inputs.hand_model
        tips = fingertip_centres(hand, forward_kinematics(hand, init.palm_pos, init.palm_rot, init.joints))
        active, point, normal = first_frame_contacts(tips, np.asarray(hand.fingertip_radius, float),
                                                     inputs.object_model.half_extents, init.box_pos, init.box_rot,
                                                     self.contact_m)
        K = len(hand.finger_names)
        contacts = Contacts(finger_names=tuple(hand.finger_names), active=np.repeat(active[None], T, 0),
                            sliding=np.zeros((T, K), bool), point=np.repeat(point[None], T, 0),
                            normal=np.repeat(normal[None], T, 0), slide_dir=np.zeros((T, K, 3)))
        return TrackOutput(box=box, contacts=contacts)


def first_frame_contacts(tips: np.ndarray, radius: np.ndarray, half: np.ndarray, box_pos, box_rot,
                         contact_m: float) -> tuple:
    """The digits whose pads touch a box face: ``(active (K,), point (K, 3), inward normal (K, 3))``,
    points and normals in the box frame.

    Args:
        tips: Pad centres in the world, (K, 3), [m].
        radius: Pad radii, (K,), [m].
        half: The box's half extents, (3,), [m].
        box_pos, box_rot: The box's pose (centre (3,), world_R_box (3, 3)).
        contact_m: The largest gap between a pad's surface and a face that counts as contact, [m].
    """
    local = (np.asarray(tips, float) - np.asarray(box_pos, float)) @ np.asarray(box_rot, float)  # box frame
    K = len(local)
    active, point, normal = np.zeros(K, bool), np.zeros((K, 3)), np.zeros((K, 3))
    for k in range(K):
        axis = int(np.argmax(np.abs(local[k]) - half))  # the face the pad is outside of
        sign = np.sign(local[k, axis]) or 1.0
        gap = abs(local[k, axis]) - half[axis] - radius[k]
        others = [a for a in range(3) if a != axis]
        over = all(abs(local[k, a]) <= half[a] for a in others)
        if abs(gap) <= contact_m and over:
            active[k] = True
            point[k] = local[k]
            point[k, axis] = sign * half[axis]
            normal[k, axis] = -sign
    return active, point, normal


@dataclass(frozen=True)
class ZeroKinematics:
    """The poses as they are, with zero velocities and accelerations: a box at rest."""

    name: str = "baseline: zero kinematics (the box at rest)"

    def __call__(self, poses: Poses) -> Kinematics:
        T = len(poses.t)
        zeros = np.zeros((T, 3))
        return Kinematics(t=poses.t, pos=poses.pos, rot=poses.rot, vel=zeros, acc=zeros, omega=zeros, alpha=zeros,
                          valid=np.ones(T, bool), method="zero")


def at_rest(kinematics: Kinematics) -> Kinematics:
    """The same poses with zero velocities and accelerations."""
    zeros = np.zeros_like(np.asarray(kinematics.vel, float))
    return replace(kinematics, vel=zeros, acc=zeros, omega=zeros, alpha=zeros)


@dataclass(frozen=True)
class GravityForces:
    """The nominal forces (eq. 4-6) that hold the box, at its estimated pose, against gravity alone."""

    settings: ForceSettings | None = None
    name: str = "baseline: nominal forces against gravity alone (the motion ignored)"

    def __call__(self, kinematics: Kinematics, contacts: Contacts, object_model, gravity) -> ForceSolution:
        return nominal_forces(at_rest(kinematics), contacts, object_model, gravity=gravity, settings=self.settings)


@dataclass(frozen=True)
class NoInternalForces:
    """The nominal forces as the final forces: no internal force at all."""

    settings: ForceSettings | None = None
    name: str = "baseline: no internal forces (the nominal forces as the final ones)"

    def __call__(self, kinematics: Kinematics, contacts: Contacts, object_model, gravity) -> tuple:
        solution = nominal_forces(kinematics, contacts, object_model, gravity=gravity, settings=self.settings)
        return solution, np.zeros(contacts.active.shape)


@dataclass(frozen=True)
class GripLineForces:
    """Internal forces from the person's grip calibration alone (no learning): the amount
    ``baseline_n + gain * p1`` at the frame's load p1 = |F_c| (eq. 10), shared equally by the digits
    in contact (each ``amount / sqrt(n)``), then the reconstruction of eq. 14. Without a calibration
    it adds no internal force."""

    settings: ForceSettings | None = None
    name: str = "baseline: the user's grip calibration line, shared equally (no learning)"

    def __call__(self, kinematics: Kinematics, contacts: Contacts, object_model, gravity, grip=None) -> tuple:
        active = contacts.active & kinematics.valid[:, None]
        if grip is None:
            amount = np.zeros(len(kinematics.t))
        else:
            p1 = grasp_features(kinematics, contacts, object_model, gravity=gravity).p1
            amount = grip.baseline_n + grip.gain * np.where(np.isfinite(p1), p1, 0.0)
        n = np.maximum(active.sum(axis=1), 1)
        predicted = np.where(active, (amount / np.sqrt(n))[:, None], 0.0)
        target = np.where(active, predicted, np.nan)
        solution = reconstruct_forces(kinematics, contacts, object_model, target, gravity=gravity, settings=self.settings)
        return solution, predicted


BASELINES = {
    "static": lambda: make_method(tracker=StaticTracker()),
    "zero-kinematics": lambda: make_method(differentiator=ZeroKinematics()),
    "gravity-forces": lambda: make_method(forces=GravityForces()),
    "no-internal": lambda: make_method(internal=NoInternalForces()),
    "grip-line": lambda: make_method(internal=GripLineForces()),
}
"""Each baseline as a method: the reference with that one stage replaced (``--method NAME``)."""

BASELINE_STAGE = {"static": "tracker", "zero-kinematics": "differentiator", "gravity-forces": "forces",
                  "no-internal": "internal", "grip-line": "internal"}
"""The stage each baseline stands in for."""
