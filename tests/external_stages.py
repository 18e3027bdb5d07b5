"""Stages written as a user outside the repo would: loaded by ``module:attribute`` in the tests."""

import numpy as np

from fsv import Contacts, Poses
from fsv.method import TrackOutput


class FrozenTracker:
    """A broken tracker: the initial box pose forever, and no contact at all."""

    name = "frozen tracker (a broken example)"

    def __call__(self, inputs, rng):
        T, K = inputs.num_frames, len(inputs.hand_model.finger_names)
        box = Poses(t=inputs.depth.t, pos=np.repeat(inputs.init.box_pos[None], T, 0),
                    rot=np.repeat(inputs.init.box_rot[None], T, 0))
        z = np.zeros((T, K, 3))
        contacts = Contacts(finger_names=inputs.hand_model.finger_names, active=np.zeros((T, K), bool),
                            sliding=np.zeros((T, K), bool), point=z, normal=z, slide_dir=z)
        return TrackOutput(box=box, contacts=contacts)


def half_the_frames(poses):
    """A differentiator that returns the wrong number of frames (an interface error)."""
    from fsv.kinematics import AlgebraicConfig, differentiate_poses

    n = len(poses) // 2
    return differentiate_poses(Poses(t=poses.t[:n], pos=poses.pos[:n], rot=poses.rot[:n]), AlgebraicConfig())


NOT_CALLABLE = 42


class NominalAsLearned:
    """An internal-force stage that returns the nominal forces under a label that reads like the
    reference's learned stage (the main command must not take it for one)."""

    name = "learned internal forces (an impostor)"

    def __call__(self, kinematics, contacts, object_model, gravity):
        from fsv.forces import nominal_forces

        solution = nominal_forces(kinematics, contacts, object_model, gravity=gravity)
        return solution, np.zeros(solution.active.shape)
