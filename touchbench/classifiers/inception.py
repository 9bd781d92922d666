"""InceptionTime (Ismail Fawaz et al., "InceptionTime: finding AlexNet for
time series classification", Data Mining and Knowledge Discovery 34,
2020), in PyTorch: the ``deep`` extra. A peer on the cell series of raw
frames.

Why not aeon's: aeon's ``InceptionTimeClassifier`` is written for
TensorFlow/Keras; touchbench's deep extra is PyTorch, and one deep-learning
framework is enough. The network and training below follow the paper
(section 3) and aeon's implementation of it, layer for layer
(``tests/test_classifiers_inception.py`` counts the parameters of every
layer by hand).

Input
-----
As the aeon peers (:mod:`touchbench.classifiers.peers`): the captures as
recorded, or ``raw-window`` rows; each of the sensor's H x W cells is one
channel of a series of F frames, ``(n, H * W, F)``. Captures are cut to
``length`` frames (None: the longest training capture), a shorter one
padded by repeating its last frame. Values are rescaled by one mean and one
standard deviation over all training values (``scaling="standard"``; an
interpretation: the paper's UCR/UEA series come z-normalised per series,
which would erase the pressure level that separates a squeeze from a
stroke, so one affine map of the raw values is used; ``"none"`` feeds raw
values).

Network (section 3.1, Fig. 1 and 2)
-----------------------------------
``depth`` = 6 Inception modules, a residual connection around every 3
(a 1 x 1 convolution and batch normalisation on the shortcut, added, then
ReLU), global average pooling over time, and a dense softmax layer. One
module: a 1 x 1 "bottleneck" convolution to 32 channels (when its input
has more than one channel), three convolutions of 32 filters with kernels
of 40, 20 and 10 (``kernel_size // 2**i``) on the bottleneck's output, and
a max-pooling of size 3 (stride 1) of the module's input followed by a
1 x 1 convolution of 32 filters; the four outputs (128 channels) are
concatenated, batch-normalised and passed through a ReLU. Convolutions
have no bias and "same" padding (as Keras pads: the extra one of an even
kernel on the right).

Training (section 4): Adam (learning rate 1e-3), batches of 64, 1500
epochs, the learning rate halved after 50 epochs without a lower training
loss (down to 1e-4), and the weights of the epoch with the lowest training
loss kept. InceptionTime is an ensemble of ``n_networks`` = 5 such
networks, each from its own seed, whose softmax outputs are averaged.
These are the defaults. On a CPU they take long (every network sees every
training capture 1500 times): a protocol may state fewer epochs or
networks, or early stopping on a validation share of the training
captures (``validation_fraction``, drawn only from the training data, by
whole ``groups`` when ``fit`` is given them; ``patience`` epochs).

Determinism: as the CNN, each network is seeded from ``random_state``
inside ``torch.random.fork_rng`` with deterministic algorithms and
``n_jobs`` threads; on the CPU a seed gives bit-identical predictions.
"""

from __future__ import annotations

from numbers import Integral, Real

import numpy as np
from sklearn.base import BaseEstimator, ClassifierMixin
from sklearn.utils import check_random_state
from sklearn.utils._param_validation import Interval, StrOptions
from sklearn.utils.multiclass import check_classification_targets
from sklearn.utils.validation import check_is_fitted, validate_data

from ..core.errors import TouchbenchError
from ._util import MAX_SEED, build, captures_to_rows, frames_in_row, is_captures, sensor_frames, torch_available
from .base import CLASSIFIERS, check_declared
from .torch_fit import INSTALL_HINT, TORCH_JOBS, Plateau, Threads, import_torch, softmax_batches, train, validation_split
from .torch_state import load_weights, weights_as_arrays

SOURCE = "Ismail Fawaz et al. 2020 (InceptionTime), sections 3-4; aeon 1.x InceptionTimeClassifier's settings"


def _same(nn, c_in: int, c_out: int, k: int):
    """A bias-free convolution with Keras' "same" padding: (k - 1) // 2 zeros on the left, the rest on the right."""
    left = (k - 1) // 2
    return nn.Sequential(nn.ConstantPad1d((left, k - 1 - left), 0.0), nn.Conv1d(c_in, c_out, k, bias=False))


def build_network(torch, in_channels: int, n_classes: int, *, depth: int = 6, n_filters: int = 32,
                  kernel_size: int = 40, bottleneck_size: int = 32, use_residual: bool = True):
    """One Inception network (module docstring) for ``in_channels`` series."""
    nn = torch.nn

    class Module(nn.Module):
        def __init__(self, c_in):
            super().__init__()
            self.bottleneck = (nn.Conv1d(c_in, bottleneck_size, 1, bias=False) if c_in > 1 else nn.Identity())
            c_b = bottleneck_size if c_in > 1 else c_in
            self.convs = nn.ModuleList(_same(nn, c_b, n_filters, max(kernel_size // 2 ** i, 1)) for i in range(3))
            self.pool = nn.MaxPool1d(3, stride=1, padding=1)
            self.pool_conv = nn.Conv1d(c_in, n_filters, 1, bias=False)
            self.bn = nn.BatchNorm1d(4 * n_filters)

        def forward(self, x):
            b = self.bottleneck(x)
            out = [conv(b) for conv in self.convs] + [self.pool_conv(self.pool(x))]
            return torch.relu(self.bn(torch.cat(out, dim=1)))

    class Network(nn.Module):
        def __init__(self):
            super().__init__()
            width = 4 * n_filters
            self.modules_ = nn.ModuleList(Module(in_channels if d == 0 else width) for d in range(depth))
            self.shortcuts = nn.ModuleList()
            if use_residual:
                c_res = in_channels
                for d in range(depth):
                    if d % 3 == 2:
                        self.shortcuts.append(nn.Sequential(nn.Conv1d(c_res, width, 1, bias=False), nn.BatchNorm1d(width)))
                        c_res = width
            self.head = nn.Linear(width, n_classes)

        def forward(self, x):
            res, k = x, 0
            for d, module in enumerate(self.modules_):
                x = module(x)
                if use_residual and d % 3 == 2:
                    x = torch.relu(x + self.shortcuts[k](res))
                    res, k = x, k + 1
            return self.head(x.mean(dim=2))

    return Network()


class InceptionTimeClassifier(ClassifierMixin, BaseEstimator):
    """InceptionTime on the H x W cell series (module docstring: input, network, training).

    Parameters
    ----------
    sensor, grid, length : as the aeon peers.
    n_networks : networks in the ensemble (5).
    depth, n_filters, kernel_size, bottleneck_size, use_residual : the network (6, 32, 40, 32, True).
    max_epochs, batch_size, learning_rate : Adam training (1500, 64, 1e-3).
    lr_factor, lr_patience, min_lr : the plateau rule on the monitored loss (0.5, 50, 1e-4).
    validation_fraction, patience : early stopping on a validation share (0: none, the paper).
    scaling : ``"standard"`` or ``"none"``.
    random_state, device, n_jobs, verbose : as the CNN.

    The domains are declared (``_parameter_constraints``: checked when a protocol is read and when
    ``fit`` begins). Upper bounds where a value only costs: ``n_networks`` at most 100 (20 times
    the paper's 5, each trained in full), ``depth`` at most 100, ``n_filters`` and
    ``bottleneck_size`` at most 1,024 (32 times the paper's 32: a convolution's weights grow with
    their square), ``kernel_size`` at most 1,000 (25 times the paper's 40), ``max_epochs`` at most
    100,000 (a pass over the training captures each). ``lr_factor`` in (0, 1) (PyTorch's
    plateau rule refuses 1), ``patience`` None or at least 1.
    """

    _parameter_constraints = {
        "sensor": "no_validation", "grid": ["array-like", None],
        "length": [Interval(Integral, 1, None, closed="left"), None],
        "n_networks": [Interval(Integral, 1, 100, closed="both")],
        "depth": [Interval(Integral, 1, 100, closed="both")],
        "n_filters": [Interval(Integral, 1, 1024, closed="both")],
        "kernel_size": [Interval(Integral, 1, 1000, closed="both")],
        "bottleneck_size": [Interval(Integral, 1, 1024, closed="both")],
        "use_residual": ["boolean"],
        "max_epochs": [Interval(Integral, 1, 100_000, closed="both")],
        "batch_size": [Interval(Integral, 1, None, closed="left")],
        "learning_rate": [Interval(Real, 0, None, closed="neither")],
        "lr_factor": [Interval(Real, 0, 1, closed="neither")],
        "lr_patience": [Interval(Integral, 0, None, closed="left")],
        "min_lr": [Interval(Real, 0, None, closed="left")],
        "validation_fraction": [Interval(Real, 0, 1, closed="left"), None],
        "patience": [Interval(Integral, 1, None, closed="left"), None],
        "scaling": [StrOptions({"standard", "none"})],
        "random_state": ["random_state"], "device": [str], "n_jobs": TORCH_JOBS, "verbose": ["verbose"],
    }

    def __init__(self, sensor=None, grid=None, length=None, n_networks=5, depth=6, n_filters=32, kernel_size=40,
                 bottleneck_size=32, use_residual=True, max_epochs=1500, batch_size=64, learning_rate=1e-3,
                 lr_factor=0.5, lr_patience=50, min_lr=1e-4, validation_fraction=0.0, patience=50,
                 scaling="standard", random_state=None, device="cpu", n_jobs=1, verbose=0):
        self.sensor = sensor
        self.grid = grid
        self.length = length
        self.n_networks = n_networks
        self.depth = depth
        self.n_filters = n_filters
        self.kernel_size = kernel_size
        self.bottleneck_size = bottleneck_size
        self.use_residual = use_residual
        self.max_epochs = max_epochs
        self.batch_size = batch_size
        self.learning_rate = learning_rate
        self.lr_factor = lr_factor
        self.lr_patience = lr_patience
        self.min_lr = min_lr
        self.validation_fraction = validation_fraction
        self.patience = patience
        self.scaling = scaling
        self.random_state = random_state
        self.device = device
        self.n_jobs = n_jobs
        self.verbose = verbose

    def check_sensor(self, sensor, min_frames=None):
        """Why InceptionTime cannot serve ``sensor`` (a ``grid`` that is not its own), or None."""
        try:
            sensor_frames("InceptionTimeClassifier", sensor, self.grid)
        except ValueError as e:
            return str(e)
        return None

    def _network(self, torch):
        """A new network for this estimator's grid, classes and architecture parameters."""
        return build_network(torch, int(self.grid_[0]) * int(self.grid_[1]), len(self.classes_), depth=int(self.depth),
                             n_filters=int(self.n_filters), kernel_size=int(self.kernel_size),
                             bottleneck_size=int(self.bottleneck_size), use_residual=bool(self.use_residual))

    def __getstate__(self):
        """Saved as the networks' weights, numpy arrays (the network classes are built when torch is imported)."""
        state = dict(super().__getstate__())  # a copy: the fitted estimator keeps its networks
        if "nets_" in state:
            state["nets_"] = [weights_as_arrays(net) for net in state["nets_"]]
        return state

    def __setstate__(self, state):
        super().__setstate__(state)
        if getattr(self, "nets_", None) and isinstance(self.nets_[0], dict):
            torch = import_torch("inception-time")
            self.nets_ = [load_weights(torch, self._network(torch), weights) for weights in self.nets_]

    def _series(self, X) -> np.ndarray:
        """Rows of flattened frames -> scaled float32 ``(n, H * W, F)``."""
        f = frames_in_row(X.shape[1], self.grid_, "InceptionTimeClassifier")
        S = X.reshape(X.shape[0], f, -1).transpose(0, 2, 1)
        return np.ascontiguousarray((S - self.scale_mean_) / self.scale_std_, dtype=np.float32)

    def fit(self, X, y, groups=None):
        """Fit on captures (or raw-window rows) ``X`` with labels ``y``; ``groups`` as the CNN's."""
        torch = import_torch("inception-time")
        check_declared(self)
        self.grid_, _ = sensor_frames("InceptionTimeClassifier", self.sensor, self.grid)
        if is_captures(X):
            length = int(self.length) if self.length is not None else max(len(c) for c in X)
            X = captures_to_rows(X, self.grid_, length, "inception-time")
        X, y = validate_data(self, X, y, dtype=np.float64)
        check_classification_targets(y)
        self.length_ = frames_in_row(X.shape[1], self.grid_, "InceptionTimeClassifier")
        self.classes_, yi = np.unique(y, return_inverse=True)
        if self.scaling == "standard":
            sd = float(X.std())
            self.scale_mean_, self.scale_std_ = float(X.mean()), (sd if sd > 0 else 1.0)
        else:
            self.scale_mean_, self.scale_std_ = 0.0, 1.0
        S = self._series(X)
        rs = check_random_state(self.random_state)
        seeds = [int(s) for s in rs.randint(MAX_SEED, size=int(self.n_networks))]
        self.nets_, self.histories_, self.best_epochs_ = [], [], []
        dev = torch.device(self.device)
        with Threads(torch, self.n_jobs), torch.random.fork_rng(devices=[]):
            for seed in seeds:
                rng = np.random.default_rng(seed)
                fit_rows, val_rows, _ = validation_split(yi, groups, rng, self.validation_fraction)
                torch.manual_seed(seed)
                net = self._network(torch).to(dev)
                opt = torch.optim.Adam(net.parameters(), lr=self.learning_rate)
                xt = torch.from_numpy(S[fit_rows]).to(dev)
                yt = torch.from_numpy(yi[fit_rows].astype(np.int64)).to(dev)
                xv = torch.from_numpy(S[val_rows]).to(dev) if len(val_rows) else None
                yv = torch.from_numpy(yi[val_rows].astype(np.int64)).to(dev) if len(val_rows) else None
                history, best = train(torch, net, opt, xt, yt, rng, max_epochs=int(self.max_epochs),
                                      batch_size=int(self.batch_size), xv=xv, yv=yv, patience=self.patience,
                                      plateau=Plateau(float(self.lr_factor), int(self.lr_patience), float(self.min_lr)),
                                      verbose=self.verbose)
                self.nets_.append(net.to("cpu") if self.device != "cpu" else net)
                self.histories_.append(history)
                self.best_epochs_.append(best)
        return self

    def predict_proba(self, X):
        """The ensemble's mean softmax."""
        torch = import_torch("inception-time")
        check_is_fitted(self)
        if is_captures(X):
            X = captures_to_rows(X, self.grid_, self.length_, "inception-time")
        X = validate_data(self, X, dtype=np.float64, reset=False)
        xt = torch.from_numpy(self._series(X))
        with Threads(torch, self.n_jobs):
            P = [softmax_batches(torch, net, xt, len(self.classes_)) for net in self.nets_]
        return np.mean(P, axis=0)

    def predict(self, X):
        P = self.predict_proba(X)
        return self.classes_[np.argmax(P, axis=1)]


DEFAULTS = {
    "length": None, "n_networks": 5, "depth": 6, "n_filters": 32, "kernel_size": 40, "bottleneck_size": 32,
    "use_residual": True, "max_epochs": 1500, "batch_size": 64, "learning_rate": 1e-3, "lr_factor": 0.5,
    "lr_patience": 50, "min_lr": 1e-4, "validation_fraction": 0.0, "patience": 50, "scaling": "standard",
    "device": "cpu", "n_jobs": 1,
}


@CLASSIFIERS.register(
    "inception-time",
    description="peer: InceptionTime (5 Inception networks of depth 6, averaged) on the H x W cell series of raw-window frames",
    source=SOURCE, defaults=DEFAULTS, extra="deep", input="captures",
    cheap_params=dict(n_networks=2, depth=3, n_filters=4, kernel_size=8, bottleneck_size=4, max_epochs=3, batch_size=8),
)
def inception_time(random_state=None, sensor=None, **params):
    """InceptionTime; raises a TouchbenchError with the install command without PyTorch."""
    if not torch_available():
        raise TouchbenchError(f"the 'inception-time' classifier needs PyTorch, which is not installed: {INSTALL_HINT}")
    return build(InceptionTimeClassifier, DEFAULTS, random_state, {**params, "sensor": sensor}, name="inception-time")
