"""A third-party differentiator for fsv-bench: Savitzky-Golay filtering of the tracked box poses.

Score it on the smoke suite without touching fsv-bench (from the folder that holds ``examples/``)::

    fsv-bench eval --suite smoke --differentiator examples.savgol:SavitzkyGolay --out runs/savgol

Any callable ``(poses: fsv.Poses) -> fsv.Kinematics`` is a differentiator; a class is instantiated
without arguments, and its ``name`` labels it in the reports. This one uses only NumPy, SciPy and
fsv's public records. Its window and order were chosen once, by hand, before scoring (not tuned).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.signal import savgol_filter
from scipy.spatial.transform import Rotation

from fsv import Kinematics, Poses


@dataclass(frozen=True)
class SavitzkyGolay:
    """Local cubic least-squares fits over a sliding window (Savitzky & Golay, 1964).

    Attributes:
        window_frames: Odd window length in frames (21 at 30 fps: 0.7 s).
        order: Polynomial order of the local fits.
    """

    window_frames: int = 21
    order: int = 3

    @property
    def name(self) -> str:
        return f"Savitzky-Golay (window {self.window_frames} frames, order {self.order})"

    def __call__(self, poses: Poses) -> Kinematics:
        T, W = len(poses), self.window_frames
        dt = float(np.median(np.diff(poses.t)))
        fit = dict(window_length=W, polyorder=self.order, axis=0, mode="interp")
        pos = savgol_filter(poses.pos, deriv=0, **fit)
        vel = savgol_filter(poses.pos, deriv=1, delta=dt, **fit)
        acc = savgol_filter(poses.pos, deriv=2, delta=dt, **fit)
        q = Rotation.from_matrix(poses.rot).as_quat()  # (x, y, z, w)
        q *= np.where(np.cumprod(np.r_[1.0, np.sign(np.sum(q[1:] * q[:-1], axis=1) + 1e-12)]) < 0, -1.0, 1.0)[:, None]
        q_smooth = savgol_filter(q, deriv=0, **fit)
        q_dot = savgol_filter(q, deriv=1, delta=dt, **fit)
        rot = Rotation.from_quat(q_smooth / np.linalg.norm(q_smooth, axis=1, keepdims=True))
        # world-frame angular velocity: omega = 2 vec(q_dot * conj(q)) for unit q
        omega = 2.0 * _quat_product(q_dot, q * np.array([-1.0, -1.0, -1.0, 1.0]))[:, :3]
        alpha = savgol_filter(omega, deriv=1, delta=dt, **fit)
        valid = np.zeros(T, bool)
        valid[W // 2 : T - W // 2] = True  # the ends are extrapolated fits: not scored
        return Kinematics(t=poses.t, pos=pos, rot=rot.as_matrix(), vel=vel, acc=acc, omega=omega, alpha=alpha,
                          valid=valid, method="savitzky-golay", delay_s=0.0)


def _quat_product(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton product of (x, y, z, w) quaternions, row by row."""
    ax, ay, az, aw = a.T
    bx, by, bz, bw = b.T
    return np.stack([aw * bx + ax * bw + ay * bz - az * by,
                     aw * by - ax * bz + ay * bw + az * bx,
                     aw * bz + ax * by - ay * bx + az * bw,
                     aw * bw - ax * bx - ay * by - az * bz], axis=1)
