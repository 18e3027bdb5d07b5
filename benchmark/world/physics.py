"""The physics of one episode: a scenario and its grasp plan in, an episode with its ground truth out.

:func:`run` builds the world, lets the synthetic human (``benchmark.world.grip.Human``) reach, grasp,
load, manipulate and possibly release the box along the task's minimum-jerk motion, and records the
:class:`~benchmark.world.truth.Truth` at the frame times t_k = k / fps.

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

from benchmark.errors import SimulationError
from benchmark.world.assets import World, box_spec, build_world, validate
from benchmark.world.episode import Episode
from benchmark.world.grip import Human
from benchmark.world.scenario import Scenario
from benchmark.world.tasks import TASKS, Motion
from benchmark.world.truth import Truth
from fsv.linalg import mv

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
    """Captures the raw state of each frame from an MjData evaluated by mj_forward.

    :meth:`record` copies only what MuJoCo computed (state, accelerations, the box's contacts and
    their forces); the arrays of the truth are derived afterwards, for all frames at once.
    """

    def __init__(self, world: World, n_frames: int):
        self.w = world
        m = world.model
        T = n_frames
        self.qpos = np.zeros((T, m.nq))
        self.qvel = np.zeros((T, m.nv))
        self.qacc = np.zeros((T, m.nv))
        self.box_R = np.zeros((T, 3, 3))
        self.tips = np.zeros((T, len(world.tip_site), 3))
        self.contacts = []  # per frame: (other geom, pos, frame, force6, sign, v_other)

    def record(self, i: int, data: mujoco.MjData) -> None:
        w, m = self.w, self.w.model
        self.qpos[i] = data.qpos
        self.qvel[i] = data.qvel
        self.qacc[i] = data.qacc
        self.box_R[i] = data.xmat[w.box_body].reshape(3, 3)
        self.tips[i] = data.site_xpos[w.tip_site]
        con = data.contact
        g1, g2 = con.geom1, con.geom2
        sel = np.flatnonzero(((g1 == w.box_geom) | (g2 == w.box_geom)) & (con.efc_address >= 0))
        f6 = np.zeros((len(sel), 6))
        for j, c_i in enumerate(sel):
            mujoco.mj_contactForce(m, data, int(c_i), f6[j])
        on2 = g2[sel] == w.box_geom
        other = np.where(on2, g1[sel], g2[sel])
        body = m.geom_bodyid[other]
        # velocity of the other body's material point at the contact (cvel is about the subtree com)
        cvel = data.cvel[body]
        p = con.pos[sel]
        v_other = cvel[:, 3:] + _cross(cvel[:, :3], p - data.subtree_com[m.body_rootid[body]])
        self.contacts.append((other, p.copy(), con.frame[sel].reshape(-1, 3, 3), f6, np.where(on2, 1.0, -1.0), v_other))

    def arrays(self) -> dict:
        """The truth's per-frame arrays (and the palm's force on the box), all frames at once."""
        w = self.w
        T, K = self.qpos.shape[0], len(w.hand.finger_names)
        qa, da = w.box_qadr, w.box_dadr
        R = self.box_R
        com = self.qpos[:, qa : qa + 3]
        vel = self.qvel[:, da : da + 3]
        omega = np.einsum("tij,tj->ti", R, self.qvel[:, da + 3 : da + 6])
        a = {
            "box_pos": com.copy(), "box_quat": self.qpos[:, qa + 3 : qa + 7].copy(), "box_vel": vel.copy(),
            "box_omega": omega, "box_acc": self.qacc[:, da : da + 3].copy(),
            "box_alpha": np.einsum("tij,tj->ti", R, self.qacc[:, da + 3 : da + 6]),
            "fingertip_pos": self.tips, "hand_qpos": self.qpos[:, w.hand_qadr],
        }
        frame_of = np.concatenate([np.full(len(c[0]), t) for t, c in enumerate(self.contacts)]).astype(np.int64)
        other = np.concatenate([c[0] for c in self.contacts]).astype(np.int64)
        p = np.concatenate([c[1] for c in self.contacts]).reshape(-1, 3)
        cframe = np.concatenate([c[2] for c in self.contacts]).reshape(-1, 3, 3)
        f6 = np.concatenate([c[3] for c in self.contacts]).reshape(-1, 6)
        sign = np.concatenate([c[4] for c in self.contacts])
        v_other = np.concatenate([c[5] for c in self.contacts]).reshape(-1, 3)
        # mj_contactForce gives the force on geom2 in the contact frame (rows: normal, tangents).
        f = sign[:, None] * np.einsum("cji,cj->ci", cframe, f6[:, :3])  # on the box, world frame
        n_in = sign[:, None] * cframe[:, 0]
        r = p - com[frame_of]
        table = other == w.table_geom
        finger = w.geom_finger[other]
        palm = ~table & (finger < 0)
        a["env_force"] = np.zeros((T, 3))
        a["env_torque"] = np.zeros((T, 3))
        a["palm_force"] = np.zeros((T, 3))
        np.add.at(a["env_force"], frame_of[table], f[table])
        np.add.at(a["env_torque"], frame_of[table], _cross(r[table], f[table]))
        np.add.at(a["palm_force"], frame_of[palm], f[palm])
        on = finger >= 0
        t_k, k = frame_of[on], finger[on]
        f, p, n_in, r = f[on], p[on], n_in[on], r[on]
        force, fn, cop = np.zeros((T, K, 3)), np.zeros((T, K)), np.zeros((T, K, 3))
        fnc = np.maximum(np.einsum("cj,cj->c", f, n_in), 0.0)
        np.add.at(force, (t_k, k), f)
        np.add.at(fn, (t_k, k), fnc)
        np.add.at(cop, (t_k, k), fnc[:, None] * p)
        # Slip: the pad's material point relative to the box's, tangential to the contact.
        v_rel = v_other[on] - (vel[t_k] + _cross(omega[t_k], r))
        v_t = v_rel - np.einsum("cj,cj->c", v_rel, n_in)[:, None] * n_in
        slide = np.zeros((T, K), bool)
        np.logical_or.at(slide, (t_k, k), np.linalg.norm(v_t, axis=1) > SLIDING_SPEED_M_S)
        active = fn > 0
        a["contact_active"] = active
        a["contact_sliding"] = slide & active
        a["contact_force"] = np.einsum("tji,tkj->tki", R, force)
        point = np.where(active[..., None], cop / np.where(active, fn, 1.0)[..., None], self.tips)
        local = np.einsum("tji,tkj->tki", R, point - com[:, None])
        a["contact_point"] = local
        # Normal into the box: the face normal at the centre of pressure (the face it is closest to).
        axis = np.argmax(np.abs(local) / w.obj.half_extents, axis=-1)
        normal = np.zeros((T, K, 3))
        np.put_along_axis(normal, axis[..., None], -np.sign(np.take_along_axis(local, axis[..., None], -1)), -1)
        a["contact_normal"] = normal
        return a


class _Momentum:
    """The box's momenta at the boundaries of the frames' intervals, for the truth's frame means.

    Frame k stands for the interval from the boundary before it to the boundary after it: half a
    frame period on either side (the episode's first and last frames end at their own instants).
    By Newton-Euler, the mean contact wrench on the box over an interval is the change of its
    momenta across it divided by its length, less gravity: exact for the force (the integrator
    steps the velocity by the acceleration it computed), to the step's order for the torque.
    """

    def __init__(self, world: World, n_frames: int):
        self.w = world
        self.step = np.zeros(n_frames + 1, np.int64)
        self.lin = np.zeros((n_frames + 1, 3))  # linear velocity of the centre of mass, world frame, [m/s]
        self.ang = np.zeros((n_frames + 1, 3))  # angular momentum about it, world frame, [kg m^2/s]

    def record(self, i: int, step: int, data: mujoco.MjData) -> None:
        """Boundary ``i`` (0: the first frame's instant, n_frames: the last's), reached at physics step ``step``."""
        w, m = self.w, self.w.model
        qa, da = w.box_qadr, w.box_dadr
        R = _rot(data.qpos[qa + 3 : qa + 7][None])[0]
        self.step[i] = step
        self.lin[i] = data.qvel[da : da + 3]
        self.ang[i] = mv(R, m.body_inertia[w.box_body] * data.qvel[da + 3 : da + 6])

    def mean_wrench(self, timestep_s: float, gravity: np.ndarray) -> np.ndarray:
        """Mean contact wrench on the box over each frame's interval, world frame, (T, 6): force [N]
        and torque about the centre of mass [N m]."""
        mass = float(self.w.model.body_mass[self.w.box_body])
        span = (np.diff(self.step) * timestep_s)[:, None]
        force = mass * np.diff(self.lin, axis=0) / span - mass * np.asarray(gravity, float)
        return np.concatenate([force, np.diff(self.ang, axis=0) / span], axis=1)


@dataclass(frozen=True)
class SimStats:
    """How a simulation went.

    Attributes:
        steps: Physics steps taken.
        timestep_s: Physics step, [s].
        wall_s: Wall-clock time of the stepping loop, [s].
    """

    steps: int
    timestep_s: float
    wall_s: float

    @property
    def steps_per_s(self) -> float:
        return self.steps / max(self.wall_s, 1e-9)


def run(scenario: Scenario, plan, progress: bool = False) -> tuple[Episode, SimStats]:
    """Simulates a scenario with a given grasp plan and records its ground truth.

    Args:
        scenario: Task, user, grasp, mass, seed and duration.
        plan: The grasp's ``benchmark.world.grasp_plan.GraspPlan`` for the scenario's person
            (``benchmark.world.simulate`` resolves the scenario's own).
        progress: Show a progress bar (tqdm) on stderr.

    Returns:
        The :class:`Episode` (``truth``, ``object_model``, ``hand_model``; no depth yet) and its
        :class:`SimStats` (speed).

    Raises:
        ScenarioError: If the task, user, grasp or mass does not exist.
        SimulationError: If the physics diverges, the hand drops the box or its palm touches it.
    """
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
    human = Human(scenario, world, plan, motion, phases, task.releases, np.arange(n_steps + 1) * m.opt.timestep, ctrl_every)
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
    momentum = _Momentum(world, n_frames)
    bar = None
    if progress:
        from tqdm import tqdm  # lazy: tqdm (30 ms) off `fsv-bench`'s start-up

        bar = tqdm(total=n_frames, desc=f"simulate {scenario.task}", unit="frame", leave=False)
    t0 = time.perf_counter()
    _step_frames(m, d, human.act, rec, momentum, spf, n_frames, scenario, bar)
    wall = time.perf_counter() - t0
    if bar is not None:
        bar.close()
    truth = _truth(scenario, world, rec.arrays(), momentum, phases, motion, n_frames)
    ep = Episode(scenario=scenario, truth=truth, object_model=world.obj, hand_model=world.hand)
    stats = SimStats(steps=n_steps, timestep_s=float(m.opt.timestep), wall_s=wall)
    return ep, stats


def _step_frames(m, d, act, rec: _Recorder, momentum: _Momentum, spf: int, n_frames: int, scenario: Scenario,
                 bar) -> None:
    """Steps the simulation through every frame: the human acts every step; each frame's state and
    the momentum at the frames' interval boundaries are recorded."""
    half = (spf + 1) // 2  # the boundary between frames k and k + 1 is this many steps after frame k
    step_fn = mujoco.mj_step
    for frame in range(n_frames):
        step = frame * spf
        act(d, step)
        mujoco.mj_forward(m, d)
        rec.record(frame, d)
        if frame == 0:
            momentum.record(0, step, d)
        if not np.all(np.isfinite(d.qacc)):
            raise SimulationError(f"the simulation diverged at t = {step * m.opt.timestep:.3f} s ({scenario})")
        if bar is not None:
            bar.update(1)
        if frame == n_frames - 1:
            momentum.record(n_frames, step, d)
            break
        step_fn(m, d)
        if half == 1:
            momentum.record(frame + 1, step + 1, d)
        for s in range(step + 1, step + spf):
            act(d, s)
            step_fn(m, d)
            if s + 1 == step + half:
                momentum.record(frame + 1, s + 1, d)


def _truth(scenario: Scenario, world, a: dict, momentum: _Momentum, phases, motion, n_frames: int) -> Truth:
    """The :class:`Truth` of the recorded arrays ``a`` (checked: finite, and the box where the task put it)."""
    m = world.model
    if not np.all(np.isfinite(a["box_pos"])):
        raise SimulationError(f"the simulation diverged ({scenario})")
    g = m.opt.gravity.copy()
    R = _rot(a["box_quat"])
    imu_acc = np.einsum("tji,tj->ti", R, a["box_acc"] - g)
    imu_gyro = np.einsum("tji,tj->ti", R, a["box_omega"])
    t = np.arange(n_frames) / scenario.fps
    held = (t >= phases.load_end) & (t <= phases.move_end)
    _check_outcome(scenario, t, held, a, motion.evaluate(t)[0])
    return Truth(
        t=t, box_pos=a["box_pos"], box_quat=a["box_quat"], box_vel=a["box_vel"], box_omega=a["box_omega"],
        box_acc=a["box_acc"], box_alpha=a["box_alpha"], imu_acc=imu_acc, imu_gyro=imu_gyro,
        finger_names=np.array(world.hand.finger_names), contact_active=a["contact_active"],
        contact_sliding=a["contact_sliding"], contact_point=a["contact_point"], contact_normal=a["contact_normal"],
        contact_force=a["contact_force"], env_force=a["env_force"], env_torque=a["env_torque"],
        fingertip_pos=a["fingertip_pos"], hand_qpos=a["hand_qpos"],
        net_wrench_mean=momentum.mean_wrench(m.opt.timestep, g), mass=float(m.body_mass[world.box_body]),
        inertia=np.diag(m.body_inertia[world.box_body]), gravity=g, held=held,
    )


DROP_M = 0.03  # the hand has dropped the box if it is this far below its planned height while held


def _check_outcome(scenario: Scenario, t: np.ndarray, held: np.ndarray, a: dict, planned_pos: np.ndarray) -> None:
    """Raises SimulationError if the hand dropped the box or its palm touched it.

    A palm contact is real physics, but the truth has one force per finger only, so an episode
    with one would not satisfy Newton-Euler with its own recorded forces.
    """
    sag = planned_pos[:, 2] - a["box_pos"][:, 2]
    dropped = held & (sag > DROP_M)
    if dropped.any():
        raise SimulationError(f"the hand dropped the box at t = {t[np.argmax(dropped)]:.2f} s "
                              f"({sag[dropped].max() * 1000:.0f} mm below the plan) in {scenario}")
    palm = np.linalg.norm(a["palm_force"], axis=1) > 0
    if palm.any():
        raise SimulationError(f"the palm touched the box at t = {t[np.argmax(palm)]:.2f} s in {scenario}; the "
                              f"truth records finger contacts only (a longer duration gives gentler motions)")


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
