"""The scores of one set of predictions: the three every task has (accuracy, balanced accuracy,
macro F1: scikit-learn's values, computed from one confusion matrix) and any scikit-learn scorer a
protocol names (``metrics:``, through the scorer itself)."""

from __future__ import annotations

import warnings

import numpy as np

__all__ = ["FIXED", "metrics", "scorer_values"]

#: the three scores of every task (columns of ``scores.parquet``) and the scikit-learn scorer of each
FIXED = {"accuracy": "accuracy", "balanced_accuracy": "balanced_accuracy", "macro_f1": "f1_macro"}


def metrics(y_true: np.ndarray, y_pred: np.ndarray) -> dict[str, float]:
    """Accuracy, balanced accuracy (mean recall over the true classes) and macro F1.

    Macro F1 averages over the classes present in truth or prediction
    (a class neither present nor predicted has no F1, one never predicted
    has F1 0). The values of the scikit-learn scorers of :data:`FIXED`
    (``accuracy_score``, ``balanced_accuracy_score``, ``f1_score(average="macro")``),
    computed from one confusion matrix with their arithmetic, in their order, so
    the floats are theirs to the last bit (scikit-learn's input checks cost more
    than the scores); empty predictions go through :func:`scorer_values`.
    """
    yt = np.asarray(y_true).astype(str)
    yp = np.asarray(y_pred).astype(str)
    if yt.shape != yp.shape or yt.ndim != 1 or not len(yt):
        values = scorer_values(list(FIXED.values()), yt, yp)
        return {column: values[name] for column, name in FIXED.items()}
    classes, codes = np.unique(np.concatenate([yt, yp]), return_inverse=True)
    k = len(classes)
    cm = np.bincount(codes[:len(yt)] * k + codes[len(yt):], minlength=k * k).reshape(k, k)
    tp, true_sum, pred_sum = np.diag(cm), cm.sum(axis=1), cm.sum(axis=0)
    with np.errstate(divide="ignore", invalid="ignore"):
        recall = tp / true_sum
    f1 = (2.0 * tp.astype(np.float64)) / (1.0 * true_sum.astype(np.float64) + pred_sum.astype(np.float64))
    return {"accuracy": float(np.average(yt == yp)),
            "balanced_accuracy": float(np.mean(recall[~np.isnan(recall)])),
            "macro_f1": float(np.nanmean(f1))}


def scorer_values(names: tuple[str, ...] | list[str], y_true: np.ndarray, y_pred: np.ndarray,
                  proba: dict[str, np.ndarray] | None = None,
                  problems: dict[str, str] | None = None) -> dict[str, float]:
    """Each scikit-learn scorer of ``names`` (``sklearn.metrics.get_scorer``) from the predictions:
    its metric function with the scorer's own arguments and sign (so ``neg_log_loss`` is negative,
    greater is better, as in scikit-learn). Scorers on probabilities or decision values take the
    class probabilities (``proba``: class -> column; the positive class's column for a binary
    problem) and are NaN for a classifier without them; classes the training fold lacked have
    probability 0. A scorer that cannot be computed here (no probabilities, a binary scorer on
    several classes, a class in the truth only...) is NaN, and ``problems`` (when given) gets the
    reason under its name."""
    from sklearn.metrics import get_scorer

    yt = np.asarray(y_true).astype(str)
    yp = np.asarray(y_pred).astype(str)
    out: dict[str, float] = {}
    for name in names:
        scorer = get_scorer(name)
        func, sign, kwargs = scorer._score_func, scorer._sign, dict(scorer._kwargs)
        method = scorer._response_method
        methods = (method,) if isinstance(method, str) else tuple(method)
        value = np.nan
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            try:
                if "predict" in methods:
                    value = func(yt, yp, **kwargs)
                elif proba is None:
                    if problems is not None:
                        problems[name] = "it needs class probabilities and the classifier gives none"
                else:
                    classes = sorted(set(yt) | set(proba))
                    P = np.column_stack([np.asarray(proba.get(c, np.zeros(len(yt))), dtype=np.float64)
                                         for c in classes])
                    score = P[:, 1] if len(classes) == 2 else P
                    try:
                        value = func(yt, score, labels=classes, **kwargs)
                    except TypeError:  # a metric without a labels argument
                        value = func(yt, score, **kwargs)
            except (ValueError, TypeError) as e:  # undefined on these labels (e.g. a regression scorer)
                if problems is not None:
                    problems[name] = f"{type(e).__name__}: {e}".split("\n")[0]
        value = float(value)
        out[name] = sign * value if np.isfinite(value) else np.nan
    return out
