"""InceptionTime (Ismail Fawaz et al. 2020) in PyTorch, and the training loop it shares with the CNN.

The network's size is counted layer by layer from the paper's description
(and aeon's Keras implementation of it); "same" padding, the ensemble's
average and the learning-rate plateau rule are checked against values
worked out by hand. PyTorch is the ``deep`` extra, which CI installs: a
missing torch fails under CI=true and skips elsewhere.
"""

from __future__ import annotations

import os

import numpy as np
import pytest

if os.environ.get("CI", "").lower() == "true":
    import torch  # noqa: F401  (CI installs the deep extra: a missing torch must fail, not skip)
else:
    torch = pytest.importorskip("torch")

from sklearn.utils.estimator_checks import parametrize_with_checks  # noqa: E402

from touchbench.classifiers import CLASSIFIERS, make_classifier  # noqa: E402
from touchbench.classifiers.inception import build_network  # noqa: E402
from touchbench.classifiers.torch_fit import Plateau, train, validation_split  # noqa: E402
from touchbench.datasets.model import SensorSpec  # noqa: E402
from helpers import slow_fast_rows  # noqa: E402


def _n_params(module) -> int:
    return sum(p.numel() for p in module.parameters())


def _module_params(c_in: int, bottleneck=32, filters=32, kernels=(40, 20, 10)) -> int:
    """One Inception module, counted by hand: bias-free convolutions, batch norm's scale and shift."""
    c_b = bottleneck if c_in > 1 else c_in
    n = c_in * bottleneck if c_in > 1 else 0  # 1 x 1 bottleneck
    n += sum(c_b * filters * k for k in kernels)  # three convolutions
    n += c_in * filters  # 1 x 1 convolution after the max pooling
    return n + 2 * 4 * filters  # batch norm over the 4 * filters channels


@pytest.mark.parametrize("c_in", [64, 1])
def test_parameter_count_is_the_papers_network(c_in):
    import torch

    n_classes = 7
    net = build_network(torch, c_in, n_classes)
    width = 128
    expected = _module_params(c_in) + 5 * _module_params(width)
    expected += (c_in * width + 2 * width) + (width * width + 2 * width)  # two residual shortcuts: 1 x 1 conv + BN
    expected += width * n_classes + n_classes  # dense softmax layer
    assert _n_params(net) == expected
    # 64 channels: 72,192 + 5 x 80,128 + 8,448 + 16,640 + 903 (the arithmetic above, written out)
    if c_in == 64:
        assert expected == (64 * 32 + 71680 + 64 * 32 + 256) + 5 * 80128 + (64 * 128 + 256) + (128 * 128 + 256) + 903


@pytest.mark.parametrize("length", [1, 9, 40, 41])
def test_same_padding_keeps_the_length_and_pads_like_keras(length):
    import torch

    net = build_network(torch, 3, 2, depth=3).eval()
    x = torch.randn(2, 3, length)
    module = net.modules_[0]
    assert module(x).shape == (2, 128, length)
    # kernel 40: 19 zeros on the left, 20 on the right (Keras "same" with an even kernel)
    pad = module.convs[0][0]
    assert pad.padding == (19, 20)
    assert net(x).shape == (2, 2)


_toy = slow_fast_rows  # slow vs fast oscillations, 2 x 2 cells


SMALL = dict(n_networks=2, depth=3, n_filters=8, kernel_size=8, bottleneck_size=8, max_epochs=25, batch_size=8)


def test_learns_slow_from_fast_and_the_ensemble_averages_its_networks():
    import torch

    X, y = _toy()
    Xt, yt = _toy(seed=1)
    est = make_classifier("inception-time", random_state=0, grid=(2, 2), **SMALL).fit(X, y)
    assert np.mean(est.predict(Xt) == yt) >= 0.9
    # the mean of each network's softmax, on the series scaled by hand (one mean / sd over the training values)
    S = ((Xt.reshape(len(Xt), -1, 4).transpose(0, 2, 1) - X.mean()) / X.std()).astype(np.float32)
    with torch.no_grad():
        P = np.mean([torch.softmax(net(torch.from_numpy(S)), 1).double().numpy() for net in est.nets_], axis=0)
    assert np.allclose(est.predict_proba(Xt), P, atol=1e-6)
    assert len(est.nets_) == 2 and list(est.classes_) == ["fast", "slow"]


def test_a_seed_gives_the_same_predictions_and_another_seed_other_ones():
    X, y = _toy(n_per_class=6)
    cheap = {**SMALL, "max_epochs": 3}
    a = make_classifier("inception-time", random_state=4, grid=(2, 2), **cheap).fit(X, y).predict_proba(X)
    b = make_classifier("inception-time", random_state=4, grid=(2, 2), **cheap).fit(X, y).predict_proba(X)
    c = make_classifier("inception-time", random_state=5, grid=(2, 2), **cheap).fit(X, y).predict_proba(X)
    assert np.array_equal(a, b) and not np.array_equal(a, c)


def test_the_grid_comes_from_the_sensor():
    sensor = SensorSpec("odd", (3, 5), 20.0)
    rng = np.random.default_rng(0)
    caps = [rng.uniform(0, 9, (12 + i % 3, 3, 5)) for i in range(8)]
    y = np.array(list("ab") * 4)
    est = make_classifier("inception-time", random_state=0, sensor=sensor, **{**SMALL, "max_epochs": 2}).fit(caps, y)
    assert tuple(est.grid_) == (3, 5) and est.length_ == 14  # the longest training capture
    assert est.predict(caps).shape == (8,)
    assert make_classifier("inception-time", grid=(2, 2)).check_sensor(sensor) is not None


def test_plateau_halves_the_rate_after_patience_epochs_without_a_lower_loss():
    import torch

    class Flat(torch.nn.Module):  # output independent of the weights: the loss never changes
        def __init__(self):
            super().__init__()
            self.lin = torch.nn.Linear(2, 2)

        def forward(self, x):
            return self.lin(x) * 0.0

    net = Flat()
    opt = torch.optim.Adam(net.parameters(), lr=1.0)
    x, yl = torch.zeros(4, 2), torch.tensor([0, 1, 0, 1])
    history, best = train(torch, net, opt, x, yl, np.random.default_rng(0), max_epochs=10, batch_size=4,
                          plateau=Plateau(factor=0.5, patience=2, min_lr=0.3))
    # epoch 1 sets the best; epochs 2-4 are 3 > 2 bad epochs -> halved after epoch 4 (the count restarts);
    # epochs 5-7 -> halved again after epoch 7, 0.25 raised to the floor 0.3
    assert [h["lr"] for h in history] == [1.0] * 4 + [0.5] * 3 + [0.3] * 3
    assert best == 1 and all(abs(h["train_loss"] - np.log(2)) < 1e-6 for h in history)


def test_validation_split_holds_out_whole_groups_or_a_share_of_every_class():
    yi = np.array([0] * 10 + [1] * 10)
    groups = np.repeat(["s1", "s2", "s3", "s4"], 5)
    fit, val, held = validation_split(yi, groups, np.random.default_rng(0), 0.25)
    assert len(held) == 1 and set(groups[val]) == set(held) and not set(groups[fit]) & set(held)
    fit, val, held = validation_split(yi, None, np.random.default_rng(0), 0.2)
    assert held is None and np.bincount(yi[val]).tolist() == [2, 2] and len(fit) == 16
    fit, val, _ = validation_split(yi, None, np.random.default_rng(0), 0.0)
    assert len(val) == 0 and len(fit) == 20


def _checked():
    est = make_classifier("inception-time", random_state=0, grid=(1, 1), **CLASSIFIERS.entry("inception-time").tags["cheap_params"])
    return [est]


@parametrize_with_checks(_checked())
def test_sklearn_estimator_checks(estimator, check):
    check(estimator)


def test_a_fitted_model_pickles_as_weights_and_predicts_the_same(tmp_path):
    import pickle

    X, y = _toy(n_per_class=6)
    est = make_classifier("inception-time", random_state=1, grid=(2, 2), **{**SMALL, "max_epochs": 3}).fit(X, y)
    back = pickle.loads(pickle.dumps(est))
    assert all(isinstance(w, np.ndarray) for w in est.__getstate__()["nets_"][0].values())  # data, no tensor
    assert np.array_equal(back.predict_proba(X), est.predict_proba(X))
