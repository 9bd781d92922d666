"""The scores of one set of predictions: accuracy, balanced accuracy, macro F1."""

from __future__ import annotations

import warnings

import numpy as np
from sklearn.metrics import balanced_accuracy_score, f1_score

__all__ = ["metrics"]


def metrics(y_true: np.ndarray, y_pred: np.ndarray) -> dict[str, float]:
    """Accuracy, balanced accuracy (mean recall over the true classes) and macro F1.

    Macro F1 averages over the classes present in truth or prediction
    (a class neither present nor predicted has no F1). Computed with
    scikit-learn; its warnings for absent classes are silenced (the fold's
    notes describe them).
    """
    yt = np.asarray(y_true).astype(str)
    yp = np.asarray(y_pred).astype(str)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return {
            "accuracy": float(np.mean(yt == yp)),
            "balanced_accuracy": float(balanced_accuracy_score(yt, yp)),
            "macro_f1": float(f1_score(yt, yp, average="macro", labels=sorted(set(yt) | set(yp)), zero_division=0)),
        }
