"""Comparing two methods of one table: :func:`compare_methods` (the paired test, per-fold and
per-class differences) and :func:`resolve_method` (the method a name or id prefix names)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import pandas as pd
from sklearn.metrics import precision_recall_fscore_support

from ..core.errors import TouchbenchError
from ..results.store import PREDICTED, TRUE
from .leaderboard import Leaderboard
from .paired import _compare
from .results import ResultSet
from .stats import PairedTest

__all__ = ["Comparison", "compare_methods", "resolve_method"]


def resolve_method(lb_rows: pd.DataFrame, spec: str) -> str:
    """The method id ``spec`` names: an id (or its prefix of at least 4 characters),
    ``features/classifier`` or a classifier label -- a label only when it names one method."""
    ids = lb_rows["method_id"].astype(str)
    hit = lb_rows[ids.str.startswith(spec)] if len(spec) >= 4 else lb_rows.iloc[0:0]
    if len(hit) == 1:
        return str(hit["method_id"].iloc[0])
    labels = lb_rows["features"].astype(str) + "/" + lb_rows["classifier"].astype(str)
    early = lb_rows["early_frames"].notna()
    labels = labels.where(~early, labels + "@" + lb_rows["early_frames"].fillna(0).astype(int).astype(str) + "f")
    by_label = lb_rows[(labels == spec) | (lb_rows["classifier"].astype(str) == spec)]
    if len(by_label) == 1:
        return str(by_label["method_id"].iloc[0])
    cand = by_label if len(by_label) else hit
    if len(cand) > 1:
        lines = [f"  {r.method_id}  {r.features}/{r.classifier}  {r.classifier_params}" for r in cand.itertuples()]
        raise TouchbenchError(f"{spec!r} names {len(cand)} methods; give the method id:\n" + "\n".join(lines))
    known = [f"  {r.method_id}  {lab}" for r, lab in zip(lb_rows.itertuples(), labels)]
    raise TouchbenchError(f"no method {spec!r} in this table; methods:\n" + "\n".join(known))


@dataclass
class Comparison:
    leaderboard: Leaderboard
    a: dict[str, Any]
    b: dict[str, Any]
    test: PairedTest
    pairs: pd.DataFrame
    per_class: pd.DataFrame


def _per_class(preds: pd.DataFrame | None, a: str, b: str, fold_keys: list[str]) -> pd.DataFrame:

    cols = ["class", "support", "recall_a", "recall_b", "recall_diff", "f1_a", "f1_b", "f1_diff"]
    if preds is None or preds.empty:
        return pd.DataFrame(columns=cols)
    out = {}
    for tag, mid in (("a", a), ("b", b)):
        p = preds[(preds["method_id"] == mid) & preds["fold_key"].isin(set(fold_keys))]
        p = p.sort_values("finished_at", kind="stable").drop_duplicates(["fold_key", "seed", "capture_id"], keep="last")
        out[tag] = p
    classes = sorted(set(out["a"][TRUE].astype(str)) | set(out["b"][TRUE].astype(str)))
    if not classes:
        return pd.DataFrame(columns=cols)
    res = {}
    for tag, p in out.items():
        _, r, f1, sup = precision_recall_fscore_support(p[TRUE].astype(str), p[PREDICTED].astype(str),
                                                        labels=classes, zero_division=0)
        res[tag] = (r, f1, sup)
    df = pd.DataFrame({"class": classes, "support": res["a"][2], "recall_a": res["a"][0], "recall_b": res["b"][0],
                       "f1_a": res["a"][1], "f1_b": res["b"][1]})
    df["recall_diff"] = df["recall_a"] - df["recall_b"]
    df["f1_diff"] = df["f1_a"] - df["f1_b"]
    return df[cols]


def compare_methods(rs: ResultSet, lb: Leaderboard, a: str, b: str) -> Comparison:
    """The paired test of ``a`` against ``b``, per-fold and per-class differences."""
    ida, idb = resolve_method(lb.rows, a), resolve_method(lb.rows, b)
    if ida == idb:
        raise TouchbenchError(f"{a!r} and {b!r} are the same method ({ida})")
    preds = rs.predictions[rs.predictions["table_key"] == lb.key] if rs.predictions is not None else None
    test, pairs = _compare(lb.folds, preds, ida, idb)
    pairs = pairs.assign(diff=pairs["a"] - pairs["b"])
    fa = set(lb.folds[lb.folds["method_id"] == ida]["fold_key"])
    fb = set(lb.folds[lb.folds["method_id"] == idb]["fold_key"])
    per_class = _per_class(preds, ida, idb, sorted(fa & fb))
    ra = lb.rows[lb.rows["method_id"] == ida].iloc[0].to_dict()
    rb = lb.rows[lb.rows["method_id"] == idb].iloc[0].to_dict()
    return Comparison(lb, ra, rb, test, pairs, per_class)
