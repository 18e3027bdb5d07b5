"""Ground truth recorded by the simulator at frame times (see docs/design.md, "Truth")."""

from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np

from benchmark.errors import BenchmarkError
from fsv.rotation import quat_to_rot


@dataclass(frozen=True)
class Truth:
    """Everything the simulator knows, sampled at t_k = k / fps. K fingers, thumb first.

    World frame unless stated. Object-frame quantities are expressed along the box's edges with
    the origin at its centre of mass.

    Attributes:
        t: Frame times, (T,), [s].
        box_pos: Centre-of-mass position, (T, 3), [m].
        box_quat: Orientation world_q_object (w, x, y, z), (T, 4).
        box_vel: Linear velocity of the centre of mass, (T, 3), [m/s].
        box_omega: Angular velocity, world frame, (T, 3), [rad/s].
        box_acc: Linear acceleration of the centre of mass, (T, 3), [m/s^2].
        box_alpha: Angular acceleration, world frame, (T, 3), [rad/s^2].
        imu_acc: Specific force R^T (a - g) in the box frame, (T, 3), [m/s^2].
        imu_gyro: Angular velocity in the box frame, (T, 3), [rad/s].
        finger_names: (K,).
        contact_active: Finger k touches the box, (T, K).
        contact_sliding: That contact slides, (T, K).
        contact_point: Centre of pressure on the box, object frame, (T, K, 3), [m].
        contact_normal: Unit normal into the box, object frame, (T, K, 3).
        contact_force: Force of finger k on the box, object frame, (T, K, 3), [N].
        env_force: Force of the table on the box, world frame, (T, 3), [N].
        env_torque: Torque of the table on the box about the centre of mass, world frame, (T, 3), [N m].
        fingertip_pos: Fingertip centres, world frame, (T, K, 3), [m].
        net_wrench_mean: Mean over frame k's interval (half a frame period on either side of t_k)
            of the resultant contact wrench on the box, fingers and table, world frame: force [N]
            and torque about the centre of mass [N m], (T, 6). What a camera at the frame rate can
            resolve: the instantaneous forces also hold contact transients of a few milliseconds
            that move the box by less than a frame can show. From the box's momenta at the
            intervals' boundaries (``benchmark.world.simulate``).
        hand_qpos: Hand joint angles, (T, n), [rad].
        mass: Box mass, [kg].
        inertia: Box inertia about the centre of mass, box frame, (3, 3), [kg m^2].
        gravity: (3,), [m/s^2].
        held: Frames in which the hand carries the box (between the end of the load phase and
            the start of a put-down), (T,) bool; None if unknown.
    """

    t: np.ndarray
    box_pos: np.ndarray
    box_quat: np.ndarray
    box_vel: np.ndarray
    box_omega: np.ndarray
    box_acc: np.ndarray
    box_alpha: np.ndarray
    imu_acc: np.ndarray
    imu_gyro: np.ndarray
    finger_names: np.ndarray
    contact_active: np.ndarray
    contact_sliding: np.ndarray
    contact_point: np.ndarray
    contact_normal: np.ndarray
    contact_force: np.ndarray
    env_force: np.ndarray
    env_torque: np.ndarray
    fingertip_pos: np.ndarray
    hand_qpos: np.ndarray
    net_wrench_mean: np.ndarray
    mass: float
    inertia: np.ndarray
    gravity: np.ndarray
    held: np.ndarray | None = None

    def __post_init__(self):
        T = np.shape(self.t)[0]
        K = len(self.finger_names)
        want = {
            "box_pos": (T, 3), "box_quat": (T, 4), "box_vel": (T, 3), "box_omega": (T, 3),
            "box_acc": (T, 3), "box_alpha": (T, 3), "imu_acc": (T, 3), "imu_gyro": (T, 3),
            "contact_active": (T, K), "contact_sliding": (T, K), "contact_point": (T, K, 3),
            "contact_normal": (T, K, 3), "contact_force": (T, K, 3), "env_force": (T, 3),
            "env_torque": (T, 3), "fingertip_pos": (T, K, 3), "net_wrench_mean": (T, 6), "inertia": (3, 3), "gravity": (3,),
        }
        for name, shape in want.items():
            got = np.shape(getattr(self, name))
            if got != shape:
                raise BenchmarkError(f"Truth.{name} must have shape {shape}, got {got}")
        if self.held is not None and np.shape(self.held) != (T,):
            raise BenchmarkError(f"Truth.held must have shape ({T},), got {np.shape(self.held)}")
        if np.shape(self.hand_qpos)[0] != T:
            raise BenchmarkError(f"Truth.hand_qpos must have {T} rows, got {np.shape(self.hand_qpos)}")

    @property
    def box_rot(self) -> np.ndarray:
        """world_R_object rotation matrices, (T, 3, 3)."""
        return quat_to_rot(self.box_quat)

    def newton_euler_residual(self) -> tuple[np.ndarray, np.ndarray]:
        """How far the recorded forces are from explaining the recorded motion.

        Force: m (a - g) - (sum of finger forces + table force). Torque about the centre of mass:
        J alpha + omega x J omega - (sum of r_k x F_k + table torque), world frame, with
        J = R J_box R^T and r_k the finger's centre of pressure relative to the centre of mass.

        Returns:
            ``(force (T, 3) [N], torque (T, 3) [N m])``.
        """
        R = self.box_rot
        f = np.einsum("tij,tkj->tki", R, self.contact_force)
        r = np.einsum("tij,tkj->tki", R, self.contact_point)
        force = self.mass * (self.box_acc - self.gravity) - f.sum(axis=1) - self.env_force
        J = np.einsum("tij,jk,tlk->til", R, self.inertia, R)
        Jw = np.einsum("tij,tj->ti", J, self.box_omega)
        torque = (np.einsum("tij,tj->ti", J, self.box_alpha) + np.cross(self.box_omega, Jw)
                  - np.cross(r, f).sum(axis=1) - self.env_torque)
        return force, torque

    def normal_force(self) -> np.ndarray:
        """Normal component of each finger's force (pressing into the box is positive), (T, K), [N]."""
        return np.einsum("tkj,tkj->tk", self.contact_force, self.contact_normal)

    def as_dict(self) -> dict:
        return {f.name: getattr(self, f.name) for f in fields(self)}
