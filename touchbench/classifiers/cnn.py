"""The raw-frame CNN of Al-mashhadani et al. 2021 (section 2.3,
Table 1, Fig. 5), in PyTorch: the ``deep`` extra.

PyTorch is imported lazily, inside this module's functions only, so the
rest of touchbench works without it; building the ``cnn`` entry without
PyTorch raises a :class:`touchbench.core.errors.TouchbenchError` naming the
install command (``pip install 'touchbench[deep]'``).

Input
-----
``X`` is the ``raw-window`` feature set: one row per capture, the capture's
``F_total`` frames of ``H x W`` cells flattened in C order (``F_total`` is
raw-window's stated ``frames``: 432 for HAART, 8 s at 54 Hz). The frame
shape ``(H, W)`` is the sensor's: the run engine passes the dataset's
sensor (``sensor``); from Python without a sensor, ``grid=(H, W)`` must be
given (a grid given with a sensor must be the sensor's); ``grid_``
records it. ``F_total = n_features / (H * W)``.

Other sensors (an interpretation: the paper has only HAART's 8 x 8 grid):
the same layers on any grid. With the paper's padding and ceil-mode
pooling every block keeps at least one cell, so even a 1 x 1 grid or a
1 x C channel sensor gives a network (there the 2 x 2 kernels mostly see
padding). A run whose shortest capture has fewer than L frames is refused
before any task (:meth:`HaartCNNClassifier.check_sensor`): its windows
would have no frame of their own, only raw-window's padding.

Sub-windows (the paper's "subsamples", section 2.3, Eq. 3)
-------------------------------------------------------
"F = floor(N / L)" with N = 432 frames; "the sample ... can be broken down
into 86 multiple subsamples of 8x8x5" (L = 86, F = 5). So a capture gives
**L consecutive, non-overlapping windows of F frames** (window ``k`` holds
frames ``k*F .. (k+1)*F - 1``; the last ``N - L*F`` frames are unused), and
the network sees one window as an ``F``-channel 8 x 8 image. L = 30 (F =
14, Table 1's "8 x 8 x 14" input) is the paper's choice from its Fig. 5
sweep. The paper then says "the first subsample is picked, and the others
are kept away ... we will have only 8x8x43 (if L = 10), which is the first
part of the big sample", so the defaults are ``train_windows="first"`` and
``test_windows="first"``: one window per capture. ``"all"`` (or a list of
window indices) trains on every window as its own sample with the capture's
label (the paper's "benefit I": more training samples) and/or classifies
every window of a test capture and combines them by a capture-level
``vote``: ``"soft"`` averages the windows' softmax outputs, ``"hard"``
takes the majority label (ties broken by the soft average). The paper
says nothing of labelling a test capture by more than its first window:
``test_windows="all"`` with ``vote="soft"`` (the ``cnn-all-windows``
entry of the paper protocol ``cnn-table2-loso-haart``) is our reading of
its subsamples as test samples of one capture, trained as the paper says.

Network (Table 1)
-----------------
Three blocks of convolution -> ReLU -> 2 x 2 max-pooling, then one fully
connected layer and the softmax output:

==========  ======================================================
block 1     conv 2x2, stride 1, pad 1, F -> 32 channels
block 2     conv 2x2, stride 1, pad 1, 32 -> 64
block 3     conv 3x3, stride 1, pad 1, 64 -> 128
pooling     2 x 2, stride 2, partial windows kept (ceil mode)
FC          128 x 2 x 2 = 512 -> 256, ReLU
output      256 -> n_classes, softmax
==========  ======================================================

Interpretations. Table 1 lists each layer's *input* channels (8x8x14, 32,
64) and the FC input "128 x 2 x 2", which fixes the output channels at 32,
64, 128. Its pooling rows read "Size 2x2, Pad 2": with stride 2 and
MATLAB-style "same" padding (PyTorch ``ceil_mode=True``) an 8 x 8 input
becomes 9 -> 5 -> 6 -> 3 -> 3 -> 2, which reproduces the table's 128 x 2 x 2;
no other reading we tried does, so "Pad 2" is taken to be the stride. The
"Softmax, Output Units 7" row needs a 256 -> 7 projection, which we add as
the output layer (as in MATLAB's ``fullyConnectedLayer(7)`` +
``softmaxLayer``); the 256-unit layer gets a ReLU (section 2.2.1.1). The
paper gives no optimiser, learning rate, batch size, epoch count or input
scaling ("raw data ... without preprocessing"): we use Adam (lr 1e-3),
batches of 32, at most 100 epochs with early stopping (patience 10, best
weights restored), and ``scaling="standard"``: one mean and one standard
deviation over all training cells (a single affine rescaling of the raw
pressures, which the first convolution could absorb, but which keeps
Adam's step sizes sensible for values in 0..1023; ``"none"`` feeds raw
values).

Early stopping and leakage
--------------------------
The validation split is drawn only from the ``X, y`` given to ``fit`` (the
training fold), stratified by label and seeded, at the capture level (all
windows of a capture fall on one side). ``fit`` cannot see subjects
unless it is given ``groups``: then whole training subjects are held out
for validation (``fit(X, y, groups=subjects)``), which imitates
leave-one-subject-out evaluation more closely. Test subjects are never
seen. ``validation_fraction=0`` trains for exactly ``max_epochs``.

One leak, for the leakage audit only: ``fit(..., test_set=(X_test,
y_test))`` (the engine passes it to a method marked ``stopped_on_test``,
the audit's ``stopped-on-test`` variant) stops early on the *test* data:
no validation split is drawn, after every epoch the network labels the
test captures as ``predict`` would (``test_windows``, ``vote``), the
weights of the epoch with the highest test accuracy are kept (the first
of equal ones) and training stops after ``patience`` epochs without a
higher one. ``history_`` records each epoch's test accuracy
(``"score"``). This is how a paper that early-stops on its held-out
subject would select its epoch (Al-mashhadani et al. describe no
validation split, section 2.3); its figure is never an honest one.

Determinism
-----------
``fit`` seeds PyTorch from ``random_state`` inside ``torch.random.fork_rng``
(the caller's global generator is untouched), turns on
``torch.use_deterministic_algorithms`` and sets ``torch.set_num_threads(
n_jobs)`` for its duration (both restored afterwards); the data order and
validation split come from a numpy generator with the same seed. On the CPU
a given seed and ``n_jobs`` give bit-identical weights and predictions.
"""

from __future__ import annotations

from numbers import Integral, Real
from typing import Any

import numpy as np
from sklearn.base import BaseEstimator, ClassifierMixin
from sklearn.utils import check_random_state
from sklearn.utils._param_validation import Interval, StrOptions
from sklearn.utils.multiclass import check_classification_targets
from sklearn.utils.validation import check_is_fitted, validate_data

from ..core.constraints import ListOf
from ..core.errors import TouchbenchError
from ._util import (
    MAX_SEED,
    build,
    captures_to_rows,
    frames_in_row,
    is_captures,
    sensor_frames,
    torch_available,
)
from .base import CLASSIFIERS, ParamError, check_declared
from .torch_fit import INSTALL_HINT, TORCH_JOBS, Threads, import_torch, softmax_batches, train, validation_split
from .torch_state import load_weights, weights_as_arrays

SOURCE = "Al-mashhadani et al. 2021, section 2.3, Table 1, Eq. 3"


def build_network(torch, in_channels: int, grid: tuple[int, int], n_classes: int,
                  channels: tuple[int, int, int] = (32, 64, 128), hidden_units: int = 256):
    """Table 1's network for ``in_channels`` (= F) frames of ``grid`` cells."""
    nn = torch.nn
    c1, c2, c3 = channels
    features = nn.Sequential(
        nn.Conv2d(in_channels, c1, kernel_size=2, stride=1, padding=1), nn.ReLU(),
        nn.MaxPool2d(2, stride=2, ceil_mode=True),
        nn.Conv2d(c1, c2, kernel_size=2, stride=1, padding=1), nn.ReLU(),
        nn.MaxPool2d(2, stride=2, ceil_mode=True),
        nn.Conv2d(c2, c3, kernel_size=3, stride=1, padding=1), nn.ReLU(),
        nn.MaxPool2d(2, stride=2, ceil_mode=True),
        nn.Flatten(),
    )
    with torch.no_grad():
        n_flat = features(torch.zeros(1, in_channels, *grid)).shape[1]
    return nn.Sequential(features, nn.Linear(n_flat, hidden_units), nn.ReLU(), nn.Linear(hidden_units, n_classes))


#: "first", "all", a window index or a list of them (an index beyond L is refused when fitting)
WINDOWS = [StrOptions({"first", "all"}), Interval(Integral, 0, None, closed="left"),
           ListOf([Interval(Integral, 0, None, closed="left")], min_length=1)]


def _window_indices(spec: Any, n_windows: int, what: str) -> np.ndarray:
    if isinstance(spec, str):
        if spec == "first":
            return np.array([0])
        if spec == "all":
            return np.arange(n_windows)
        raise ValueError(f"{what} must be 'first', 'all', a window index or a list of them, got {spec!r}")
    idx = np.atleast_1d(np.asarray(spec))
    if idx.size == 0 or idx.dtype.kind not in "iu":
        raise ValueError(f"{what} must be 'first', 'all', a window index or a list of them, got {spec!r}")
    if idx.min() < 0 or idx.max() >= n_windows:
        raise ValueError(f"{what}: window index out of range 0..{n_windows - 1}: {spec!r}")
    return idx.astype(np.int64)


class HaartCNNClassifier(ClassifierMixin, BaseEstimator):
    """Al-mashhadani et al.'s CNN as a scikit-learn classifier (module
    docstring: input, sub-windows, network, interpretations).

    Parameters
    ----------
    sensor : the data's SensorSpec; gives the grid (the run engine passes it).
    grid : (H, W) of a frame, only without a sensor (else it must be the
        sensor's); the row length must be a multiple of H * W.
    length : frames taken from each capture when ``X`` is a list of captures (their
        first ``length`` frames; a shorter capture padded by repeating its last
        frame); None: the longest training capture. A 2-D ``X`` holds flattened
        frames (``raw-window``'s layout) and gives its own length.
    L : number of sub-windows per capture; F = floor(F_total / L) frames each.
    train_windows, test_windows : ``"first"`` (the paper), ``"all"``, a
        window index or a list of indices.
    vote : ``"soft"`` or ``"hard"``, combines a capture's test windows.
    max_epochs, batch_size, learning_rate, weight_decay : Adam training.
    patience : epochs without a lower validation loss before stopping.
    validation_fraction : share of the training captures (or of the
        training ``groups``) held out for early stopping; 0 disables it.
    validation_by : ``"groups"`` (hold out whole ``groups`` when ``fit`` is
        given them) or ``"rows"`` (ignore them: rows drawn stratified by
        label; the leakage audit's window variant, where the rows are windows
        and the paper says nothing of a validation split).
    scaling : ``"standard"`` (one mean / std over training cells) or ``"none"``.
    channels, hidden_units : Table 1's (32, 64, 128) and 256.
    random_state : seed of everything random in ``fit``.
    device : ``"cpu"`` (deterministic) or a torch device string.
    n_jobs : torch threads during fit and predict (default 1; -1 = all cores).
    verbose : print one line per epoch when > 0.

    The domains are declared (``_parameter_constraints``: checked when a protocol is read and when
    ``fit`` begins). Upper bounds where a value only costs: ``max_epochs`` at most 100,000 (an
    epoch is a pass over the training windows, as the MLP's), ``hidden_units`` at most 16,384 and
    each of ``channels`` at most 4,096 (64 and 32 times Table 1's 256 and 128: the weights grow
    with their products). ``L`` has no upper bound of its own: a run whose captures are shorter
    than ``L`` frames is refused by :meth:`check_sensor`. ``patience`` at least 1 (0 would stop
    after the first epoch); ``n_jobs`` -1 (every core) or at least 1.
    """

    _parameter_constraints = {
        "sensor": "no_validation", "grid": ["array-like", None],
        "length": [Interval(Integral, 1, None, closed="left"), None],
        "L": [Interval(Integral, 1, None, closed="left")],
        "train_windows": WINDOWS, "test_windows": WINDOWS,
        "vote": [StrOptions({"soft", "hard"})],
        "max_epochs": [Interval(Integral, 1, 100_000, closed="both")],
        "batch_size": [Interval(Integral, 1, None, closed="left")],
        "learning_rate": [Interval(Real, 0, None, closed="neither")],
        "weight_decay": [Interval(Real, 0, None, closed="left")],
        "patience": [Interval(Integral, 1, None, closed="left")],
        "validation_fraction": [Interval(Real, 0, 1, closed="left"), None],
        "validation_by": [StrOptions({"groups", "rows"})],
        "scaling": [StrOptions({"standard", "none"})],
        "channels": [ListOf([Interval(Integral, 1, 4096, closed="both")], length=3)],
        "hidden_units": [Interval(Integral, 1, 16_384, closed="both")],
        "random_state": ["random_state"], "device": [str], "n_jobs": TORCH_JOBS, "verbose": ["verbose"],
    }

    def __init__(self, sensor=None, grid=None, length=None, L=30, train_windows="first", test_windows="first", vote="soft",
                 max_epochs=100, batch_size=32, learning_rate=1e-3, weight_decay=0.0, patience=10,
                 validation_fraction=0.1, scaling="standard", channels=(32, 64, 128), hidden_units=256,
                 random_state=None, device="cpu", n_jobs=1, verbose=0, validation_by="groups"):
        self.sensor = sensor
        self.grid = grid
        self.length = length
        self.L = L
        self.train_windows = train_windows
        self.test_windows = test_windows
        self.vote = vote
        self.max_epochs = max_epochs
        self.batch_size = batch_size
        self.learning_rate = learning_rate
        self.weight_decay = weight_decay
        self.patience = patience
        self.validation_fraction = validation_fraction
        self.scaling = scaling
        self.channels = channels
        self.hidden_units = hidden_units
        self.random_state = random_state
        self.device = device
        self.n_jobs = n_jobs
        self.verbose = verbose
        self.validation_by = validation_by

    # -- shapes ---------------------------------------------------------------
    def check_sensor(self, sensor, min_frames=None):
        """Why the CNN cannot serve ``sensor`` with captures of at least ``min_frames`` frames, or None."""
        try:
            sensor_frames("HaartCNNClassifier", sensor, self.grid)
        except ValueError as e:
            return str(e)
        if min_frames is not None and isinstance(self.L, (int, np.integer)) and min_frames < int(self.L):
            return (f"cnn: L={int(self.L)} windows need captures of at least {int(self.L)} frames (one frame per window); "
                    f"the shortest has {min_frames}: lower L")
        return None

    def _windows(self, X, idx):
        """(n, F_total*H*W) rows -> (n, len(idx), F, H, W) float32 windows."""
        n = X.shape[0]
        H, W = self.grid_
        F, L = self.frames_per_window_, int(self.L)
        frames = X.reshape(n, self.n_frames_total_, H, W)[:, : L * F]
        return frames.reshape(n, L, F, H, W)[:, idx].astype(np.float32)

    # -- fit ------------------------------------------------------------------
    def fit(self, X, y, groups=None, test_set=None):
        """Fit on captures ``X`` with labels ``y``; ``groups`` (e.g. subjects),
        if given, makes the early-stopping split hold out whole groups.
        ``test_set``: ``(X_test, y_test)``, a leak: early stopping on the
        test data's accuracy instead of a validation split (module docstring)."""
        torch = import_torch("cnn")
        check_declared(self)
        grid, _ = sensor_frames("HaartCNNClassifier", self.sensor, self.grid)
        if is_captures(X):  # the captures as recorded: the stated length, else the longest training capture
            length = int(self.length) if self.length is not None else max(len(c) for c in X)
            X = captures_to_rows(X, grid, length, "cnn")
        X, y = validate_data(self, X, y, dtype=np.float64)
        check_classification_targets(y)
        self.grid_ = grid
        self.n_frames_total_ = frames_in_row(X.shape[1], grid, "HaartCNNClassifier")
        self.frames_per_window_ = self.n_frames_total_ // int(self.L)
        if self.frames_per_window_ < 1:
            raise ValueError(f"L={self.L} leaves no frame per window ({self.n_frames_total_} frames in a capture)")
        self.classes_, yi = np.unique(y, return_inverse=True)
        train_idx = _window_indices(self.train_windows, int(self.L), "train_windows")
        _window_indices(self.test_windows, int(self.L), "test_windows")

        rs = check_random_state(self.random_state)
        seed = int(rs.randint(MAX_SEED))
        rng = np.random.default_rng(seed)
        by = groups if self.validation_by == "groups" else None
        fraction = 0.0 if test_set is not None else self.validation_fraction  # the test data stop it instead
        fit_rows, val_rows, self.validation_groups_ = validation_split(yi, by, rng, fraction)
        self.validation_size_ = len(val_rows)

        Wtr = self._windows(X[fit_rows], train_idx)  # (n, w, F, H, W)
        ytr = np.repeat(yi[fit_rows], len(train_idx))
        Wtr = Wtr.reshape(-1, *Wtr.shape[2:])
        if self.scaling == "standard":
            self.scale_mean_ = float(Wtr.mean(dtype=np.float64))
            sd = float(Wtr.std(dtype=np.float64))
            self.scale_std_ = sd if sd > 0 else 1.0
        else:
            self.scale_mean_, self.scale_std_ = 0.0, 1.0
        Wtr = (Wtr - np.float32(self.scale_mean_)) / np.float32(self.scale_std_)
        if len(val_rows):
            Wva = self._scaled_windows(X[val_rows], train_idx)
            yva = np.repeat(yi[val_rows], len(train_idx))

        val = (Wva, yva) if len(val_rows) else None
        score = self._test_accuracy(torch, *test_set) if test_set is not None else None
        net, self.history_, self.best_epoch_ = self._train(torch, seed, rng, Wtr, ytr, val, score)
        self.net_ = net.to("cpu") if self.device != "cpu" else net
        self.n_epochs_ = len(self.history_)
        return self

    def _train(self, torch, seed, rng, Wtr, ytr, val, score):
        """Table 1's network trained on the scaled windows ``Wtr`` (labels ``ytr``), early stopping on
        ``val`` (windows, labels) or on ``score``: ``(network, history, best epoch)``."""
        with Threads(torch, self.n_jobs), torch.random.fork_rng(devices=[]):
            torch.manual_seed(seed)
            dev = torch.device(self.device)
            net = build_network(torch, self.frames_per_window_, self.grid_, len(self.classes_),
                                tuple(self.channels), int(self.hidden_units)).to(dev)
            opt = torch.optim.Adam(net.parameters(), lr=self.learning_rate, weight_decay=self.weight_decay)
            xt = torch.from_numpy(np.ascontiguousarray(Wtr)).to(dev)
            yt = torch.from_numpy(ytr.astype(np.int64)).to(dev)
            xv = yv = None
            if val is not None:
                xv = torch.from_numpy(np.ascontiguousarray(val[0])).to(dev)
                yv = torch.from_numpy(val[1].astype(np.int64)).to(dev)
            history, best_epoch = train(torch, net, opt, xt, yt, rng, max_epochs=int(self.max_epochs),
                                        batch_size=int(self.batch_size), xv=xv, yv=yv, patience=int(self.patience),
                                        verbose=self.verbose, score=score)
        net.eval()
        return net, history, best_epoch

    def _test_accuracy(self, torch, X_test, y_test):
        """The leak of ``fit``'s ``test_set``: a function of the network giving its accuracy on the test
        captures, labelled as :meth:`predict` labels them (a label unseen in training counts as wrong)."""
        if is_captures(X_test):
            X_test = captures_to_rows(X_test, self.grid_, self.n_frames_total_, "cnn")
        X_test = np.asarray(X_test, dtype=np.float64)
        y_test = np.asarray(y_test)
        known = np.isin(y_test, self.classes_)
        codes = np.where(known, np.searchsorted(self.classes_, y_test), -1)
        Wx = self._scaled_windows(X_test, _window_indices(self.test_windows, int(self.L), "test_windows"))

        def accuracy(net):
            p = self._softmax(torch, net, Wx, len(X_test))
            return float(np.mean(np.argmax(self._vote(p)[1], axis=1) == codes)) if len(codes) else 0.0
        return accuracy

    def __getstate__(self):
        """Saved with the network's weights as numpy arrays (:mod:`.torch_state`): the network is built again."""
        state = dict(super().__getstate__())  # a copy: the fitted estimator keeps its network
        if state.get("net_") is not None:
            state["net_"] = weights_as_arrays(state["net_"])
        return state

    def __setstate__(self, state):
        super().__setstate__(state)
        if isinstance(getattr(self, "net_", None), dict):
            torch = import_torch("cnn")
            net = build_network(torch, self.frames_per_window_, self.grid_, len(self.classes_),
                                tuple(self.channels), int(self.hidden_units))
            self.net_ = load_weights(torch, net, self.net_)

    # -- predict --------------------------------------------------------------
    def _scaled_windows(self, X, idx):
        """(n, F_total*H*W) rows -> (n * len(idx), F, H, W) windows, scaled as in training."""
        Wx = self._windows(X, idx)
        return (Wx.reshape(-1, *Wx.shape[2:]) - np.float32(self.scale_mean_)) / np.float32(self.scale_std_)

    def _softmax(self, torch, net, Wx, n):
        """The network's softmax of ``n`` captures' scaled windows: (n, windows, classes)."""
        with Threads(torch, self.n_jobs):
            p = softmax_batches(torch, net, torch.from_numpy(np.ascontiguousarray(Wx)), len(self.classes_))
        return p.reshape(n, -1, len(self.classes_))

    def _window_proba(self, X):
        torch = import_torch("cnn")
        check_is_fitted(self)
        if is_captures(X):
            X = captures_to_rows(X, self.grid_, self.n_frames_total_, "cnn")
        X = validate_data(self, X, dtype=np.float64, reset=False)
        idx = _window_indices(self.test_windows, int(self.L), "test_windows")
        return self._softmax(torch, self.net_, self._scaled_windows(X, idx), X.shape[0])

    def _vote(self, p):
        """A capture's windows' softmax ``p`` (n, windows, classes) combined: ``(probabilities, key)``,
        the label being the key's argmax. Soft: both the mean of the windows' softmax. Hard: the share
        of windows voting for each class; the key adds half the soft mean (below one vote), which only
        orders classes with equal vote counts."""
        soft = p.mean(axis=1)
        if self.vote == "soft" or p.shape[1] == 1:
            return soft, soft
        votes = np.zeros_like(soft)
        win = p.argmax(axis=2)
        for j in range(p.shape[1]):
            votes[np.arange(p.shape[0]), win[:, j]] += 1.0
        return votes / p.shape[1], votes + soft / 2.0

    def predict_proba(self, X):
        """Capture probabilities: the soft vote (mean of the windows' softmax),
        or with ``vote="hard"`` the share of windows voting for each class."""
        return self._vote(self._window_proba(X))[0]

    def predict(self, X):
        key = self._vote(self._window_proba(X))[1]  # first: an unfitted estimator says so (no classes_ yet)
        return self.classes_[np.argmax(key, axis=1)]


DEFAULTS = {
    "length": None, "L": 30, "train_windows": "first", "test_windows": "first", "vote": "soft",
    "max_epochs": 100, "batch_size": 32, "learning_rate": 1e-3, "weight_decay": 0.0, "patience": 10,
    "validation_fraction": 0.1, "validation_by": "groups", "scaling": "standard", "channels": (32, 64, 128), "hidden_units": 256,
    "device": "cpu", "n_jobs": 1,
}


def check_windows(params: dict) -> None:
    """The rule across fields: a capture cut or padded to ``length`` frames holds ``L`` windows of at
    least one frame each (``length`` is set by the run engine unless a protocol sets it)."""
    length, L = params.get("length"), params.get("L", 30)
    if isinstance(length, int) and isinstance(L, int) and not isinstance(length, bool) and length < L:
        raise ParamError(("length",), f"length {length} leaves no frame per window for L={L}: at least L frames")


@CLASSIFIERS.register(
    "cnn",
    description="raw-frame CNN (3 conv blocks + FC 256, softmax) on H x W x F windows, F = floor(frames/L), L = 30",
    source=SOURCE, defaults=DEFAULTS, extra="deep", input="captures", check_params=check_windows,
    cheap_params=dict(max_epochs=3, channels=(4, 8, 8), hidden_units=16), stops_on_test=True,
)
def cnn(random_state=None, sensor=None, **params):
    """The CNN; raises a TouchbenchError with the install command without PyTorch."""
    if not torch_available():
        raise TouchbenchError(f"the 'cnn' classifier needs PyTorch, which is not installed: {INSTALL_HINT}")
    return build(HaartCNNClassifier, DEFAULTS, random_state, {**params, "sensor": sensor}, name="cnn")
