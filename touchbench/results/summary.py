"""Summaries of a scores table and the comparison with a protocol's ``expected`` numbers.

``mean`` aggregation averages a metric over the folds of a configuration
(what Gaus et al. report for 10-fold CV, "the average results of 10 fold
cross validation", Sec. 4.1, and Al-mashhadani et al. for LOSO, Table 2 with
its standard deviation over subjects). ``pooled`` computes the metric once
over every test prediction of the configuration.
"""

from __future__ import annotations

from typing import Any, Callable, Sequence

import numpy as np
import pandas as pd

from ..scoring.metrics import FIXED, metrics
from .store import PREDICTED, TRUE

__all__ = ["CONFIG_KEYS", "check_expected", "summarize"]

CONFIG_KEYS = ["features", "classifier", "early_frames"]
METRICS = list(FIXED)


def summarize(scores: pd.DataFrame, predictions: pd.DataFrame | None = None, by: list[str] | None = None,
              metrics: Sequence[str] = ()) -> pd.DataFrame:
    """One row per configuration: mean and standard deviation over folds of :data:`METRICS` and of
    ``metrics`` (a protocol's scorers), counts, pooled accuracy."""
    by = list(by or CONFIG_KEYS)
    names = list(dict.fromkeys([*METRICS, *(m for m in metrics if m in scores.columns)]))
    if scores.empty:
        return pd.DataFrame(columns=by + ["n_folds", "n_failed"])
    s = scores.copy()
    s["early_frames"] = s["early_frames"].fillna(-1) if "early_frames" in s else -1
    rows = []
    for key, g in s.groupby(by, sort=False, dropna=False):
        key = key if isinstance(key, tuple) else (key,)
        ok = g[g["status"] == "ok"]
        row: dict[str, Any] = dict(zip(by, key))
        row["n_folds"] = int(len(ok))
        row["n_failed"] = int((g["status"] == "failed").sum())
        for m in names:
            vals = ok[m].to_numpy(dtype=np.float64)
            row[f"{m}_mean"] = float(np.mean(vals)) if len(vals) else np.nan
            row[f"{m}_std"] = float(np.std(vals, ddof=1)) if len(vals) > 1 else np.nan
        row["n_test"] = int(ok["n_test"].sum())
        row["pooled_accuracy"] = (
            float((ok["accuracy"] * ok["n_test"]).sum() / ok["n_test"].sum()) if ok["n_test"].sum() else np.nan
        )
        row["latency_ms_median"] = float(ok["latency_ms"].median()) if len(ok) else np.nan
        rows.append(row)
    out = pd.DataFrame(rows)
    if "early_frames" in out:
        out["early_frames"] = out["early_frames"].astype("float64").where(out["early_frames"] >= 0)
    return out


def _pooled_metric(preds: pd.DataFrame, metric: str) -> float:
    """``metric`` (one of :data:`METRICS`) over the predictions of every fold at once."""
    if preds.empty:
        return np.nan
    return metrics(preds[TRUE].to_numpy(), preds[PREDICTED].to_numpy())[metric]


def check_expected(expected, scores: pd.DataFrame, predictions: pd.DataFrame | None = None,
                   features_label_of: Callable[[list[str]], str] | None = None) -> list[dict[str, Any]]:
    """Compare a protocol's ``expected`` block (values in percent) with the scores.

    An expected result names a feature combination as the protocol wrote it;
    ``features_label_of`` (the protocol's
    :meth:`touchbench.protocols.schema.Protocol.features_label_of`) gives the
    features label the results carry for its methods.

    One dict per expected result: ``observed`` (percent, ``None`` when the
    configuration has no successful fold), ``difference`` and ``within``
    (``|observed - expected| <= tolerance``).
    """
    if expected is None:
        return []
    out = []
    ok = scores[scores["status"] == "ok"] if not scores.empty else scores
    for r in expected.results:
        metric = r.metric or expected.metric
        tol = r.tolerance if r.tolerance is not None else expected.tolerance
        key = "+".join(r.features)
        named = features_label_of(list(r.features)) if features_label_of is not None else key
        keys = {key, named}
        sel = ok[ok["feature_sets"].isin(keys) | ok["features"].isin(keys)] if not ok.empty else ok
        if not sel.empty:
            by_label = sel[sel["classifier"] == r.classifier]
            sel = by_label if not by_label.empty else sel[sel["classifier_name"] == r.classifier]
        if r.group is not None and not sel.empty:
            sel = sel[sel["fold_group"] == r.group]
        observed = None if sel.empty else _observed(sel, predictions, metric, expected.aggregate)
        seeds = []  # one value per repetition (seed), where there are several
        if "repetition" in sel and sel["repetition"].nunique() > 1:
            seeds = [_observed(g, predictions, metric, expected.aggregate) for _, g in sel.groupby("repetition")]
        out.append({
            "features": named,  # as the results name the method's input
            "classifier": r.classifier,
            "group": r.group,
            "metric": metric,
            "aggregate": expected.aggregate,
            "expected": r.value,
            "observed": observed,
            "difference": None if observed is None else observed - r.value,
            "tolerance": tol,
            "within": None if observed is None else bool(abs(observed - r.value) <= tol),
            "n_folds": int(len(sel)),
            "seeds": seeds,
            "source": r.source or expected.source,
        })
    return out


def _observed(sel: pd.DataFrame, predictions: pd.DataFrame | None, metric: str, aggregate: str) -> float:
    """The metric of the tasks ``sel`` in percent: pooled over their predictions, or the mean of theirs."""
    if aggregate == "pooled" and predictions is not None:
        return 100.0 * _pooled_metric(predictions[predictions["task_id"].isin(sel["task_id"])], metric)
    return 100.0 * float(sel[metric].mean())
