"""A method as one scikit-learn-style estimator over captures.

:class:`FeaturePipeline` fits its method (:func:`touchbench.methods.fitting.fit_method`:
the feature sets, built with the sensor of the data, on the training
captures, then the estimator on their columns) into a
:class:`touchbench.classifiers.fitting.FittedMethod` (``method_``), the one
object that holds a fitted method: model files hold it too, and the run
engine fits the same two halves, taking fold-independent features from its
cache instead of recomputing them.
"""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np

from ..classifiers.adapt import uses_unlabelled_test
from ..core.errors import TouchbenchError
from ..datasets.model import SensorSpec
from .base import MethodSpec
from .fitting import FittedMethod, fit_method

__all__ = ["FeaturePipeline"]


class FeaturePipeline:
    """Feature sets -> estimator, fitted on captures.

    ``spec`` names the feature sets and the estimator; ``random_state`` is
    the estimator's seed; ``sensor`` is given to every feature set (and to
    the estimator when it takes one). ``memory`` (a folder or a
    :class:`joblib.Memory`), as scikit-learn's ``Pipeline(memory=...)``:
    what a feature set that learns nothing computes from the training
    captures is cached, so fitting again on the same captures (another
    estimator, another seed) reads it back. After ``fit``: ``method_`` (the
    fitted method), ``classes_``. An estimator that adapts to sessions
    (``touch-et-adapt``) is adapted to a new session's captures with
    :meth:`adapt` before :meth:`predict`.
    """

    def __init__(self, spec: MethodSpec, random_state: int | None = None, sensor: SensorSpec | None = None,
                 memory: Any = None):
        self.spec = spec
        self.random_state = random_state
        self.sensor = sensor
        self.memory = memory

    def fit(self, captures: Sequence[np.ndarray], y: Any, groups: Any = None) -> "FeaturePipeline":
        self.method_ = fit_method(self.spec, self.random_state, captures, y, groups, self.sensor, self.memory)
        self.classes_ = self.method_.classes
        return self

    @property
    def sets_(self) -> list:
        """The fitted feature sets."""
        return self.method_.sets

    @property
    def fitted_(self):
        """The fitted estimator with the labels its codes stand for."""
        return self.method_.fitted

    def transform(self, captures: Sequence[np.ndarray]) -> np.ndarray | list[np.ndarray]:
        return self.method_.transform(captures)

    def adapt(self, captures: Sequence[np.ndarray]) -> "FeaturePipeline":
        """Adapt an estimator that adapts to sessions (``session-centred``) to one new session's
        captures, unlabelled, before :meth:`predict` labels them; refused for any other estimator."""
        est = self.method_.estimator
        if not uses_unlabelled_test(self.spec.estimator):
            raise TouchbenchError(f"{self.spec.estimator!r} does not adapt to sessions: predict without adapt")
        if est is not None:  # a training set of one class has no estimator to adapt
            est.adapt(self.method_.transform(captures))
        return self

    def predict(self, captures: Sequence[np.ndarray]) -> np.ndarray:
        return self.method_.predict(captures)

    def predict_proba(self, captures: Sequence[np.ndarray]) -> dict[str, np.ndarray] | None:
        return self.method_.predict_proba(captures)

    @classmethod
    def of(cls, spec: MethodSpec, method: FittedMethod, random_state: int | None = None,
           sensor: SensorSpec | None = None) -> "FeaturePipeline":
        """A fitted pipeline around an already fitted method (the engine's halves)."""
        out = cls(spec, random_state, sensor)
        out.method_, out.classes_ = method, method.classes
        return out
