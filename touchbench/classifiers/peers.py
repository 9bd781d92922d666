"""Peers: off-the-shelf time-series classifiers from aeon, run on the cell series.

MiniRocket (Dempster, Schmidt and Webb, KDD 2021) and MultiRocket (Tan,
Dempster, Bergmeir and Webb, DMKD 2022) as aeon ships them
(``aeon.classification.convolution_based``), defaults unchanged: 10,000
kernels, a ridge classifier with cross-validated regularisation (aeon's
default estimator), one thread. They are the methods touchbench's own must
beat: an off-the-shelf MiniRocket on HAART's 64 cell series is
about 71 % on the challenge test subjects.

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

A training set of one class gets no aeon model: the peer predicts that
class (the run engine does the same for a one-class training fold).

aeon is an optional extra: ``pip install 'touchbench[peers]'``; it is
imported when a peer is fitted, never when the registry is listed.
"""

from __future__ import annotations

import numpy as np
from sklearn.base import BaseEstimator, ClassifierMixin
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

INSTALL_HINT = "pip install 'touchbench[peers]'  (or: pip install aeon)"
SOURCE_MINI = "Dempster et al. 2021 (MiniRocket), aeon 1.x MiniRocketClassifier, defaults"
SOURCE_MULTI = "Tan et al. 2022 (MultiRocket), aeon 1.x MultiRocketClassifier, defaults"


def aeon_available() -> bool:
    """Whether aeon can be imported, without importing it."""
    return importable("aeon")


MIN_TIMEPOINTS = 9


def frames_to_series(X: np.ndarray, grid: tuple[int, int]) -> np.ndarray:
    """Flattened frames ``(n, F * H * W)`` -> cell series ``(n, H * W, max(F, 9))`` float64, C-contiguous.

    Fewer than ``MIN_TIMEPOINTS`` frames are padded by repeating the last one.
    """
    f = frames_in_row(X.shape[1], grid)
    cells = int(grid[0]) * int(grid[1])
    S = X.reshape(X.shape[0], f, cells).transpose(0, 2, 1)
    if f < MIN_TIMEPOINTS:
        S = np.concatenate([S, np.repeat(S[:, :, -1:], MIN_TIMEPOINTS - f, axis=2)], axis=2)
    return np.ascontiguousarray(S, dtype=np.float64)


class _RocketPeer(ClassifierMixin, BaseEstimator):
    """An aeon Rocket-family classifier over the cells of raw frames."""

    _aeon_class = ""

    def __init__(self, sensor=None, grid=None, length=None, n_kernels=10000, max_dilations_per_kernel=32, n_jobs=1,
                 random_state=None):
        self.sensor = sensor
        self.grid = grid
        self.length = length
        self.n_kernels = n_kernels
        self.max_dilations_per_kernel = max_dilations_per_kernel
        self.n_jobs = n_jobs
        self.random_state = random_state

    def _make(self, seed: int):
        if not aeon_available():
            raise TouchbenchError(f"the {type(self).__name__} peer needs aeon, which is not installed: {INSTALL_HINT}")
        from aeon.classification import convolution_based

        cls = getattr(convolution_based, self._aeon_class)
        return cls(n_kernels=int(self.n_kernels), max_dilations_per_kernel=int(self.max_dilations_per_kernel),
                   n_jobs=int(self.n_jobs), random_state=seed)

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
        self.model_.fit(frames_to_series(X, self.grid_), y)
        return self

    def predict(self, X):
        check_is_fitted(self)
        X = validate_data(self, self._rows(X), dtype=np.float64, reset=False)
        if self.model_ is None:
            return np.repeat(self.classes_, X.shape[0])
        return np.asarray(self.model_.predict(frames_to_series(X, self.grid_)))

    def predict_proba(self, X):
        """aeon's probabilities (for the ridge estimator: one-hot of the prediction)."""
        check_is_fitted(self)
        X = validate_data(self, self._rows(X), dtype=np.float64, reset=False)
        if self.model_ is None:
            return np.ones((X.shape[0], 1))
        P = np.asarray(self.model_.predict_proba(frames_to_series(X, self.grid_)), dtype=np.float64)
        order = [list(self.model_.classes_).index(c) for c in self.classes_]
        return P[:, order]


class MiniRocketPeer(_RocketPeer):
    """aeon's ``MiniRocketClassifier`` on the H x W cell series."""

    _aeon_class = "MiniRocketClassifier"


class MultiRocketPeer(_RocketPeer):
    """aeon's ``MultiRocketClassifier`` on the H x W cell series."""

    _aeon_class = "MultiRocketClassifier"


DEFAULTS = {"length": None, "n_kernels": 10000, "max_dilations_per_kernel": 32, "n_jobs": 1}


@CLASSIFIERS.register("minirocket", description="peer: aeon MiniRocket (10k kernels + ridge) on the H x W cell series of raw-window frames",
                      source=SOURCE_MINI, defaults=DEFAULTS, extra="peers", input="captures", cheap_params=dict(n_kernels=84))
def minirocket(random_state=None, sensor=None, **params):
    return build(MiniRocketPeer, DEFAULTS, random_state, {**params, "sensor": sensor}, name="minirocket")


@CLASSIFIERS.register("multirocket", description="peer: aeon MultiRocket (10k kernels, 4 poolings + ridge) on the H x W cell series of raw-window frames",
                      source=SOURCE_MULTI, defaults=DEFAULTS, extra="peers", input="captures", cheap_params=dict(n_kernels=84))
def multirocket(random_state=None, sensor=None, **params):
    return build(MultiRocketPeer, DEFAULTS, random_state, {**params, "sensor": sensor}, name="multirocket")
