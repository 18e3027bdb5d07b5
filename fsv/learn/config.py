"""What the networks learn from and how: :class:`LearnConfig` and the :class:`TrainingSet` of samples."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from fsv.errors import InputError
from fsv.features import Features

GRIP_INPUTS = 2
"""Inputs a grip calibration adds to the networks' (:meth:`fsv.grip.GripCalibration.vector`)."""

AMOUNT_LOSSES = ("squared", "relative")
"""The training losses of ANN_L2 (:attr:`LearnConfig.amount_loss`)."""

@dataclass(frozen=True)
class LearnConfig:
    """Architecture and training of the two networks.

    Attributes:
        hidden_l2: Hidden layer sizes of ANN_L2 (the paper: 6, 7).
        hidden_decomp: Hidden layer sizes of ANN_decomp (the paper: 8, 13).
        epochs: Full-batch Rprop iterations per network.
        lr: Rprop's initial step size.
        etas: Rprop's (decrease, increase) factors.
        step_sizes: Rprop's (min, max) step sizes.
        folds: Number of folds for :func:`cross_validate`.
        seed: Seed of the weight initialisation.
        min_l2_n: Samples whose internal-force norm is below this [N] carry no share information
            and are left out of ANN_decomp's loss.
        members: Pairs of networks trained from different initial weights; predictions are
            their average (1: the paper's single pair).
        amount_loss: ANN_L2's training loss, one of :data:`AMOUNT_LOSSES`: ``"squared"``, the mean
            squared error of the standardised amount (the paper's); ``"relative"``, the mean
            relative error |a_hat - a| / max(a, relative_floor_n), the error the forces are scored by.
        relative_floor_n: Smallest amount a relative error is taken against, [N].
        grip_inputs: The networks also take the person's grip calibration
            (:class:`fsv.grip.GripCalibration`, two values) beside the paper's features.
    """

    hidden_l2: tuple = (6, 7)
    hidden_decomp: tuple = (8, 13)
    epochs: int = 1500
    lr: float = 0.01
    etas: tuple = (0.5, 1.2)
    step_sizes: tuple = (1e-6, 50.0)
    folds: int = 5
    seed: int = 0
    min_l2_n: float = 0.05
    members: int = 1
    amount_loss: str = "squared"
    relative_floor_n: float = 1.0
    grip_inputs: bool = False

    def __post_init__(self):
        for name in ("hidden_l2", "hidden_decomp"):
            h = tuple(int(v) for v in getattr(self, name))
            if len(h) == 0 or any(v <= 0 for v in h):
                raise InputError(f"LearnConfig.{name} must be a non-empty tuple of positive sizes, got {h}")
            object.__setattr__(self, name, h)
        for name in ("epochs", "folds", "seed", "members"):
            v = getattr(self, name)
            low = 2 if name == "folds" else 0 if name == "seed" else 1
            if isinstance(v, bool) or int(v) != v or v < low:
                raise InputError(f"LearnConfig.{name} must be an integer >= {low}, got {v!r}")
            object.__setattr__(self, name, int(v))
        if not (self.lr > 0 and self.min_l2_n >= 0):
            raise InputError(f"LearnConfig.lr must be > 0 and min_l2_n >= 0, got {self.lr!r}, {self.min_l2_n!r}")
        if self.amount_loss not in AMOUNT_LOSSES:
            raise InputError(f"LearnConfig.amount_loss must be one of {', '.join(AMOUNT_LOSSES)}, got {self.amount_loss!r}")
        if not (isinstance(self.relative_floor_n, (int, float)) and self.relative_floor_n > 0):
            raise InputError(f"LearnConfig.relative_floor_n must be a number of newtons > 0, got {self.relative_floor_n!r}")
        if not isinstance(self.grip_inputs, bool):
            raise InputError(f"LearnConfig.grip_inputs must be True or False, got {self.grip_inputs!r}")
        object.__setattr__(self, "etas", tuple(float(v) for v in self.etas))
        object.__setattr__(self, "step_sizes", tuple(float(v) for v in self.step_sizes))


@dataclass(frozen=True)
class TrainingSet:
    """Samples for the two networks: one row per (frame, hand).

    Attributes:
        x: Network inputs (see :meth:`fsv.features.Features.matrix`), shape (N, 2 + 3K).
        internal: Internal normal forces f_k^(i) per finger (eq. 9's decomposition), shape (N, K),
            [N]; ignored where not active.
        active: Finger k in contact, shape (N, K).
        groups: Group label per sample (e.g. the episode), shape (N,); cross-validation folds
            never split a group.
        grip: The grip calibration of the person in each sample
            (:meth:`fsv.grip.GripCalibration.vector`), shape (N, 2); None if not known.
    """

    x: np.ndarray
    internal: np.ndarray
    active: np.ndarray
    groups: np.ndarray = field(default=None)
    grip: np.ndarray = field(default=None)

    def __post_init__(self):
        x = np.asarray(self.x, dtype=np.float64)
        f = np.asarray(self.internal, dtype=np.float64)
        a = np.asarray(self.active, dtype=bool)
        if x.ndim != 2 or f.ndim != 2 or a.shape != f.shape or x.shape[0] != f.shape[0]:
            raise InputError(f"TrainingSet: x (N, D), internal and active (N, K) expected, got {x.shape}, {f.shape}, {a.shape}")
        K = f.shape[1]
        if x.shape[1] != 2 + 3 * K:
            raise InputError(f"TrainingSet.x must have 2 + 3K = {2 + 3 * K} columns for K = {K} fingers, got {x.shape[1]}")
        if not (np.all(np.isfinite(x)) and np.all(np.isfinite(f))):
            raise InputError("TrainingSet.x and .internal must be finite")
        g = np.arange(x.shape[0]) if self.groups is None else np.asarray(self.groups)
        if g.shape != (x.shape[0],):
            raise InputError(f"TrainingSet.groups must have shape ({x.shape[0]},), got {g.shape}")
        grip = None
        if self.grip is not None:
            grip = np.asarray(self.grip, dtype=np.float64)
            if grip.shape != (x.shape[0], GRIP_INPUTS) or not np.all(np.isfinite(grip)):
                raise InputError(f"TrainingSet.grip must be finite with shape ({x.shape[0]}, {GRIP_INPUTS}), got {grip.shape}")
        for k, v in dict(x=x, internal=np.where(a, f, 0.0), active=a, groups=g, grip=grip).items():
            object.__setattr__(self, k, v)

    def __len__(self) -> int:
        return self.x.shape[0]

    @property
    def num_fingers(self) -> int:
        return self.internal.shape[1]

    def subset(self, index) -> "TrainingSet":
        grip = None if self.grip is None else self.grip[index]
        return TrainingSet(self.x[index], self.internal[index], self.active[index], self.groups[index], grip)

    def inputs(self, grip_inputs: bool) -> np.ndarray:
        """The networks' inputs: ``x``, followed by ``grip`` if ``grip_inputs``, shape (N, 2 + 3K [+ 2])."""
        if not grip_inputs:
            return self.x
        if self.grip is None:
            raise InputError("networks with grip inputs need TrainingSet.grip, the grip calibration of every sample")
        return np.concatenate([self.x, self.grip], axis=1)

    @staticmethod
    def from_features(features: Features, internal: np.ndarray, groups=None) -> "TrainingSet":
        return TrainingSet(features.matrix(), internal, features.active, groups)
