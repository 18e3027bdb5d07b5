"""Learning how humans share internal grip forces (the paper's §3.6): two small networks.

* ``ANN_L2`` predicts the amount of internal force, ||f^(i)||_2 over the fingers in contact, [N].
* ``ANN_decomp`` predicts each finger's share, f_k^(i) / ||f^(i)||_2 (dimensionless).

Both take the features of :mod:`fsv.features` (eq. 10-13), are multilayer perceptrons with logistic
(sigmoid) hidden neurons and a linear output (like R's ``neuralnet`` with ``linear.output=TRUE``),
two hidden layers of (6, 7) and (8, 13) neurons as in the paper, and are trained full-batch with
resilient backpropagation (``torch.optim.Rprop``) on standardised inputs. ANN_L2's loss is the
paper's squared error or, with ``LearnConfig.amount_loss="relative"``, the mean relative error
|a_hat - a| / max(a, 1 N), the error the forces are scored by (the shipped model's): when people
who grip differently show the same motion, the first predicts their mean squeeze, the second a
median weighted by 1 / a.

Members. ``LearnConfig.members`` pairs of networks are trained from different initial weights
(one seeded generator, drawn in turn) and their outputs are averaged: the mean norm, and the mean
share vector renormalised. ``members=1`` is the paper's single pair; a few members average out
the dependence of a small network on its initial weights (``fsv-bench train`` and the Table 2
scorer say how many they used).

The person. The paper's features carry the motion and the contact geometry, nothing of who
squeezes, and people add very different amounts of internal force to the same motion. With
``LearnConfig.grip_inputs`` both networks also take the person's grip calibration
(:class:`fsv.grip.GripCalibration`: the amount of internal force against the load, fitted to a
short calibration recording with force sensors), two more inputs after the features. Such a model
assumes, for a person without a calibration, the mean calibration of its training samples.

Fingers not in contact. The hand has a fixed number K of finger slots (thumb first). The input is
``[p1, p3, p2_1..p2_K, p4_1..p4_K, active_1..active_K]`` (2 + 3K values) with p2_k = p4_k = 0 for
a finger not in contact, so the network sees which fingers touch. ``ANN_decomp`` has K outputs;
its loss counts only the fingers in contact, and at prediction time the shares of fingers not in
contact are set to 0 and the remaining shares are rescaled to unit L2 norm, so that the predicted
internal forces have exactly the norm ``ANN_L2`` predicts.

Determinism. Weights are drawn from a ``torch.Generator`` seeded with ``LearnConfig.seed``; the
global torch RNG is neither read nor advanced. Rprop on the full batch has no randomness, and
training runs single-threaded (the thread count is restored afterwards) so that floating-point
reductions happen in one order: the same data and config give bit-identical weights. Everything
is float64.

Forces. :func:`learned_forces` chains the features, the networks and the reconstruction SOCP
(eq. 14, :func:`fsv.forces.reconstruct_forces`): full contact forces that explain the motion and
whose internal normal components follow the predictions. Before the reconstruction, the predicted
amount of internal force (ANN_L2's output) is averaged over time with a Gaussian window of
:data:`AMOUNT_SMOOTHING_S` (:func:`smooth_over_time`); the shares stay per frame. The networks see
one frame's features, which tracked contacts and differentiated poses make noisy, while a person's
squeeze varies slowly; the window was chosen on the ``dev`` suite (docs/findings.md, "The amount
of internal force over time"). The paper's Table 2 protocol scores the networks per sample and
is not smoothed.

Files. :meth:`InternalForceModel.save` writes one NumPy ``.npz`` archive (weights and biases of
every layer, input and target normalisation; a JSON header with the config, finger names and
free-form metadata with the provenance of the environment that first wrote it,
:func:`fsv.provenance.provenance`) atomically, with a SHA-256 of all of that
(:func:`content_sha256`); :func:`load` reads it back without pickles, recomputes the digest and
refuses the file if it differs. Torch is needed to train, not to load or predict: the forward
pass is a few NumPy contractions (no BLAS, so the same bits on every BLAS kernel), which keeps the
~1.4 s import of torch out of every command that only applies a model.
"""

from __future__ import annotations

import os
import tempfile
from dataclasses import asdict, dataclass, field

import json

import numpy as np

from fsv.digest import tree_sha256
from fsv.errors import InputError, one_line
from fsv.features import GRAVITY, Features, grasp_features
from fsv.forces import ForceSettings, ForceSolution, reconstruct_forces
from fsv.models import ObjectModel
from fsv.types import Contacts, Kinematics

AMOUNT_SMOOTHING_S = 1.0
"""Standard deviation of the Gaussian window over which :func:`learned_forces` averages the predicted
amount of internal force, [s]; 0 turns it off. Chosen on ``dev`` with tracked inputs (median error
of the final forces over its 48 episodes: 20.7 % per frame, 19.0 % at 0.1 s, 18.1 % at 0.25 s, 17.3 % at 0.5 s,
17.1 % at 1 s and at 2 s; the middle of the plateau)."""

GRIP_INPUTS = 2
"""Inputs a grip calibration adds to the networks' (:meth:`fsv.grip.GripCalibration.vector`)."""

AMOUNT_LOSSES = ("squared", "relative")
"""The training losses of ANN_L2 (:attr:`LearnConfig.amount_loss`)."""

FORMAT = "fsv-internal-forces"
VERSION = 4  # versions 1 and 2 carried no digest; 3 was a torch archive. None of them is read


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


def _targets(internal: np.ndarray, active: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    f = np.where(active, internal, 0.0)
    l2 = np.linalg.norm(f, axis=1)
    shares = f / np.where(l2 > 0, l2, 1.0)[:, None]
    return l2, shares


def _mlp(n_in: int, hidden: tuple, n_out: int, gen):
    """A torch MLP (sigmoid hidden layers, linear output) with weights drawn from ``gen``."""
    import torch

    layers, prev = [], n_in
    for h in hidden:
        layers += [torch.nn.utils.skip_init(torch.nn.Linear, prev, h, dtype=torch.float64), torch.nn.Sigmoid()]
        prev = h
    layers.append(torch.nn.utils.skip_init(torch.nn.Linear, prev, n_out, dtype=torch.float64))
    with torch.no_grad():
        for m in layers:
            if isinstance(m, torch.nn.Linear):
                b = 1.0 / np.sqrt(m.in_features)
                torch.nn.init.uniform_(m.weight, -b, b, generator=gen)
                torch.nn.init.uniform_(m.bias, -b, b, generator=gen)
    return torch.nn.Sequential(*layers)


def _rprop(net, x, loss_fn, config: LearnConfig, on_epoch=None) -> float:
    import torch

    opt = torch.optim.Rprop(net.parameters(), lr=config.lr, etas=config.etas, step_sizes=config.step_sizes, foreach=False)
    loss = None
    for _ in range(config.epochs):
        opt.zero_grad()
        loss = loss_fn(net(x))
        loss.backward()
        opt.step()
        if on_epoch is not None:
            on_epoch(1)
    with torch.no_grad():
        return float(loss_fn(net(x)))


def _layers(net) -> list:
    """The (weight (out, in), bias (out,)) pairs of a torch MLP's linear layers, as float64 arrays."""
    import torch

    return [(m.weight.detach().numpy().copy(), m.bias.detach().numpy().copy())
            for m in net if isinstance(m, torch.nn.Linear)]


def forward(layers: list, z: np.ndarray) -> np.ndarray:
    """An MLP's output: logistic hidden layers, linear output layer.

    Args:
        layers: (weight (out, in), bias (out,)) per layer.
        z: Standardised inputs, shape (N, in).

    Returns:
        Shape (N, out of the last layer).
    """
    h = z
    for i, (W, b) in enumerate(layers):
        h = np.einsum("ni,oi->no", h, W) + b
        if i < len(layers) - 1:
            with np.errstate(over="ignore"):  # exp(-h) = inf far below 0: the logistic is 0 there
                h = 1.0 / (1.0 + np.exp(-h))
    return h


class InternalForceModel:
    """The trained pair of networks with their normalisation.

    Attributes:
        config: How they were built and trained.
        finger_names: The K finger slots, thumb first.
        x_mean, x_std: Input standardisation, shape (2 + 3K,), or (2 + 3K + 2,) with grip inputs.
        l2_mean, l2_std: Standardisation of ANN_L2's target, [N].
        net_l2, net_decomp: The networks, one per member (lists of ``config.members``); each is its
            list of (weight (out, in), bias (out,)) float64 layers (see :func:`forward`).
        metadata: Free-form description (dataset, command, losses); JSON-like values only.
        grip_mean: With grip inputs, the mean grip calibration of the training samples, shape (2,):
            what :meth:`predict` assumes for a person without one; None otherwise.
    """

    def __init__(self, config, finger_names, x_mean, x_std, l2_mean, l2_std, net_l2, net_decomp, metadata=None,
                 grip_mean=None):
        self.config = config
        self.finger_names = tuple(str(n) for n in finger_names)
        self.x_mean = np.asarray(x_mean, dtype=np.float64)
        self.x_std = np.asarray(x_std, dtype=np.float64)
        self.l2_mean = float(l2_mean)
        self.l2_std = float(l2_std)
        self.net_l2 = [[(np.asarray(W, np.float64), np.asarray(b, np.float64)) for W, b in net] for net in net_l2]
        self.net_decomp = [[(np.asarray(W, np.float64), np.asarray(b, np.float64)) for W, b in net] for net in net_decomp]
        if len(self.net_l2) != len(self.net_decomp) or not self.net_l2:
            raise InputError(f"a model needs as many ANN_L2 as ANN_decomp networks (>= 1), got {len(self.net_l2)}, "
                             f"{len(self.net_decomp)}")
        self.metadata = dict(metadata or {})
        if config.grip_inputs:
            g = np.asarray(grip_mean if grip_mean is not None else np.full(GRIP_INPUTS, np.nan), dtype=np.float64)
            if g.shape != (GRIP_INPUTS,) or not np.all(np.isfinite(g)):
                raise InputError(f"a model with grip inputs needs a finite grip_mean of shape ({GRIP_INPUTS},), got {grip_mean!r}")
            self.grip_mean = g
        else:
            self.grip_mean = None

    @property
    def num_fingers(self) -> int:
        return len(self.finger_names)

    @property
    def num_inputs(self) -> int:
        """Network inputs: 2 + 3K features, and 2 more with grip inputs."""
        return 2 + 3 * self.num_fingers + (GRIP_INPUTS if self.config.grip_inputs else 0)

    def grip_columns(self, grip, n: int) -> np.ndarray:
        """The grip inputs of ``n`` samples, shape (n, 2): ``grip`` ((2,), (n, 2), a
        :class:`fsv.grip.GripCalibration`, or None for :attr:`grip_mean`)."""
        if grip is None:
            g = self.grip_mean
        elif hasattr(grip, "vector"):
            g = grip.vector()
        else:
            g = np.asarray(grip, dtype=np.float64)
        g = np.broadcast_to(g, (n, GRIP_INPUTS)) if np.shape(g) in ((GRIP_INPUTS,), (n, GRIP_INPUTS)) else None
        if g is None or not np.all(np.isfinite(g)):
            raise InputError(f"grip must be a GripCalibration, or finite values of shape ({GRIP_INPUTS},) or "
                             f"({n}, {GRIP_INPUTS}), got {grip!r:.80}")
        return g

    def predict(self, x: np.ndarray, active: np.ndarray, grip=None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Predicts the internal forces of each finger in contact.

        Args:
            x: The paper's features, shape (N, 2 + 3K) (see :meth:`fsv.features.Features.matrix`).
            active: Finger in contact, shape (N, K).
            grip: With grip inputs, the person's grip calibration (see :meth:`grip_columns`);
                None assumes the training samples' mean. Ignored by a model without grip inputs.

        Returns:
            ``(l2, shares, internal)``: the internal-force norm, shape (N,), [N] (clipped at 0);
            the per-finger shares, shape (N, K), unit L2 norm over the active fingers and 0
            elsewhere; and the internal normal forces l2 * shares, shape (N, K), [N]. With several
            members, the norm is their mean and the shares their mean, renormalised.
        """
        x = np.asarray(x, dtype=np.float64)
        a = np.asarray(active, dtype=bool)
        K = self.num_fingers
        if x.ndim != 2 or x.shape[1] != 2 + 3 * K or a.shape != (x.shape[0], K):
            raise InputError(f"predict expects x of shape (N, {2 + 3 * K}) and active of shape (N, {K}), got {x.shape}, {a.shape}")
        if self.config.grip_inputs:
            x = np.concatenate([x, self.grip_columns(grip, x.shape[0])], axis=1)
        z = (x - self.x_mean) / self.x_std
        l2 = np.mean([forward(net, z)[:, 0] for net in self.net_l2], axis=0) * self.l2_std + self.l2_mean
        s = np.zeros((x.shape[0], K))
        for net in self.net_decomp:
            out = np.where(a, forward(net, z), 0.0)
            n = np.linalg.norm(out, axis=1)
            s += out / np.where(n > 0, n, 1.0)[:, None]
        norm = np.linalg.norm(s, axis=1)
        s = s / np.where(norm > 0, norm, 1.0)[:, None]
        l2 = np.maximum(l2, 0.0)
        return l2, s, l2[:, None] * s

    def predict_features(self, features: Features, grip=None) -> np.ndarray:
        """Internal normal forces per finger, shape (T, K), [N], from :class:`Features` (and the
        person's grip calibration, see :meth:`predict`)."""
        if features.num_fingers != self.num_fingers:
            raise InputError(f"features have {features.num_fingers} fingers, the model {self.num_fingers} ({self.finger_names})")
        return self.predict(features.matrix(), features.active, grip)[2]

    def state(self) -> dict:
        """What :meth:`save` writes: the model, its metadata and ``sha256``, the digest of the rest.

        The metadata gains ``provenance`` (:func:`fsv.provenance.provenance`) unless it has one
        already (a model read from a file keeps the provenance of the environment that wrote it).
        """
        from fsv.provenance import provenance

        metadata = dict(self.metadata)
        if "provenance" not in metadata:
            metadata["provenance"] = provenance()
        st = {
            "format": FORMAT,
            "version": VERSION,
            "config": asdict(self.config),
            "finger_names": list(self.finger_names),
            "x_mean": self.x_mean.copy(),
            "x_std": self.x_std.copy(),
            "l2_mean": self.l2_mean,
            "l2_std": self.l2_std,
            "net_l2": [[{"weight": W.copy(), "bias": b.copy()} for W, b in net] for net in self.net_l2],
            "net_decomp": [[{"weight": W.copy(), "bias": b.copy()} for W, b in net] for net in self.net_decomp],
            "metadata": metadata,
        }
        if self.grip_mean is not None:
            st["grip_mean"] = [float(v) for v in self.grip_mean]
        st["sha256"] = content_sha256(st)
        return st

    def save(self, path) -> None:
        """Writes the model to ``path`` atomically (temporary file in the same folder, then rename)."""
        path = os.fspath(path)
        folder = os.path.dirname(os.path.abspath(path))
        os.makedirs(folder, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=folder, prefix=".tmp-", suffix=".npz")
        try:
            with os.fdopen(fd, "wb") as fh:
                np.savez(fh, **_to_arrays(self.state()))
                fh.flush()
                os.fsync(fh.fileno())
            os.chmod(tmp, 0o644)  # mkstemp makes it private; a model is shared like any data file
            os.replace(tmp, path)
        except BaseException:
            if os.path.exists(tmp):
                os.unlink(tmp)
            raise


def content_sha256(state: dict) -> str:
    """SHA-256 of a model file's content: every entry of ``state`` but ``sha256`` (format, config,
    finger names, normalisation, every weight array's dtype, shape and bytes, metadata), in a
    canonical order (:func:`fsv.digest.tree_sha256`)."""
    return tree_sha256({k: v for k, v in state.items() if k != "sha256"})


_NETS = ("net_l2", "net_decomp")


def _to_arrays(state: dict) -> dict:
    """The ``.npz`` members of a state: its arrays by name, and the rest as a JSON ``header``."""
    arrays = {"x_mean": state["x_mean"], "x_std": state["x_std"]}
    header = {k: v for k, v in state.items() if k not in ("x_mean", "x_std", *_NETS)}
    header["layers"] = {}
    for key in _NETS:
        header["layers"][key] = [len(net) for net in state[key]]
        for m, net in enumerate(state[key]):
            for i, layer in enumerate(net):
                arrays[f"{key}.{m}.{i}.weight"] = layer["weight"]
                arrays[f"{key}.{m}.{i}.bias"] = layer["bias"]
    arrays["header"] = np.array(json.dumps(header, allow_nan=False))
    return arrays


def _from_arrays(npz) -> dict:
    """The state of a model file's ``.npz`` members (the inverse of :func:`_to_arrays`)."""
    state = json.loads(str(npz["header"][()]))
    layers = state.pop("layers")
    state["x_mean"], state["x_std"] = npz["x_mean"], npz["x_std"]
    for key in _NETS:
        state[key] = [[{"weight": npz[f"{key}.{m}.{i}.weight"], "bias": npz[f"{key}.{m}.{i}.bias"]} for i in range(n)]
                      for m, n in enumerate(layers[key])]
    return state


def read_state(path) -> dict:
    """The raw content of a model file (what :meth:`InternalForceModel.state` wrote), unchecked."""
    with np.load(path, allow_pickle=False) as npz:
        return _from_arrays(npz)


def load(path) -> InternalForceModel:
    """Reads a model written by :meth:`InternalForceModel.save` and checks its digest.

    Raises:
        InputError: If the file is missing, is not an internal-force model of this version, or its
            content does not match the digest stored in it (flipped bytes, a truncated or edited
            file); the message names the file.
    """
    path = os.fspath(path)
    if not os.path.isfile(path):
        raise InputError(f"no internal-force model at {path!r}")
    try:
        st = read_state(path)
    except Exception as e:  # a truncated, corrupt or foreign file: report it as bad input
        raise InputError(f"{path!r} is not a readable internal-force model: {one_line(e)}") from e
    if not isinstance(st, dict) or st.get("format") != FORMAT:
        raise InputError(f"{path!r} is not an {FORMAT} file")
    if st.get("version") != VERSION:
        raise InputError(f"{path!r} is an {FORMAT} file of version {st.get('version')!r}; this fsv reads version "
                         f"{VERSION} (train the model again)")
    try:
        digest = content_sha256(st)
    except InputError as e:
        raise InputError(f"{path!r} is corrupt: {e}") from e
    if st.get("sha256") != digest:
        raise InputError(f"{path!r} is corrupt: its content has SHA-256 {digest[:16]}..., the file records "
                         f"{str(st.get('sha256'))[:16]}...")
    try:
        config = LearnConfig(**dict(st["config"]))
        K = len(st["finger_names"])
        nets = {key: [[(layer["weight"], layer["bias"]) for layer in net] for net in st[key]] for key in _NETS}
        for key, hidden, n_out in (("net_l2", config.hidden_l2, 1), ("net_decomp", config.hidden_decomp, K)):
            sizes = [2 + 3 * K + (GRIP_INPUTS if config.grip_inputs else 0), *hidden, n_out]
            for net in nets[key]:
                if [W.shape for W, _ in net] != list(zip(sizes[1:], sizes[:-1])) or \
                        [b.shape for _, b in net] != [(n,) for n in sizes[1:]]:
                    raise InputError(f"{key} layers do not have the config's sizes {sizes}")
        return InternalForceModel(config, st["finger_names"], st["x_mean"], st["x_std"], st["l2_mean"], st["l2_std"],
                                  nets["net_l2"], nets["net_decomp"], st["metadata"], st.get("grip_mean"))
    except (KeyError, TypeError, AttributeError, ValueError, InputError) as e:
        raise InputError(f"{path!r} has inconsistent internal-force model data: {one_line(e)}") from e


def train(data: TrainingSet, config: LearnConfig = LearnConfig(), *, finger_names=None, metadata=None,
          on_epoch=None) -> InternalForceModel:
    """Trains ANN_L2 and ANN_decomp on all samples of ``data``.

    Args:
        data: Features and internal normal forces (from the decomposition SOCP, eq. 9).
        config: Architecture and Rprop settings; ``config.seed`` fixes the initial weights.
        finger_names: Names of the K finger slots (default ``finger0..``).
        metadata: JSON-like description stored with the model.
        on_epoch: Called with 1 after every epoch of every network (``2 * members * epochs`` calls),
            e.g. a progress bar's ``update``.

    Returns:
        The trained :class:`InternalForceModel`; its metadata gains the final training losses.
    """
    if len(data) < 2:
        raise InputError(f"training needs at least 2 samples, got {len(data)}")
    K = data.num_fingers
    names = tuple(finger_names) if finger_names is not None else tuple(f"finger{k}" for k in range(K))
    if len(names) != K:
        raise InputError(f"finger_names has {len(names)} names for K = {K} finger slots")
    x = data.inputs(config.grip_inputs)
    x_mean = x.mean(axis=0)
    x_std = x.std(axis=0)
    x_std = np.where(x_std > 1e-12, x_std, 1.0)
    l2, shares = _targets(data.internal, data.active)
    l2_mean, l2_std = float(l2.mean()), float(l2.std()) if l2.std() > 1e-12 else 1.0
    import torch

    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    try:
        gen = torch.Generator().manual_seed(config.seed)
        z = torch.from_numpy((x - x_mean) / x_std)
        y = torch.from_numpy((l2 - l2_mean) / l2_std)
        w = torch.from_numpy((data.active & (l2 >= config.min_l2_n)[:, None]).astype(np.float64))
        s = torch.from_numpy(shares)
        n_w = max(float(w.sum()), 1.0)
        if config.amount_loss == "squared":
            def amount_loss(out):
                return torch.mean((out[:, 0] - y) ** 2)
        else:
            a = torch.from_numpy(l2)
            inv = torch.from_numpy(1.0 / np.maximum(l2, config.relative_floor_n))

            def amount_loss(out):
                return torch.mean(torch.abs(out[:, 0] * l2_std + l2_mean - a) * inv)
        net_l2, net_decomp, loss_l2, loss_dec = [], [], [], []
        for _ in range(config.members):
            net_l2.append(_mlp(z.shape[1], config.hidden_l2, 1, gen))
            net_decomp.append(_mlp(z.shape[1], config.hidden_decomp, K, gen))
            loss_l2.append(_rprop(net_l2[-1], z, amount_loss, config, on_epoch))
            loss_dec.append(_rprop(net_decomp[-1], z, lambda out: torch.sum(w * (out - s) ** 2) / n_w, config, on_epoch))
    finally:
        torch.set_num_threads(threads)
    meta = dict(metadata or {})
    loss_name = "train_mse_l2_std" if config.amount_loss == "squared" else "train_rel_err_l2"
    meta.update({"samples": len(data), loss_name: float(np.mean(loss_l2)), "train_mse_shares": float(np.mean(loss_dec))})
    grip_mean = data.grip.mean(axis=0) if config.grip_inputs else None
    return InternalForceModel(config, names, x_mean, x_std, l2_mean, l2_std, [_layers(n) for n in net_l2],
                              [_layers(n) for n in net_decomp], meta, grip_mean)


def relative_errors_pct(predicted: np.ndarray, truth: np.ndarray, active: np.ndarray, min_force_n: float = 1.0) -> np.ndarray:
    """Relative force errors (Table 2): |f_hat - f| / f in percent for every finger in contact
    whose true force f is at least ``min_force_n``.

    Args:
        predicted, truth: Forces per frame and finger, shape (N, K), [N].
        active: Finger in contact, shape (N, K).
        min_force_n: Smallest true force that is scored, [N].

    Returns:
        The errors of the scored (frame, finger) pairs, shape (M,), [%].
    """
    p, t, a = np.asarray(predicted, float), np.asarray(truth, float), np.asarray(active, bool)
    if not (p.shape == t.shape == a.shape):
        raise InputError(f"predicted, truth and active must share a shape, got {p.shape}, {t.shape}, {a.shape}")
    m = a & (t >= min_force_n)
    return 100.0 * np.abs(p[m] - t[m]) / t[m]


@dataclass(frozen=True)
class CrossValidation:
    """k-fold cross-validation of the two networks.

    Attributes:
        fold_rel_err_pct: Mean relative error of the predicted internal normal forces per fold
            (fingers with an internal force >= 1 N), shape (folds,), [%].
        fold_l2_rel_err_pct: Mean relative error of the predicted internal-force norm per fold, [%].
        fold_share_rmse: RMS error of the predicted shares (fingers in contact) per fold.
    """

    fold_rel_err_pct: np.ndarray
    fold_l2_rel_err_pct: np.ndarray
    fold_share_rmse: np.ndarray

    def summary(self) -> dict:
        return {
            "folds": int(len(self.fold_rel_err_pct)),
            "rel_err_pct_mean": float(np.mean(self.fold_rel_err_pct)),
            "l2_rel_err_pct_mean": float(np.mean(self.fold_l2_rel_err_pct)),
            "share_rmse_mean": float(np.mean(self.fold_share_rmse)),
        }


def cross_validate(data: TrainingSet, config: LearnConfig = LearnConfig(), *, on_epoch=None) -> CrossValidation:
    """k-fold cross-validation (``config.folds``) with folds made of whole groups.

    Groups are assigned to folds in a seeded random order (``config.seed``), so no group (episode)
    contributes to both the training and the validation side of a fold. ``on_epoch`` is passed to
    every fold's :func:`train`.
    """
    groups = np.unique(data.groups)
    if len(groups) < config.folds:
        raise InputError(f"cross-validation with {config.folds} folds needs at least {config.folds} groups, got {len(groups)}")
    order = np.random.default_rng(config.seed).permutation(len(groups))
    fold_of_group = dict(zip(groups[order], np.arange(len(groups)) % config.folds))
    fold = np.array([fold_of_group[g] for g in data.groups])
    rel, l2e, srm = [], [], []
    for k in range(config.folds):
        model = train(data.subset(fold != k), config, on_epoch=on_epoch)
        val = data.subset(fold == k)
        l2, s, f = model.predict(val.x, val.active, val.grip)
        l2_true, s_true = _targets(val.internal, val.active)
        rel.append(np.mean(relative_errors_pct(f, val.internal, val.active)))
        ok = l2_true >= 1.0
        l2e.append(np.mean(100 * np.abs(l2[ok] - l2_true[ok]) / l2_true[ok]))
        srm.append(np.sqrt(np.mean((s - s_true)[val.active] ** 2)))
    return CrossValidation(np.array(rel), np.array(l2e), np.array(srm))


def learned_forces(
    model: InternalForceModel,
    kinematics: Kinematics,
    contacts: Contacts,
    object_model: ObjectModel,
    *,
    gravity=GRAVITY,
    settings: ForceSettings | None = None,
    smoothing_s: float = AMOUNT_SMOOTHING_S,
    grip=None,
) -> tuple[ForceSolution, np.ndarray]:
    """Full contact forces from vision with human-like internal forces (the paper's Fig. 2b).

    Args:
        model: Trained networks whose finger slots match ``contacts.finger_names``.
        kinematics: Object kinematics (world frame), T frames.
        contacts: Finger contacts (object frame), T frames.
        object_model: The known object (mass, inertia, friction).
        gravity: Gravity, world frame, shape (3,), [m/s^2].
        settings: Settings of the cone program.
        smoothing_s: Standard deviation of the Gaussian window over which the predicted amount of
            internal force is averaged, [s] (:func:`smooth_over_time`); 0: per frame.
        grip: The person's :class:`fsv.grip.GripCalibration`, for a model with grip inputs (None:
            the training samples' mean, see :meth:`InternalForceModel.predict`).

    Returns:
        ``(solution, predicted)``: the reconstruction (eq. 14) and the predicted internal normal
        forces fed to it, shape (T, K), [N] (0 for fingers not in contact).
    """
    if tuple(contacts.finger_names) != model.finger_names:
        raise InputError(f"contacts have fingers {contacts.finger_names}, the model {model.finger_names}")
    if not (np.isfinite(smoothing_s) and smoothing_s >= 0):
        raise InputError(f"smoothing_s must be a finite number of seconds >= 0, got {smoothing_s!r}")
    features = grasp_features(kinematics, contacts, object_model, gravity=gravity)
    ok = kinematics.valid[:, None] & contacts.active
    x = features.matrix()
    x = np.where(np.isfinite(x), x, 0.0)
    amount, shares, _ = model.predict(x, contacts.active, grip)
    if smoothing_s > 0:
        amount = smooth_over_time(amount, kinematics.t, ok.any(axis=1), smoothing_s)
    predicted = np.where(ok, amount[:, None] * shares, 0.0)
    target = np.where(ok, predicted, np.nan)
    solution = reconstruct_forces(kinematics, contacts, object_model, target, gravity=gravity, settings=settings)
    return solution, predicted


def smooth_over_time(values: np.ndarray, t: np.ndarray, defined: np.ndarray, sigma_s: float) -> np.ndarray:
    """Gaussian-weighted average of a per-frame signal over the frames where it is defined.

    At frame i the result is sum_j w_ij v_j / sum_j w_ij over the defined frames j, with
    w_ij = exp(-(t_i - t_j)^2 / (2 sigma^2)) truncated at 4 sigma: a window that ends at the video's
    edges or at undefined frames is renormalised rather than padded. Frames are taken as evenly
    spaced (the window in frames is ``sigma_s`` over the mean frame interval). The sums run in
    SciPy's own loops (no BLAS), so the result has the same bits under every BLAS kernel.

    Args:
        values: The signal, shape (T,).
        t: Frame times, shape (T,), [s].
        defined: Frames where the signal is defined, shape (T,).
        sigma_s: The window's standard deviation, [s]; > 0.

    Returns:
        The averaged signal, shape (T,); 0 where no defined frame lies within the window or where
        ``defined`` is False.
    """
    from scipy.ndimage import gaussian_filter1d

    v = np.asarray(values, dtype=np.float64)
    t = np.asarray(t, dtype=np.float64)
    d = np.asarray(defined, dtype=bool)
    if not (v.ndim == 1 and t.shape == v.shape == d.shape):
        raise InputError(f"values, t and defined must be (T,) arrays of one length, got {v.shape}, {t.shape}, {d.shape}")
    if not (np.isfinite(sigma_s) and sigma_s > 0):
        raise InputError(f"sigma_s must be a finite number of seconds > 0, got {sigma_s!r}")
    if v.size < 2:
        return np.where(d, v, 0.0)
    sigma = sigma_s / float(np.mean(np.diff(t)))
    weight = gaussian_filter1d(d.astype(np.float64), sigma, mode="constant", truncate=4.0)
    total = gaussian_filter1d(np.where(d, v, 0.0), sigma, mode="constant", truncate=4.0)
    with np.errstate(invalid="ignore", divide="ignore"):
        out = total / weight
    return np.where(d & (weight > 0), out, 0.0)


def default_model() -> InternalForceModel:
    """The small model shipped with the package (``fsv/data/internal_forces.npz``); see docs/data.md
    for the command that trained it and the data it was trained on."""
    from importlib.resources import files

    return load(files("fsv").joinpath("data", "internal_forces.npz"))
