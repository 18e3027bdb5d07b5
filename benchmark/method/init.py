"""The first-frame initialisation handed to the method: the only truth it sees.

The scenario's nominal start (the box and the hand as the simulation starts them, frame 0)
perturbed by seeded Gaussian errors from ``Scenario.rng("tracker-init")`` with the standard
deviations of :data:`INIT_PERTURBATION`; no later frame of the truth is ever used. It decides how
hard tracking is.
"""

from __future__ import annotations

import numpy as np

from benchmark.world.scenario import Scenario
from benchmark.world.truth import Truth
from fsv import HandModel
from fsv.linalg import mm
from fsv.rotation import exp_so3
from fsv.track.tracker import TrackInit

INIT_PERTURBATION = {
    "box_pos_m": 0.003,
    "box_rot_rad": np.radians(2.0),
    "palm_pos_m": 0.005,
    "palm_rot_rad": np.radians(3.0),
    "joints_rad": 0.05,
}
"""Standard deviations of the seeded first-frame errors (per axis / per joint)."""


def tracker_init(truth: Truth, scenario: Scenario, hand_model: HandModel, scale: float = 1.0) -> TrackInit:
    """The first-frame initialisation handed to the tracker: the nominal start, perturbed.

    Args:
        truth: The episode's truth; only frame 0 (the start the simulation began from) is read.
        scenario: Seeds the perturbation (stream "tracker-init").
        hand_model: The hand model (joint ranges).
        scale: Multiplies every standard deviation of :data:`INIT_PERTURBATION` (0 = exact start).
    """
    rng = scenario.rng("tracker-init")
    s = {k: v * float(scale) for k, v in INIT_PERTURBATION.items()}
    base = TrackInit.from_qpos(truth.box_pos[0], truth.box_quat[0], truth.hand_qpos[0])
    joints = base.joints + rng.normal(0.0, s["joints_rad"], base.joints.shape)
    return TrackInit(
        box_pos=base.box_pos + rng.normal(0.0, s["box_pos_m"], 3),
        box_rot=mm(exp_so3(rng.normal(0.0, s["box_rot_rad"], 3)), base.box_rot),
        palm_pos=base.palm_pos + rng.normal(0.0, s["palm_pos_m"], 3),
        palm_rot=mm(exp_so3(rng.normal(0.0, s["palm_rot_rad"], 3)), base.palm_rot),
        joints=np.clip(joints, hand_model.joint_range[:, 0], hand_model.joint_range[:, 1]),
    )


