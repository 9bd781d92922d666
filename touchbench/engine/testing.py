"""Small datasets and test-only components for testing the engine and schemes.

Not used by a run. :func:`random_dataset` builds a :class:`TouchDataset` with
chosen metadata (subjects, gestures, sessions, groups...) and random
captures whose mean pressure depends on the gesture, so a classifier does
better than chance. :func:`components_for_tests` registers minimal feature sets
and classifiers (names starting ``test-``) and removes them afterwards; pass
:func:`register_test_components` as ``worker_setup`` to a parallel run so
the worker processes know them too.
"""

from __future__ import annotations

import contextlib
import itertools
from typing import Any, Iterator, Sequence

import numpy as np
import pandas as pd
from sklearn.base import BaseEstimator, ClassifierMixin
from sklearn.ensemble import RandomForestClassifier
from sklearn.linear_model import LogisticRegression
from sklearn.pipeline import make_pipeline
from sklearn.preprocessing import StandardScaler

from ..classifiers import CLASSIFIERS
from ..datasets.model import SensorSpec, TouchDataset
from ..features.base import FEATURES, FeatureSet

__all__ = [
    "INTERRUPT",
    "random_dataset",
    "register_test_components",
    "components_for_tests",
    "unregister_test_components",
]

SENSOR = SensorSpec(name="test-4x4", grid=(4, 4), frame_rate=10.0, value_range=(0.0, 255.0))


def random_dataset(
    subjects: Sequence[str] = ("s1", "s2", "s3"),
    gestures: Sequence[str] = ("pat", "rub", "stroke"),
    per_cell: int = 2,
    extra: dict[str, Sequence[Any]] | None = None,
    rows: list[dict[str, Any]] | None = None,
    frames: tuple[int, int] = (8, 12),
    seed: int = 0,
    name: str = "test-random",
    sensor: SensorSpec = SENSOR,
) -> TouchDataset:
    """A dataset of ``per_cell`` captures per (subject, gesture, *extra values*).

    ``extra`` adds metadata columns crossed with subject and gesture (e.g.
    ``{"session": [1, 2]}``); ``rows`` gives the metadata rows explicitly
    instead (each a dict with at least subject and gesture). ``sensor``
    gives the grid and value range (the values are clipped to it; uint8
    when it fits in 0..255, else uint16); ``frames`` the inclusive range of
    capture lengths.
    """
    rng = np.random.default_rng(seed)
    if rows is None:
        extra = dict(extra or {})
        keys = ["subject", "gesture", *extra]
        rows = []
        for combo in itertools.product(subjects, gestures, *extra.values()):
            for _ in range(per_cell):
                rows.append(dict(zip(keys, combo)))
    meta = pd.DataFrame(rows)
    meta.insert(0, "capture_id", [f"c{i:04d}" for i in range(len(meta))])
    lo, hi = sensor.value_range
    dtype = np.uint8 if lo >= 0 and hi <= 255 else np.uint16
    gest = sorted({str(g) for g in meta["gesture"]})
    level = {g: 20.0 + 25.0 * i for i, g in enumerate(gest)}
    caps = []
    for g in meta["gesture"]:
        t = int(rng.integers(frames[0], frames[1] + 1))
        base = rng.normal(level[str(g)], 15.0, size=(t, *sensor.grid))
        caps.append(np.clip(base, lo, hi).astype(dtype))
    return TouchDataset(name=name, captures=caps, meta=meta, sensor=sensor)


# ----------------------------------------------------------------- feature sets
class MeanFrame(FeatureSet):
    """Mean of every cell over the frames (fold-independent)."""

    paper = "test only"
    cost = "cheap"
    fold_dependent = False

    def __init__(self, scale: float = 1.0, sensor: SensorSpec | None = None):
        self.scale = scale
        self.sensor = sensor

    def _transform_one(self, capture: np.ndarray) -> np.ndarray:
        return self.scale * capture.astype(np.float64).mean(axis=0).reshape(-1)

    def feature_names(self, grid):
        return [f"mean_r{r}c{c}" for r in range(grid[0]) for c in range(grid[1])]


class CenteredMax(FeatureSet):
    """Maximum of every cell minus its mean over the training fold (fold-dependent)."""

    paper = "test only"
    cost = "cheap"
    fold_dependent = True

    def __init__(self, sensor: SensorSpec | None = None):
        self.sensor = sensor

    def _fit(self, captures, y=None) -> None:
        self.center_ = np.mean([c.astype(np.float64).max(axis=0).reshape(-1) for c in captures], axis=0)

    def _transform_one(self, capture: np.ndarray) -> np.ndarray:
        return capture.astype(np.float64).max(axis=0).reshape(-1) - self.center_

    def feature_names(self, grid):
        return [f"cmax_r{r}c{c}" for r in range(grid[0]) for c in range(grid[1])]


# ----------------------------------------------------------------- classifiers
def _logreg(random_state=None, C: float = 1.0, max_iter: int = 500):

    return make_pipeline(StandardScaler(), LogisticRegression(C=C, max_iter=max_iter, random_state=random_state))


def _forest(random_state=None, n_estimators: int = 10, max_features: str | float = "sqrt"):

    return RandomForestClassifier(n_estimators=n_estimators, max_features=max_features, random_state=random_state, n_jobs=1)


class AlwaysFails(ClassifierMixin, BaseEstimator):
    """Raises in ``fit`` (a task that fails must become a failed row)."""

    def __init__(self, random_state=None, message: str = "deliberate failure"):
        self.random_state = random_state
        self.message = message

    def fit(self, X, y):
        raise ValueError(self.message)

    def predict(self, X):  # pragma: no cover - never fitted
        raise RuntimeError("not fitted")


INTERRUPT: dict[str, int] = {"after": -1}


class InterruptAfter(ClassifierMixin, BaseEstimator):
    """A nearest-centroid classifier that raises KeyboardInterrupt once
    ``INTERRUPT["after"]`` fits have happened in this process (simulates
    Ctrl-C in the middle of a run; -1 never interrupts)."""

    last_groups: list[str] | None = None  # the groups the last fit received (tests read it)

    def __init__(self, random_state=None):
        self.random_state = random_state

    def fit(self, X, y, groups=None):
        if INTERRUPT["after"] == 0:
            INTERRUPT["after"] = -1
            raise KeyboardInterrupt
        if INTERRUPT["after"] > 0:
            INTERRUPT["after"] -= 1
        self.classes_ = np.unique(y)
        self.centroids_ = np.vstack([X[y == c].mean(axis=0) for c in self.classes_])
        self.groups_seen_ = None if groups is None else sorted(set(groups))
        InterruptAfter.last_groups = self.groups_seen_
        return self

    def predict(self, X):
        d = ((X[:, None, :] - self.centroids_[None]) ** 2).sum(axis=2)
        return self.classes_[np.argmin(d, axis=1)]


def _registries():

    return [
        (FEATURES, "test-mean", MeanFrame, "test only: mean of every cell", {}),
        (FEATURES, "test-centered", CenteredMax, "test only: max of every cell minus the training mean", {}),
        (CLASSIFIERS, "test-logreg", _logreg, "test only: standardised logistic regression", {}),
        (CLASSIFIERS, "test-forest", _forest, "test only: small random forest", {}),
        (CLASSIFIERS, "test-fail", AlwaysFails, "test only: raises in fit", {}),
        (CLASSIFIERS, "test-interrupt", InterruptAfter, "test only: nearest centroid that can simulate Ctrl-C", {}),
    ]


def register_test_components() -> None:
    """Register the ``test-*`` components (idempotent; usable as ``worker_setup``)."""
    for reg, name, obj, desc, tags in _registries():
        try:
            reg.names()  # load the real entries first (so they cannot clash later)
        except Exception:  # another module failing to import is not the tests' concern
            pass
        if name not in reg:
            reg.register(name, description=desc, **tags)(obj)


def unregister_test_components() -> None:
    for reg, name, *_ in _registries():
        reg._entries.pop(name, None)


@contextlib.contextmanager
def components_for_tests() -> Iterator[None]:
    """The ``test-*`` components, registered for the duration of the block."""
    register_test_components()
    try:
        yield
    finally:
        unregister_test_components()
