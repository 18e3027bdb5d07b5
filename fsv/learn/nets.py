"""The two small multilayer perceptrons, their Rprop training, and their forward pass in NumPy."""

from __future__ import annotations

import numpy as np

from fsv.errors import InputError
from fsv.learn.config import LearnConfig


def _targets(internal: np.ndarray, active: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    f = np.where(active, internal, 0.0)
    l2 = np.linalg.norm(f, axis=1)
    shares = f / np.where(l2 > 0, l2, 1.0)[:, None]
    return l2, shares


ACTIVATIONS = ("logistic", "relu")
"""Hidden-layer activations of :func:`forward`: the logistic (the paper's networks) or the
rectifier max(h, 0) (the end-to-end network, :mod:`fsv.learn.direct`: no transcendental function,
so its forward pass has the same bits on every CPU)."""


def _mlp(n_in: int, hidden: tuple, n_out: int, gen, activation: str = "logistic"):
    """A torch MLP (``activation`` hidden layers, linear output) with weights drawn from ``gen``
    (uniform in +-1 / sqrt(fan-in), torch's default range)."""
    import torch  # lazy: torch (1.2 s) off `import fsv`

    act = {"logistic": torch.nn.Sigmoid, "relu": torch.nn.ReLU}[activation]
    layers, prev = [], n_in
    for h in hidden:
        layers += [torch.nn.utils.skip_init(torch.nn.Linear, prev, h, dtype=torch.float64), act()]
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
    import torch  # lazy: torch (1.2 s) off `import fsv`

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
    import torch  # lazy: torch (1.2 s) off `import fsv`

    return [(m.weight.detach().numpy().copy(), m.bias.detach().numpy().copy())
            for m in net if isinstance(m, torch.nn.Linear)]


def forward(layers: list, z: np.ndarray, activation: str = "logistic") -> np.ndarray:
    """An MLP's output: hidden layers with ``activation`` (:data:`ACTIVATIONS`), linear output layer.

    Args:
        layers: (weight (out, in), bias (out,)) per layer.
        z: Standardised inputs, shape (N, in).
        activation: "logistic" or "relu".

    Returns:
        Shape (N, out of the last layer).
    """
    if activation not in ACTIVATIONS:
        raise InputError(f"activation must be one of {ACTIVATIONS}, got {activation!r}")
    h = z
    for i, (W, b) in enumerate(layers):
        h = np.einsum("ni,oi->no", h, W) + b
        if i < len(layers) - 1:
            if activation == "relu":
                h = np.maximum(h, 0.0)
            else:
                with np.errstate(over="ignore"):  # exp(-h) = inf far below 0: the logistic is 0 there
                    h = 1.0 / (1.0 + np.exp(-h))
    return h
