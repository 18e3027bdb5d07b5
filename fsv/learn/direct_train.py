"""Training the end-to-end force network (:class:`fsv.learn.direct.DirectForceModel`) in torch on the CPU.

Loss. The mean squared error of the standardised outputs over the entries that count: the three
components of each finger in contact (the inputs' ``active``) and the table's six where the box is
not clearly off the table (:func:`fsv.learn.direct.on_table`); the entries the model zeroes at
prediction time are left out. Each output is standardised by the mean and standard deviation of
its counted entries.

Optimiser. Adam on mini-batches of :attr:`DirectConfig.batch` samples, for
:attr:`DirectConfig.epochs` passes. A share :attr:`DirectConfig.val_fraction` of the episodes is
held out and the weights of the epoch with the least loss on them are kept (early stopping).

Determinism. The initial weights, the order of the samples and the held-out episodes are drawn
from generators seeded with :attr:`DirectConfig.seed` (a ``torch.Generator`` and NumPy's
``default_rng``; the global generators are neither read nor advanced), everything is float64, and
training runs single-threaded (the thread count is restored afterwards): the same data and config
give bit-identical weights on one machine.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from fsv.errors import InputError
from fsv.learn.direct import ACTIVATION, DirectConfig, DirectForceModel
from fsv.learn.direct_inputs import input_names
from fsv.learn.nets import _layers, _mlp


@dataclass(frozen=True)
class DirectSamples:
    """Training samples of the end-to-end network.

    Attributes:
        x: Inputs (:func:`fsv.learn.direct_inputs.direct_inputs`), shape (N, n_in), finite.
        y: Targets: each finger's true force (object frame, finger-major) and the table's wrench
            on the box (object frame, about the centre of mass), shape (N, 3K + 6), [N, N m].
        mask: The entries the loss counts, shape (N, 3K + 6).
        groups: The episode of each sample, shape (N,) (the held-out set takes whole episodes).
    """

    x: np.ndarray
    y: np.ndarray
    mask: np.ndarray
    groups: np.ndarray

    def __post_init__(self):
        x, y = np.asarray(self.x, np.float64), np.asarray(self.y, np.float64)
        mask, groups = np.asarray(self.mask, bool), np.asarray(self.groups)
        n = len(x)
        if x.ndim != 2 or y.ndim != 2 or mask.shape != y.shape or len(y) != n or groups.shape != (n,):
            raise InputError(f"DirectSamples: x (N, n_in), y and mask (N, n_out) and groups (N,) must share N, got "
                             f"{x.shape}, {y.shape}, {mask.shape}, {groups.shape}")
        if not (np.all(np.isfinite(x)) and np.all(np.isfinite(y[mask]))):
            raise InputError("DirectSamples: the inputs and the counted targets must be finite")
        for name, v in (("x", x), ("y", np.where(mask, y, 0.0)), ("mask", mask), ("groups", groups)):
            object.__setattr__(self, name, v)

    def __len__(self) -> int:
        return len(self.x)

    def subset(self, rows) -> "DirectSamples":
        return DirectSamples(self.x[rows], self.y[rows], self.mask[rows], self.groups[rows])


def _standardise(samples: DirectSamples) -> tuple:
    x_mean, x_std = samples.x.mean(axis=0), samples.x.std(axis=0)
    x_std = np.where(x_std > 1e-12, x_std, 1.0)
    count = samples.mask.sum(axis=0)
    y_mean = np.where(count > 0, samples.y.sum(axis=0) / np.maximum(count, 1), 0.0)
    var = np.where(samples.mask, (samples.y - y_mean) ** 2, 0.0).sum(axis=0) / np.maximum(count, 1)
    y_std = np.where(var > 1e-12, np.sqrt(var), 1.0)
    return x_mean, x_std, y_mean, y_std


def held_out(groups: np.ndarray, fraction: float, seed: int) -> np.ndarray:
    """Samples of the held-out episodes: ``round(fraction * episodes)`` of them (at least one when
    ``fraction`` > 0 and there are two or more), drawn with ``seed``; shape (N,) bool."""
    episodes = np.unique(groups)
    n = int(round(fraction * len(episodes)))
    if fraction > 0 and len(episodes) >= 2:
        n = min(max(n, 1), len(episodes) - 1)
    else:
        n = 0
    chosen = np.random.default_rng(seed).permutation(len(episodes))[:n]
    return np.isin(groups, episodes[chosen])


def train_direct(samples: DirectSamples, finger_names, config: DirectConfig = DirectConfig(), *, metadata=None,
                 on_epoch=None, timing: dict | None = None) -> DirectForceModel:
    """Trains the network on ``samples`` (see the module docstring).

    Args:
        samples: Inputs, targets, counted entries and episodes.
        finger_names: The K finger slots of the inputs and outputs, thumb first.
        config: Architecture and training.
        metadata: JSON-like description stored with the model.
        on_epoch: Called with 1 after every epoch (e.g. a progress bar's ``update``).
        timing: A dict that gains ``seconds``, the wall-clock time of the training proper (torch's
            import and the samples' standardisation left out); kept out of the model, whose file
            then has the same bytes on every training.

    Returns:
        The model; its metadata gains ``samples``, ``held_out_samples``, ``parameters``,
        ``best_epoch``, and ``train_loss`` and ``val_loss`` per epoch (standardised MSE). No
        timing: the file of one machine's training has the same bytes every time.
    """
    if not isinstance(config, DirectConfig):
        raise InputError(f"config must be an fsv.learn.DirectConfig, got {type(config).__name__}")
    names = tuple(str(n) for n in finger_names)
    n_in, n_out = len(input_names(names, config.window)), 3 * len(names) + 6
    if samples.x.shape[1] != n_in or samples.y.shape[1] != n_out:
        raise InputError(f"samples have {samples.x.shape[1]} inputs and {samples.y.shape[1]} outputs; "
                         f"{len(names)} fingers and window {config.window} need {n_in} and {n_out}")
    val = held_out(samples.groups, config.val_fraction, config.seed)
    train, check = samples.subset(~val), samples.subset(val)
    if len(train) < 2:
        raise InputError(f"training needs at least 2 samples outside the held-out episodes, got {len(train)}")
    x_mean, x_std, y_mean, y_std = _standardise(train)
    import torch  # lazy: torch (1.2 s) off `import fsv`

    t0 = time.perf_counter()
    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    try:
        gen = torch.Generator().manual_seed(config.seed)
        net = _mlp(n_in, config.hidden, n_out, gen, activation=ACTIVATION)

        def tensors(s: DirectSamples):
            return (torch.from_numpy((s.x - x_mean) / x_std), torch.from_numpy((s.y - y_mean) / y_std),
                    torch.from_numpy(s.mask.astype(np.float64)))

        def loss_of(z, y, m):
            return torch.sum(m * (net(z) - y) ** 2) / torch.clamp(torch.sum(m), min=1.0)

        z, y, m = tensors(train)
        zv, yv, mv = tensors(check)
        opt = torch.optim.Adam(net.parameters(), lr=config.lr, weight_decay=config.weight_decay, foreach=False)
        train_loss, val_loss, best, best_epoch = [], [], None, 0
        for epoch in range(config.epochs):
            order = torch.randperm(len(train), generator=gen)
            for start in range(0, len(train), config.batch):
                rows = order[start:start + config.batch]
                opt.zero_grad()
                loss = loss_of(z[rows], y[rows], m[rows])
                loss.backward()
                opt.step()
            with torch.no_grad():
                train_loss.append(float(loss_of(z, y, m)))
                val_loss.append(float(loss_of(zv, yv, mv)) if len(check) else float("nan"))
            if len(check) and (best is None or val_loss[-1] < val_loss[best_epoch]):
                best, best_epoch = _layers(net), epoch
            if on_epoch is not None:
                on_epoch(1)
        layers = best if best is not None else _layers(net)
        if best is None:
            best_epoch = config.epochs - 1
    finally:
        torch.set_num_threads(threads)
    if timing is not None:
        timing["seconds"] = time.perf_counter() - t0
    meta = dict(metadata or {})
    meta.update(samples=len(train), held_out_samples=len(check), held_out_episodes=int(len(np.unique(check.groups))),
                parameters=int(sum(W.size + b.size for W, b in layers)), best_epoch=int(best_epoch),
                train_loss=[float(v) for v in train_loss], val_loss=[None if np.isnan(v) else float(v) for v in val_loss])
    return DirectForceModel(config, names, x_mean, x_std, y_mean, y_std, layers, meta)
