"""fsv.learn.direct_train: the end-to-end network's training: deterministic, masked, early-stopped."""

import numpy as np
import pytest

from fsv import InputError
from fsv.learn import DirectConfig, DirectSamples, train_direct
from fsv.learn.direct_inputs import input_names
from fsv.learn.direct_train import held_out

NAMES = ("thumb", "index")


def samples(n=400, episodes=8, seed=0) -> DirectSamples:
    """Outputs linear in the inputs plus a little noise; the index finger inactive on half the rows
    (its target there a value the loss must not see), the table's wrench counted on a third."""
    rng = np.random.default_rng(seed)
    n_in, n_out = len(input_names(NAMES)), 3 * len(NAMES) + 6
    x = rng.normal(size=(n, n_in))
    y = x @ rng.normal(size=(n_in, n_out)) / np.sqrt(n_in) * 3 + 1 + 0.01 * rng.normal(size=(n, n_out))
    mask = np.ones((n, n_out), bool)
    off = rng.random(n) < 0.5
    mask[off, 3:6] = False
    y[off, 3:6] = 1e3  # never counted
    mask[rng.random(n) < 2 / 3, 6:] = False
    return DirectSamples(x, y, mask, np.arange(n) % episodes)


CONFIG = DirectConfig(hidden=(16, 16), epochs=40, batch=32, lr=1e-2, val_fraction=0.25, seed=3)


@pytest.fixture(scope="module")
def trained():
    return train_direct(samples(), NAMES, CONFIG, metadata={"data": "synthetic"})


def test_two_trainings_give_the_same_bits(trained):
    again = train_direct(samples(), NAMES, CONFIG, metadata={"data": "synthetic"})
    for (Wa, ba), (Wb, bb) in zip(trained.layers, again.layers):
        assert np.array_equal(Wa, Wb) and np.array_equal(ba, bb)
    assert trained.state()["sha256"] == again.state()["sha256"]  # the whole file's content, metadata included
    other = train_direct(samples(), NAMES, DirectConfig(**{**CONFIG.__dict__, "seed": 4}))
    assert not np.array_equal(trained.layers[0][0], other.layers[0][0])


def test_it_learns_and_keeps_the_best_held_out_epoch(trained):
    m = trained.metadata
    assert m["samples"] == 300 and m["held_out_samples"] == 100 and m["held_out_episodes"] == 2
    assert m["parameters"] == trained.num_parameters == (40 * 16 + 16) + (16 * 16 + 16) + (16 * 12 + 12)
    val = np.array(m["val_loss"])
    assert m["best_epoch"] == int(np.argmin(val)) and val.min() < 0.3 * val[0]  # measured 0.18 of the first epoch
    data = samples()
    out = trained.predict_inputs(data.x)
    counted = data.mask
    # the masked targets of 1e3 N did not pull the network: its errors are those of the counted entries
    assert np.sqrt(np.mean((out - data.y)[counted] ** 2)) < 0.4 * np.std(data.y[counted])  # measured 0.27


def test_numpy_prediction_equals_the_torch_network(trained):
    import torch

    from fsv.learn.nets import _mlp

    net = _mlp(trained.num_inputs, trained.config.hidden, trained.num_outputs, torch.Generator().manual_seed(0),
               activation="relu")
    with torch.no_grad():
        linear = [m for m in net if isinstance(m, torch.nn.Linear)]
        for m, (W, b) in zip(linear, trained.layers):
            m.weight.copy_(torch.from_numpy(W))
            m.bias.copy_(torch.from_numpy(b))
        x = samples(n=50, seed=9).x
        z = torch.from_numpy((x - trained.x_mean) / trained.x_std)
        expected = net(z).numpy() * trained.y_std + trained.y_mean
    np.testing.assert_allclose(trained.predict_inputs(x), expected, rtol=1e-12, atol=1e-12)


def test_the_held_out_episodes_are_whole_and_seeded():
    groups = np.repeat(np.arange(10), 5)
    a = held_out(groups, 0.2, 0)
    assert a.sum() == 10 and len(np.unique(groups[a])) == 2
    assert not set(groups[a]) & set(groups[~a])
    assert np.array_equal(a, held_out(groups, 0.2, 0)) and not held_out(groups, 0.0, 0).any()
    assert held_out(np.zeros(5, int), 0.5, 0).sum() == 0  # one episode: nothing to hold out


def test_samples_that_do_not_fit_the_fingers_or_are_not_finite_are_refused():
    s = samples()
    with pytest.raises(InputError, match="need 47 and 15"):
        train_direct(s, ("thumb", "index", "middle"), CONFIG)
    x = s.x.copy()
    x[0, 0] = np.nan
    with pytest.raises(InputError, match="must be finite"):
        DirectSamples(x, s.y, s.mask, s.groups)
