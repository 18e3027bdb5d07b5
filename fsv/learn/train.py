"""Training the networks on a :class:`~fsv.learn.config.TrainingSet`, cross-validation, and the relative error they are scored by."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fsv.errors import InputError
from fsv.learn.config import LearnConfig, TrainingSet
from fsv.learn.model import InternalForceModel
from fsv.learn.nets import _layers, _mlp, _rprop, _targets


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
    import torch  # lazy: torch (1.2 s) off `import fsv`

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
