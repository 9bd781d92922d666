"""A method as one scikit-learn-style estimator over captures.

:class:`FeaturePipeline` fits its feature sets (built with the sensor of
the data) on the training captures, concatenates their outputs and fits the
estimator through :func:`touchbench.methods.fitting.fit_estimator`. It is
what ``touchbench train`` saves and ``predict`` / ``stream`` apply; the run
engine fits the same two halves, taking fold-independent features from its
cache instead of recomputing them.
"""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np

from ..datasets.model import SensorSpec
from ..features.base import make_feature_set, stack_features
from .base import MethodSpec
from .fitting import FittedEstimator, fit_estimator

__all__ = ["FeaturePipeline"]


class FeaturePipeline:
    """Feature sets -> estimator, fitted on captures.

    ``spec`` names the feature sets and the estimator; ``random_state`` is
    the estimator's seed; ``sensor`` is given to every feature set (and to
    the estimator when it takes one).
    """

    def __init__(self, spec: MethodSpec, random_state: int | None = None, sensor: SensorSpec | None = None):
        self.spec = spec
        self.random_state = random_state
        self.sensor = sensor

    def fit(self, captures: Sequence[np.ndarray], y: Any, groups: Any = None) -> "FeaturePipeline":
        y = np.asarray(y, dtype=object)
        self.sets_ = []
        for name, params in self.spec.feature_sets:
            fs = make_feature_set(name, dict(params), self.sensor)
            fs.fit(captures, y)
            self.sets_.append(fs)
        X = stack_features(self.sets_, captures)
        self.fitted_ = fit_estimator(self.spec.estimator, self.spec.estimator_params, self.random_state, X, y, groups,
                                     sensor=self.sensor)
        self.classes_ = self.fitted_.classes
        return self

    def transform(self, captures: Sequence[np.ndarray]) -> np.ndarray:
        return stack_features(self.sets_, captures)

    def predict(self, captures: Sequence[np.ndarray]) -> np.ndarray:
        return self.fitted_.predict(self.transform(captures))

    def predict_proba(self, captures: Sequence[np.ndarray]) -> dict[str, np.ndarray] | None:
        return self.fitted_.predict_proba(self.transform(captures))

    @classmethod
    def from_parts(cls, spec: MethodSpec, sets: list, fitted: FittedEstimator, random_state: int | None = None,
                   sensor: SensorSpec | None = None) -> "FeaturePipeline":
        """A fitted pipeline from already fitted feature sets and estimator (the engine's halves)."""
        out = cls(spec, random_state, sensor)
        out.sets_, out.fitted_, out.classes_ = list(sets), fitted, fitted.classes
        return out
