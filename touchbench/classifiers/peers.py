"""Peers: off-the-shelf time-series classifiers from aeon, run on the cell series.

As aeon ships them, defaults unchanged (one thread where they take one):

- MiniRocket (Dempster, Schmidt and Webb, KDD 2021) and MultiRocket (Tan,
  Dempster, Bergmeir and Webb, DMKD 2022),
  ``aeon.classification.convolution_based``: 10,000 kernels, a ridge
  classifier with cross-validated regularisation (aeon's default
  estimator). An off-the-shelf MiniRocket on HAART's 64 cell series is
  about 71 % on the challenge test subjects.
- MultiRocket-Hydra (Dempster, Schmidt and Webb, "Hydra: competing
  convolutional kernels for fast and accurate time series
  classification", DMKD 2023, section 5: Hydra's features concatenated with
  MultiRocket's, a ridge classifier): 64 groups of 8 kernels. aeon runs
  Hydra in PyTorch, so it needs the ``deep`` extra too.
- QUANT (Dempster, Schmidt and Webb, "QUANT: a minimalist interval method
  for time series classification", DMKD 2024): quantiles over dyadic
  intervals (depth 6, a quarter of each interval's values) of the series,
  its first and second differences and its Fourier magnitudes, fed to
  extra-trees (aeon's default: 200 trees, ``max_features=0.1``,
  entropy). aeon computes the quantiles in PyTorch (``deep`` extra).
- RDST (Guillaume, Vrain and Elloumi, "Random dilated shapelet
  transform", ICPRAM 2022): 10,000 random dilated shapelets, a ridge
  classifier, ``aeon.classification.shapelet_based``.

These are the methods touchbench's own must beat.

Input: the captures as recorded (a list of ``(T, H, W)`` arrays in their
native dtype: the run engine hands a peer the captures, see
:mod:`touchbench.methods`), or a 2-D matrix of flattened frames in
``raw-window``'s layout (frame-major, row-major: ``X.reshape(n, F, H,
W)``). The grid ``(H, W)`` is the
sensor's: the run engine passes the dataset's sensor (``sensor``); from
Python without a sensor, ``grid`` must be given (a grid given with a
sensor must be the sensor's). ``grid_`` records the grid a fitted peer
used. Each of the H x W cells is one channel of a multivariate series of
F time points: the classifier passes aeon an ``(n, H * W, F)`` array,
values as recorded (no scaling: the kernels' biases come from the
training data's own quantiles).

Unequal lengths: aeon's Rocket family needs equal-length series here.
Captures are cut to ``length`` frames (a stated parameter; beside
``[raw-window]`` in a protocol, raw-window's ``frames``; None: the longest
training capture), a shorter one padded by repeating its last frame.
``raw-window`` itself makes every capture exactly F frames (a stated parameter;
432, HAART's length, in the HAART protocols): a shorter capture is
refused or padded by repeating its last frame (raw-window's stated
``shorter`` rule), a longer one truncated to its first F frames. HAART's
captures are all 432 frames, so on ``haart`` and ``haart-challenge``
nothing is padded. This is stated in the protocol (``touch-haart``) and so
in every run's manifest. Series shorter than aeon's minimum (``MIN_TIMEPOINTS`` = 9, the
length of MiniRocket's kernels) are padded here the same way, by repeating
the last frame (a held pose; aeon itself asks for zero padding, which on a
pressure sensor would invent a release).

Declared domains (``_parameter_constraints``, checked when a protocol is read), from what
aeon 1.x does with a value: MiniRocket silently runs 84 kernels for any
``n_kernels`` below 84 and MultiRocket divides by zero there (both use
``n_kernels // 84`` kernels of each of the 84 shapes), so ``n_kernels`` is at
least 84; ``max_dilations_per_kernel`` 0, Hydra's ``n_kernels`` or ``n_groups``
0, QUANT's ``interval_depth`` or ``quantile_divisor`` 0 and RDST's
``max_shapelets`` 0 fail inside aeon, so each is at least 1. Upper bounds
where a count only costs: ``n_kernels`` and ``max_shapelets`` at most
100,000 (ten times the papers' 10,000; every kernel or shapelet gives each
capture one to eight features, a matrix of some gigabytes on HAART at the
bound), Hydra's ``n_kernels`` at most 128 and ``n_groups`` at most 1,024 (16
times the paper's 8 and 64: the features grow as their product), QUANT's
``interval_depth`` at most 16 (``2**depth - 1`` intervals per
representation). ``n_jobs``: None or a whole number other than 0 (-1: every
core). The engine's ``sensor``, ``grid`` and ``length`` are declared as
they come (a sensor, an ``(H, W)`` pair, a frame count).

A training set of one class gets no aeon model: the peer predicts that
class (the run engine does the same for a one-class training fold).

aeon is an optional extra: ``pip install 'touchbench[peers]'``; it is
imported when a peer is fitted, never when the registry is listed.
"""

from __future__ import annotations

import importlib
import sys
from numbers import Integral

import numpy as np
from sklearn.base import BaseEstimator, ClassifierMixin
from sklearn.utils._param_validation import Interval
from sklearn.utils.multiclass import check_classification_targets
from sklearn.utils.validation import check_is_fitted, validate_data

from ..core.errors import TouchbenchError
from ._util import (
    build,
    captures_to_rows,
    frames_in_row,
    importable,
    is_captures,
    seed_int,
    sensor_frames,
)
from .base import CLASSIFIERS
from .torch_state import decode_torch, encode_torch

INSTALL_HINT = "pip install 'touchbench[peers]'  (or: pip install aeon)"
INSTALL_HINT_TORCH = "pip install 'touchbench[peers,deep]'  (or: pip install aeon torch)"
SOURCE_MINI = "Dempster et al. 2021 (MiniRocket), aeon 1.x MiniRocketClassifier, defaults"
SOURCE_MULTI = "Tan et al. 2022 (MultiRocket), aeon 1.x MultiRocketClassifier, defaults"


def aeon_available() -> bool:
    """Whether aeon can be imported, without importing it."""
    return importable("aeon")


MIN_TIMEPOINTS = 9


def frames_to_series(X: np.ndarray, grid: tuple[int, int], minimum: int = MIN_TIMEPOINTS) -> np.ndarray:
    """Flattened frames ``(n, F * H * W)`` -> cell series ``(n, H * W, max(F, minimum))`` float64, C-contiguous.

    Fewer than ``minimum`` frames are padded by repeating the last one.
    """
    f = frames_in_row(X.shape[1], grid)
    cells = int(grid[0]) * int(grid[1])
    S = X.reshape(X.shape[0], f, cells).transpose(0, 2, 1)
    if f < minimum:
        S = np.concatenate([S, np.repeat(S[:, :, -1:], minimum - f, axis=2)], axis=2)
    return np.ascontiguousarray(S, dtype=np.float64)


class _AeonPeer(ClassifierMixin, BaseEstimator):
    """An aeon classifier over the cells of raw frames.

    A subclass names aeon's module and class, the packages aeon needs for
    it (``_requires``) and the shortest series it takes; every parameter of
    its own beyond :data:`_OWN` is forwarded to aeon under the same name.
    """

    _OWN = ("sensor", "grid", "length", "random_state")
    #: the engine's parameters, declared as the engine passes them (module docstring)
    _parameter_constraints = {"sensor": "no_validation", "grid": ["array-like", None],
                              "length": [Interval(Integral, 1, None, closed="left"), None],
                              "random_state": ["random_state"]}
    _aeon_module = "aeon.classification.convolution_based"
    _aeon_class = ""
    _requires: tuple[str, ...] = ("aeon",)
    _min_timepoints = MIN_TIMEPOINTS

    def _make(self, seed: int):
        missing = [m for m in self._requires if not importable(m)]
        if missing:
            hint = INSTALL_HINT if missing == ["aeon"] else INSTALL_HINT_TORCH
            raise TouchbenchError(f"the {type(self).__name__} peer needs {' and '.join(missing)}, "
                                  f"which {'is' if len(missing) == 1 else 'are'} not installed: {hint}")
        cls = getattr(importlib.import_module(self._aeon_module), self._aeon_class)
        params = {p: v for p, v in self.get_params(deep=False).items() if p not in self._OWN}
        return cls(**{k: (int(v) if isinstance(v, (int, np.integer)) and not isinstance(v, bool) else v)
                      for k, v in params.items()}, random_state=seed)

    def _series(self, X):
        return frames_to_series(X, self.grid_, self._min_timepoints)

    def __getstate__(self):
        """Saved with aeon's torch tensors and modules as arrays (:mod:`.torch_state`): a model file holds data."""
        state = super().__getstate__()
        if "torch" in sys.modules and getattr(self, "model_", None) is not None:
            state = {**state, "model_": encode_torch(state["model_"])}
        return state

    def __setstate__(self, state):
        super().__setstate__(state)
        if getattr(self, "model_", None) is not None and "torch" in self._requires:
            self.model_ = decode_torch(self.model_)

    def check_sensor(self, sensor, min_frames=None):
        """Why this peer cannot serve ``sensor`` (a ``grid`` that is not its own), or None."""
        try:
            sensor_frames(type(self).__name__, sensor, self.grid)
        except ValueError as e:
            return str(e)
        return None

    def _rows(self, X):
        """Captures -> rows of ``length_`` frames (see the module docstring); rows pass as they are."""
        if is_captures(X):
            return captures_to_rows(X, self.grid_, self.length_, type(self).__name__)
        return X

    def fit(self, X, y):
        self.grid_, _ = sensor_frames(type(self).__name__, self.sensor, self.grid)
        if is_captures(X):  # the captures as recorded: the stated length, else the longest training capture
            self.length_ = int(self.length) if self.length is not None else max(len(c) for c in X)
            X = self._rows(X)
        X, y = validate_data(self, X, y, dtype=np.float64)
        check_classification_targets(y)
        self.length_ = frames_in_row(X.shape[1], self.grid_, type(self).__name__)
        self.classes_ = np.unique(y)
        if len(self.classes_) == 1:
            self.model_ = None  # one class: nothing to learn
            return self
        self.model_ = self._make(seed_int(self.random_state))
        self.model_.fit(self._series(X), y)
        return self

    def predict(self, X):
        check_is_fitted(self)
        X = validate_data(self, self._rows(X), dtype=np.float64, reset=False)
        if self.model_ is None:
            return np.repeat(self.classes_, X.shape[0])
        return np.asarray(self.model_.predict(self._series(X)))

    def predict_proba(self, X):
        """aeon's probabilities (for a ridge estimator: one-hot of the prediction)."""
        check_is_fitted(self)
        X = validate_data(self, self._rows(X), dtype=np.float64, reset=False)
        if self.model_ is None:
            return np.ones((X.shape[0], 1))
        P = np.asarray(self.model_.predict_proba(self._series(X)), dtype=np.float64)
        order = [list(self.model_.classes_).index(c) for c in self.classes_]
        return P[:, order]


#: None, or a whole number other than 0 (aeon's and joblib's: -1 every core, -2 all but one)
N_JOBS = [Interval(Integral, 1, None, closed="left"), Interval(Integral, None, -1, closed="right"), None]
#: the most kernels or shapelets: ten times the papers' 10,000 (module docstring)
MAX_KERNELS = 100_000


class _RocketPeer(_AeonPeer):
    """MiniRocket and MultiRocket: the parameters they share (bounds: module docstring)."""

    _parameter_constraints = {**_AeonPeer._parameter_constraints,
                              "n_kernels": [Interval(Integral, 84, MAX_KERNELS, closed="both")],
                              "max_dilations_per_kernel": [Interval(Integral, 1, None, closed="left")],
                              "n_jobs": N_JOBS}

    def __init__(self, sensor=None, grid=None, length=None, n_kernels=10000, max_dilations_per_kernel=32, n_jobs=1,
                 random_state=None):
        self.sensor = sensor
        self.grid = grid
        self.length = length
        self.n_kernels = n_kernels
        self.max_dilations_per_kernel = max_dilations_per_kernel
        self.n_jobs = n_jobs
        self.random_state = random_state


class MiniRocketPeer(_RocketPeer):
    """aeon's ``MiniRocketClassifier`` on the H x W cell series."""

    _aeon_class = "MiniRocketClassifier"


class MultiRocketPeer(_RocketPeer):
    """aeon's ``MultiRocketClassifier`` on the H x W cell series."""

    _aeon_class = "MultiRocketClassifier"


class MultiRocketHydraPeer(_AeonPeer):
    """aeon's ``MultiRocketHydraClassifier`` on the H x W cell series (aeon runs Hydra in PyTorch)."""

    _aeon_class = "MultiRocketHydraClassifier"
    _requires = ("aeon", "torch")
    _min_timepoints = MIN_TIMEPOINTS + 1  # its MultiRocket half also convolves the first differences
    #: 16 times the paper's 8 kernels per group and 64 groups at most (module docstring)
    _parameter_constraints = {**_AeonPeer._parameter_constraints,
                              "n_kernels": [Interval(Integral, 1, 128, closed="both")],
                              "n_groups": [Interval(Integral, 1, 1024, closed="both")], "n_jobs": N_JOBS}

    def __init__(self, sensor=None, grid=None, length=None, n_kernels=8, n_groups=64, n_jobs=1, random_state=None):
        self.sensor = sensor
        self.grid = grid
        self.length = length
        self.n_kernels = n_kernels
        self.n_groups = n_groups
        self.n_jobs = n_jobs
        self.random_state = random_state


class QuantPeer(_AeonPeer):
    """aeon's ``QUANTClassifier`` on the H x W cell series (aeon computes the quantiles in PyTorch)."""

    _aeon_module = "aeon.classification.interval_based"
    _aeon_class = "QUANTClassifier"
    _requires = ("aeon", "torch")
    #: depth 16 at most: 2**16 - 1 intervals per representation (module docstring)
    _parameter_constraints = {**_AeonPeer._parameter_constraints,
                              "interval_depth": [Interval(Integral, 1, 16, closed="both")],
                              "quantile_divisor": [Interval(Integral, 1, None, closed="left")]}

    def __init__(self, sensor=None, grid=None, length=None, interval_depth=6, quantile_divisor=4, random_state=None):
        self.sensor = sensor
        self.grid = grid
        self.length = length
        self.interval_depth = interval_depth
        self.quantile_divisor = quantile_divisor
        self.random_state = random_state


class RDSTPeer(_AeonPeer):
    """aeon's ``RDSTClassifier`` (random dilated shapelets + ridge) on the H x W cell series."""

    _aeon_module = "aeon.classification.shapelet_based"
    _aeon_class = "RDSTClassifier"
    _parameter_constraints = {**_AeonPeer._parameter_constraints,
                              "max_shapelets": [Interval(Integral, 1, MAX_KERNELS, closed="both")], "n_jobs": N_JOBS}

    def __init__(self, sensor=None, grid=None, length=None, max_shapelets=10000, n_jobs=1, random_state=None):
        self.sensor = sensor
        self.grid = grid
        self.length = length
        self.max_shapelets = max_shapelets
        self.n_jobs = n_jobs
        self.random_state = random_state


DEFAULTS = {"length": None, "n_kernels": 10000, "max_dilations_per_kernel": 32, "n_jobs": 1}


@CLASSIFIERS.register("minirocket", description="peer: aeon MiniRocket (10k kernels + ridge) on the H x W cell series of raw-window frames",
                      source=SOURCE_MINI, defaults=DEFAULTS, extra="peers", input="captures", cheap_params=dict(n_kernels=84))
def minirocket(random_state=None, sensor=None, **params):
    return build(MiniRocketPeer, DEFAULTS, random_state, {**params, "sensor": sensor}, name="minirocket")


@CLASSIFIERS.register("multirocket", description="peer: aeon MultiRocket (10k kernels, 4 poolings + ridge) on the H x W cell series of raw-window frames",
                      source=SOURCE_MULTI, defaults=DEFAULTS, extra="peers", input="captures", cheap_params=dict(n_kernels=84))
def multirocket(random_state=None, sensor=None, **params):
    return build(MultiRocketPeer, DEFAULTS, random_state, {**params, "sensor": sensor}, name="multirocket")


SOURCE_MRHYDRA = "Dempster, Schmidt and Webb 2023 (Hydra, with MultiRocket), aeon 1.x MultiRocketHydraClassifier, defaults"
SOURCE_QUANT = "Dempster, Schmidt and Webb 2024 (QUANT), aeon 1.x QUANTClassifier, defaults"
SOURCE_RDST = "Guillaume, Vrain and Elloumi 2022 (RDST), aeon 1.x RDSTClassifier, defaults"
DEFAULTS_MRHYDRA = {"length": None, "n_kernels": 8, "n_groups": 64, "n_jobs": 1}
DEFAULTS_QUANT = {"length": None, "interval_depth": 6, "quantile_divisor": 4}
DEFAULTS_RDST = {"length": None, "max_shapelets": 10000, "n_jobs": 1}


@CLASSIFIERS.register("multirocket-hydra", description="peer: aeon MultiRocket-Hydra (Hydra's competing kernels + MultiRocket, ridge) on the H x W cell series of raw-window frames",
                      source=SOURCE_MRHYDRA, defaults=DEFAULTS_MRHYDRA, extra="peers,deep", input="captures",
                      cheap_params=dict(n_groups=4))
def multirocket_hydra(random_state=None, sensor=None, **params):
    return build(MultiRocketHydraPeer, DEFAULTS_MRHYDRA, random_state, {**params, "sensor": sensor}, name="multirocket-hydra")


@CLASSIFIERS.register("quant", description="peer: aeon QUANT (quantiles over dyadic intervals + extra-trees) on the H x W cell series of raw-window frames",
                      source=SOURCE_QUANT, defaults=DEFAULTS_QUANT, extra="peers,deep", input="captures",
                      cheap_params=dict(interval_depth=2))
def quant(random_state=None, sensor=None, **params):
    return build(QuantPeer, DEFAULTS_QUANT, random_state, {**params, "sensor": sensor}, name="quant")


@CLASSIFIERS.register("rdst", description="peer: aeon RDST (random dilated shapelets + ridge) on the H x W cell series of raw-window frames",
                      source=SOURCE_RDST, defaults=DEFAULTS_RDST, extra="peers", input="captures",
                      cheap_params=dict(max_shapelets=32))
def rdst(random_state=None, sensor=None, **params):
    return build(RDSTPeer, DEFAULTS_RDST, random_state, {**params, "sensor": sensor}, name="rdst")
