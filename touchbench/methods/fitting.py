"""The fit path of a method's estimator: labels as text, subjects as text.

:func:`fit_estimator` is :func:`touchbench.classifiers.fitting.fit_on_codes`
(label codes, subjects as ``groups``, one-class folds) with every label and
subject read as a string, so the codes are those of the sorted class names
whatever type the metadata column has. The engine's tasks and
``touchbench train`` fit through it.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..classifiers.fitting import FittedEstimator, fit_on_codes, label_codes

__all__ = ["FittedEstimator", "encode_labels", "fit_estimator"]


def _as_text(values: Any) -> np.ndarray:
    return np.array([str(v) for v in np.asarray(values, dtype=object).tolist()], dtype=object)


def encode_labels(y: Any) -> tuple[np.ndarray, np.ndarray]:
    """``(classes, codes)``: the sorted distinct labels (as str) and each row's index into them."""
    return label_codes(_as_text(y))


def fit_estimator(name: str, params: dict[str, Any], seed: int | None, X: np.ndarray, y: Any,
                  groups: Any = None, **build: Any) -> FittedEstimator:
    """Build the registered estimator ``name`` (``random_state=seed``, ``params``,
    and ``build`` keywords such as the sensor) and fit it on ``X``, ``y`` (labels as text; the
    subjects ``groups`` as text to an estimator that takes them)."""
    return fit_on_codes(name, params, seed, X, _as_text(y), None if groups is None else _as_text(groups), **build)
