"""The scores of one set of predictions: accuracy, balanced accuracy, macro F1, and any
scikit-learn scorer a protocol names (``metrics:``)."""

from __future__ import annotations

import warnings

import numpy as np
from sklearn.metrics import balanced_accuracy_score, f1_score

__all__ = ["metrics", "scorer_values"]


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


def scorer_values(names: tuple[str, ...] | list[str], y_true: np.ndarray, y_pred: np.ndarray,
                  proba: dict[str, np.ndarray] | None = None) -> dict[str, float]:
    """Each scikit-learn scorer of ``names`` (``sklearn.metrics.get_scorer``) from the predictions:
    its metric function with the scorer's own arguments and sign (so ``neg_log_loss`` is negative,
    greater is better, as in scikit-learn). Scorers on probabilities or decision values take the
    class probabilities (``proba``: class -> column; the positive class's column for a binary
    problem) and are NaN for a classifier without them; classes the training fold lacked have
    probability 0."""
    from sklearn.metrics import get_scorer

    yt = np.asarray(y_true).astype(str)
    yp = np.asarray(y_pred).astype(str)
    out: dict[str, float] = {}
    for name in names:
        scorer = get_scorer(name)
        func, sign, kwargs = scorer._score_func, scorer._sign, dict(scorer._kwargs)
        method = scorer._response_method
        methods = (method,) if isinstance(method, str) else tuple(method)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            try:
                if "predict" in methods:
                    value = func(yt, yp, **kwargs)
                elif proba is None:
                    value = np.nan
                else:
                    classes = sorted(set(yt) | set(proba))
                    P = np.column_stack([np.asarray(proba.get(c, np.zeros(len(yt))), dtype=np.float64)
                                         for c in classes])
                    score = P[:, 1] if len(classes) == 2 else P
                    try:
                        value = func(yt, score, labels=classes, **kwargs)
                    except TypeError:  # a metric without a labels argument
                        value = func(yt, score, **kwargs)
            except ValueError:  # e.g. a class present in truth only: the metric is undefined here
                value = np.nan
        out[name] = float(sign * value) if np.isfinite(value) else np.nan
    return out
