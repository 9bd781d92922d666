"""The fit path of a method's estimator: labels as text, subjects as text.

:func:`fit_estimator` is :func:`touchbench.classifiers.fitting.fit_on_codes`
(label codes, subjects as ``groups``, one-class folds) with every label and
subject read as a string, so the codes are those of the sorted class names
whatever type the metadata column has. The engine's tasks and
``touchbench train`` fit through it; :func:`fit_method` fits a whole method
(its feature sets, then its estimator) into a :class:`FittedMethod`.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..classifiers.fitting import FittedEstimator, FittedMethod, fit_on_codes, fit_pipeline, label_codes
from .base import MethodSpec

__all__ = ["FittedEstimator", "FittedMethod", "encode_labels", "fit_estimator", "fit_method"]


def _as_text(values: Any) -> np.ndarray:
    return np.array([str(v) for v in np.asarray(values, dtype=object).tolist()], dtype=object)


def encode_labels(y: Any) -> tuple[np.ndarray, np.ndarray]:
    """``(classes, codes)``: the sorted distinct labels (as str) and each row's index into them."""
    return label_codes(_as_text(y))


def fit_estimator(name: str, params: dict[str, Any], seed: int | None, X: np.ndarray, y: Any,
                  groups: Any = None, test_set: tuple[Any, Any] | None = None, **build: Any) -> FittedEstimator:
    """Build the registered estimator ``name`` (``random_state=seed``, ``params``,
    and ``build`` keywords such as the sensor) and fit it on ``X``, ``y`` (labels as text; the
    subjects ``groups`` as text to an estimator that takes them; ``test_set``, the test rows and
    labels of a method stopped on test, labels as text)."""
    test = None if test_set is None else (test_set[0], _as_text(test_set[1]))
    return fit_on_codes(name, params, seed, X, _as_text(y), None if groups is None else _as_text(groups),
                        test_set=test, **build)


def fit_method(spec: MethodSpec, seed: int | None, captures: Any, y: Any, groups: Any = None,
               sensor: Any = None, memory: Any = None) -> FittedMethod:
    """Fit the method ``spec`` on ``captures`` (labels and subjects as text), its feature sets built
    with ``sensor``; ``memory`` caches the feature sets that learn nothing
    (:func:`touchbench.classifiers.fitting.fit_pipeline`)."""
    return fit_pipeline(spec.feature_sets, spec.estimator, spec.estimator_params, seed, captures, _as_text(y),
                        None if groups is None else _as_text(groups), sensor, memory)
