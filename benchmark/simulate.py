"""Simulation: a scenario in, an episode with its ground truth out.

:func:`simulate` builds the world, lets the synthetic human (``benchmark.grip.Human``) reach, grasp,
load, manipulate and possibly release the box along the task's minimum-jerk motion, and records the
:class:`~benchmark.truth.Truth` at the frame times t_k = k / fps.

The physics step divides the frame period exactly (about 1 ms: 33 steps per frame at 30 fps), so a
frame is a simulator state, not an interpolation. At a frame, the state is evaluated once with
``mj_forward`` and everything is read from that one evaluation: accelerations and contact forces
come from the same constraint solve, so the recorded truth obeys Newton-Euler to floating-point
precision.

MuJoCo conventions used here (checked by tests/test_simulate.py): a free joint's qvel is the
linear velocity of the body origin in the world frame followed by the angular velocity in the body
frame, and qacc is its time derivative in the same coordinates; ``mj_contactForce`` returns the
force in the contact frame (rows of ``contact.frame``: normal from geom1 to geom2, two tangents),
acting on geom2 (its opposite acts on geom1).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import mujoco
import numpy as np

from benchmark.episode import Episode
from benchmark.errors import SimulationError
from benchmark.grip import Human
from benchmark.scenario import Scenario
from benchmark.tasks import TASKS, Motion
from benchmark.truth import Truth
from benchmark.world import World, box_spec, build_world, validate

CONTROL_PERIOD_S = 0.004  # the synthetic human updates the finger torques at ~250 Hz
SLIDING_SPEED_M_S = 0.005  # a pad slides when its tangential speed relative to the box exceeds this
SETTLE_S = 0.2  # simulated before t = 0 so that the box rests in its table contact at the first frame
STEP_S = 0.001  # the physics step is the largest divisor of the frame period not above this


def steps_per_frame(fps: float) -> int:
    """Physics steps per camera frame (the step is 1 / (fps * steps) <= 1 ms)."""
    return int(math.ceil(1.0 / (fps * STEP_S) - 1e-9))


def duration_of(scenario: Scenario) -> float:
    """The scenario's episode length in [s] (its own, or its task's default)."""
    return float(scenario.duration_s) if scenario.duration_s is not None else TASKS[scenario.task].default_duration_s


class _Recorder:
    """Reads the truth of one frame from an MjData evaluated by mj_forward."""

    def __init__(self, world: World, n_frames: int):
        self.w = world
        K = len(world.hand.finger_names)
        T = n_frames
        self.a = {
            "box_pos": np.zeros((T, 3)), "box_quat": np.zeros((T, 4)), "box_vel": np.zeros((T, 3)),
            "box_omega": np.zeros((T, 3)), "box_acc": np.zeros((T, 3)), "box_alpha": np.zeros((T, 3)),
            "contact_active": np.zeros((T, K), bool), "contact_sliding": np.zeros((T, K), bool),
            "contact_point": np.zeros((T, K, 3)), "contact_normal": np.zeros((T, K, 3)),
            "contact_force": np.zeros((T, K, 3)), "env_force": np.zeros((T, 3)), "env_torque": np.zeros((T, 3)),
            "fingertip_pos": np.zeros((T, K, 3)), "hand_qpos": np.zeros((T, len(world.hand_qadr))),
            "palm_force": np.zeros((T, 3)),
        }

    def record(self, i: int, data: mujoco.MjData) -> None:
        w, a, m = self.w, self.a, self.w.model
        qa, da = w.box_qadr, w.box_dadr
        R = data.xmat[w.box_body].reshape(3, 3)
        com = data.xpos[w.box_body].copy()
        a["box_pos"][i] = data.qpos[qa : qa + 3]
        a["box_quat"][i] = data.qpos[qa + 3 : qa + 7]
        a["box_vel"][i] = data.qvel[da : da + 3]
        omega = R @ data.qvel[da + 3 : da + 6]
        a["box_omega"][i] = omega
        a["box_acc"][i] = data.qacc[da : da + 3]
        a["box_alpha"][i] = R @ data.qacc[da + 3 : da + 6]
        a["fingertip_pos"][i] = data.site_xpos[w.tip_site]
        a["hand_qpos"][i] = data.qpos[w.hand_qadr]
        K = len(w.hand.finger_names)
        force = np.zeros((K, 3))
        fn = np.zeros(K)
        cop = np.zeros((K, 3))
        slide = np.zeros(K, bool)
        con = data.contact
        g1, g2 = con.geom1, con.geom2
        sel = np.flatnonzero(((g1 == w.box_geom) | (g2 == w.box_geom)) & (con.efc_address >= 0))
        if len(sel):
            f6 = np.zeros((len(sel), 6))
            for j, c_i in enumerate(sel):
                mujoco.mj_contactForce(m, data, int(c_i), f6[j])
            frame = con.frame[sel].reshape(-1, 3, 3)
            # mj_contactForce gives the force on geom2 in the contact frame (rows: normal, tangents).
            sign = np.where(g2[sel] == w.box_geom, 1.0, -1.0)
            f = sign[:, None] * np.einsum("cji,cj->ci", frame, f6[:, :3])  # on the box, world frame
            n_in = sign[:, None] * frame[:, 0]
            p = con.pos[sel]
            other = np.where(g2[sel] == w.box_geom, g1[sel], g2[sel])
            table = other == w.table_geom
            a["env_force"][i] = f[table].sum(axis=0)
            a["env_torque"][i] = _cross(p[table] - com, f[table]).sum(axis=0)
            finger = w.geom_finger[other]
            palm = ~table & (finger < 0)
            a["palm_force"][i] = f[palm].sum(axis=0)
            on = finger >= 0
            k, f, p, n_in = finger[on], f[on], p[on], n_in[on]
            fnc = np.maximum(np.einsum("cj,cj->c", f, n_in), 0.0)
            np.add.at(force, k, f)
            np.add.at(fn, k, fnc)
            np.add.at(cop, k, fnc[:, None] * p)
            # Slip speed: the pad's material point relative to the box's, tangential to the contact.
            body = m.geom_bodyid[other[on]]
            cvel = data.cvel[body]
            v_finger = cvel[:, 3:] + _cross(cvel[:, :3], p - data.subtree_com[m.body_rootid[body]])
            v_rel = v_finger - (a["box_vel"][i] + _cross(omega, p - com))
            v_t = v_rel - np.einsum("cj,cj->c", v_rel, n_in)[:, None] * n_in
            np.logical_or.at(slide, k, np.linalg.norm(v_t, axis=1) > SLIDING_SPEED_M_S)
        active = fn > 0
        a["contact_active"][i] = active
        a["contact_sliding"][i] = slide & active
        a["contact_force"][i] = force @ R
        safe = np.where(fn > 0, fn, 1.0)
        point = np.where(active[:, None], cop / safe[:, None], data.site_xpos[w.tip_site])
        a["contact_point"][i] = (point - com) @ R
        normal = np.zeros((K, 3))
        # Normal into the box: the box face normal at the centre of pressure.
        local = a["contact_point"][i]
        half = w.obj.half_extents
        axis = np.argmax(np.abs(local) / half, axis=1)
        normal[np.arange(K), axis] = -np.sign(local[np.arange(K), axis])
        a["contact_normal"][i] = normal


@dataclass(frozen=True)
class SimStats:
    """How a simulation went.

    Attributes:
        steps: Physics steps taken.
        timestep_s: Physics step, [s].
        wall_s: Wall-clock time of the stepping loop, [s].
        palm_force_max_n: Largest force of the palm on the box over the frames, [N] (the grasps
            keep the palm off the box, so this should be 0).
    """

    steps: int
    timestep_s: float
    wall_s: float
    palm_force_max_n: float

    @property
    def steps_per_s(self) -> float:
        return self.steps / max(self.wall_s, 1e-9)


def simulate(scenario: Scenario, progress: bool = False) -> Episode:
    """Simulates a scenario and records its ground truth.

    Args:
        scenario: Task, user, grasp, mass, seed and duration.
        progress: Show a progress bar (tqdm) on stderr.

    Returns:
        An :class:`Episode` with ``truth``, ``object_model`` and ``hand_model`` (no depth yet).

    Raises:
        ScenarioError: If the task, user, grasp or mass does not exist.
        SimulationError: If the physics diverges.
    """
    return run(scenario, progress)[0]


def run(scenario: Scenario, progress: bool = False) -> tuple[Episode, SimStats]:
    """:func:`simulate`, also returning the :class:`SimStats` (speed, palm contacts)."""
    validate(scenario)
    task = TASKS[scenario.task]
    duration = duration_of(scenario)
    world = build_world(scenario)
    m = world.model
    spf = steps_per_frame(scenario.fps)
    m.opt.timestep = 1.0 / (scenario.fps * spf)
    d = mujoco.MjData(m)
    start_pos = np.asarray(box_spec()["start_pos"], dtype=float)
    phases = task.phases(duration)
    motion = Motion(start_pos, np.eye(3), task.keyframes(phases, scenario.rng("task")))
    n_frames = int(math.floor(duration * scenario.fps + 1e-9)) + 1
    n_steps = (n_frames - 1) * spf
    ctrl_every = max(1, int(round(CONTROL_PERIOD_S / m.opt.timestep)))
    human = Human(scenario, world, motion, phases, task.releases, np.arange(n_steps + 1) * m.opt.timestep, ctrl_every)
    palm_pos, palm_quat = human.palm_start()
    d.qpos[world.hand_qadr[:3]] = palm_pos
    d.qpos[world.hand_qadr[3:7]] = palm_quat
    d.qpos[world.joint_qadr] = human.plan.q_open
    mujoco.mj_forward(m, d)
    # Let the box settle into its contact with the table (and the hand hang still) before t = 0.
    human.act(d, 0)
    for _ in range(int(round(SETTLE_S / m.opt.timestep))):
        mujoco.mj_step(m, d)
    d.time = 0.0

    rec = _Recorder(world, n_frames)
    bar = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(total=n_frames, desc=f"simulate {scenario.task}", unit="frame", leave=False)
    t0 = time.perf_counter()
    for step in range(n_steps + 1):
        frame, rem = divmod(step, spf)
        human.act(d, step)
        if rem == 0:
            mujoco.mj_forward(m, d)
            rec.record(frame, d)
            if bar is not None:
                bar.update(1)
            if step == n_steps:
                break
        mujoco.mj_step(m, d)
        if step % 200 == 0 and not np.all(np.isfinite(d.qacc)):
            raise SimulationError(f"the simulation diverged at t = {step * m.opt.timestep:.3f} s ({scenario})")
    wall = time.perf_counter() - t0
    if bar is not None:
        bar.close()
    a = rec.a
    if not np.all(np.isfinite(a["box_pos"])):
        raise SimulationError(f"the simulation diverged ({scenario})")
    g = m.opt.gravity.copy()
    R = _rot(a["box_quat"])
    imu_acc = np.einsum("tji,tj->ti", R, a["box_acc"] - g)
    imu_gyro = np.einsum("tji,tj->ti", R, a["box_omega"])
    t = np.arange(n_frames) / scenario.fps
    held = (t >= phases.load_end) & (t <= phases.move_end)
    truth = Truth(
        t=t, box_pos=a["box_pos"], box_quat=a["box_quat"], box_vel=a["box_vel"], box_omega=a["box_omega"],
        box_acc=a["box_acc"], box_alpha=a["box_alpha"], imu_acc=imu_acc, imu_gyro=imu_gyro,
        finger_names=np.array(world.hand.finger_names), contact_active=a["contact_active"],
        contact_sliding=a["contact_sliding"], contact_point=a["contact_point"], contact_normal=a["contact_normal"],
        contact_force=a["contact_force"], env_force=a["env_force"], env_torque=a["env_torque"],
        fingertip_pos=a["fingertip_pos"], hand_qpos=a["hand_qpos"], mass=float(m.body_mass[world.box_body]),
        inertia=np.diag(m.body_inertia[world.box_body]), gravity=g, held=held,
    )
    ep = Episode(scenario=scenario, truth=truth, object_model=world.obj, hand_model=world.hand)
    stats = SimStats(steps=n_steps, timestep_s=float(m.opt.timestep), wall_s=wall,
                     palm_force_max_n=float(np.linalg.norm(a["palm_force"], axis=1).max()))
    return ep, stats


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """a x b along the last axis (np.cross is slow on the small arrays of one frame)."""
    a, b = np.broadcast_arrays(a, b)
    out = np.empty(a.shape)
    out[..., 0] = a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1]
    out[..., 1] = a[..., 2] * b[..., 0] - a[..., 0] * b[..., 2]
    out[..., 2] = a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]
    return out


def _rot(quat: np.ndarray) -> np.ndarray:
    w, x, y, z = np.moveaxis(quat, -1, 0)
    return np.stack(
        [
            np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
            np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
            np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1),
        ],
        -2,
    )
