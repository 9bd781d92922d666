"""Paired results of two methods of one table and the test that fits them: by fold (the corrected
resampled t-test) or by test capture of one test set (McNemar's exact test), with the interval of the
difference (by bootstrap over subjects where subjects are the unit); per-subject accuracy."""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Iterable

import numpy as np
import pandas as pd

from .stats import PairedTest, corrected_resampled_t, mcnemar_exact, no_test, subject_bootstrap

__all__ = ["paired_captures", "paired_test", "subject_values"]


def subject_values(predictions: pd.DataFrame | None, method: str, fold_keys: Iterable[str] | None = None) -> pd.Series:
    """Per-subject accuracy of ``method`` from its predictions (over ``fold_keys``)."""
    if predictions is None or predictions.empty:
        return pd.Series(dtype=np.float64)
    p = predictions[predictions["method_id"] == method]
    if fold_keys is not None:
        p = p[p["fold_key"].isin(set(fold_keys))]
    if p.empty:
        return pd.Series(dtype=np.float64)
    return _latest(p).groupby("subject")["correct"].mean().astype(np.float64)


def _latest(p: pd.DataFrame) -> pd.DataFrame:
    """One prediction per fold, seed and capture: the last written (a rerun's replaces the earlier)."""
    return p.sort_values("finished_at", kind="stable").drop_duplicates(["fold_key", "seed", "capture_id"], keep="last")


def paired_captures(preds: pd.DataFrame | None, a: str, b: str, fold_keys: Iterable[str]) -> pd.DataFrame:
    """The test captures both ``a`` and ``b`` predicted in ``fold_keys``: columns ``fold_key``,
    ``capture_id``, ``subject``, ``a``, ``b`` (each method's correctness, the mean over its seeds)."""
    cols = ["fold_key", "capture_id", "subject", "a", "b"]
    if preds is None or preds.empty:
        return pd.DataFrame(columns=cols)
    keys = ["fold_key", "capture_id", "subject"]
    sides = []
    for mid in (a, b):
        p = preds[(preds["method_id"] == mid) & preds["fold_key"].isin(set(fold_keys))]
        sides.append(_latest(p).astype({"correct": np.float64}).groupby(keys, observed=True)["correct"].mean())
    both = pd.concat(sides, axis=1, keys=["a", "b"], join="inner").reset_index()
    return both[cols]


def _pair(folds: pd.DataFrame, preds: pd.DataFrame | None, a: str, b: str) -> tuple[str, pd.DataFrame]:
    """Paired results of methods ``a`` and ``b``: by fold when they share two or more folds (columns
    ``unit``, ``a``, ``b`` the fold accuracies, ``n_test``, ``n_train``), else by test capture of
    their one shared fold (``unit`` the capture, ``a``, ``b`` its correctness, ``subject``).

    Returns ``(paired_by, frame)``: ``"fold"``, ``"capture"`` or ``""`` (nothing shared).
    """
    fa = folds[folds["method_id"] == a].set_index("fold_key")
    fb = folds[folds["method_id"] == b].set_index("fold_key")
    common = fa.index.intersection(fb.index)
    if len(common) >= 2:
        return "fold", pd.DataFrame({"unit": [str(fa.loc[k, "fold"]) for k in common],
                                     "a": fa.loc[common, "accuracy"].to_numpy(np.float64),
                                     "b": fb.loc[common, "accuracy"].to_numpy(np.float64),
                                     "n_test": fa.loc[common, "n_test"].to_numpy(np.float64),
                                     "n_train": fa.loc[common, "n_train"].to_numpy(np.float64)})
    caps = paired_captures(preds, a, b, common)
    if len(caps):
        return "capture", caps.rename(columns={"capture_id": "unit"})[["unit", "a", "b", "subject", "fold_key"]]
    return "", pd.DataFrame({"unit": [], "a": [], "b": []})


def _subjects_are_units(caps: pd.DataFrame, by: str) -> bool:
    """Whether subjects are the unit of the design: one test set (its captures clustered in its
    subjects), or folds that each test a single subject (leave-one-subject-out)."""
    if caps.empty:
        return False
    return by == "capture" or bool((caps.groupby("fold_key")["subject"].nunique() == 1).all())


def paired_test(by: str, pairs: pd.DataFrame, caps: pd.DataFrame) -> PairedTest:
    """The test that fits the pairing (:mod:`touchbench.reports.stats`: McNemar's exact test on the
    captures of one test set, the corrected resampled t-test over folds), with the interval of the
    difference: by bootstrap over subjects where subjects are the unit (``caps``: the paired
    captures, :func:`paired_captures`), else the test's own (kept in ``test_ci_*`` in either case)."""
    if by == "fold":
        ratio = float(np.mean(pairs["n_test"] / pairs["n_train"])) if (pairs["n_train"] > 0).all() else math.nan
        test = corrected_resampled_t(pairs["a"] - pairs["b"], ratio)
    elif by == "capture":
        test = mcnemar_exact(pairs["a"] >= 0.5, pairs["b"] >= 0.5)
    else:
        return no_test("", [])
    n_subjects = int(caps["subject"].nunique()) if len(caps) else 0
    if test.test != "none" and n_subjects >= 2 and _subjects_are_units(caps, by):
        per = caps.groupby("subject", observed=True).agg(a=("a", "sum"), b=("b", "sum"), n=("a", "size"))
        lo, hi = subject_bootstrap(per["a"], per["b"], per["n"])
        return replace(test, ci_low=lo, ci_high=hi, ci_method="subject-bootstrap", n_subjects=n_subjects)
    return replace(test, n_subjects=n_subjects)


def _compare(folds: pd.DataFrame, preds: pd.DataFrame | None, a: str, b: str) -> tuple[PairedTest, pd.DataFrame]:
    """The paired test of ``a`` against ``b`` and the pairs it was computed on."""
    by, pairs = _pair(folds, preds, a, b)
    shared = set(folds[folds["method_id"] == a]["fold_key"]) & set(folds[folds["method_id"] == b]["fold_key"])
    caps = pairs if by == "capture" else paired_captures(preds, a, b, shared)
    return paired_test(by, pairs, caps), pairs
