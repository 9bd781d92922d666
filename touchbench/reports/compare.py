"""Comparing two methods of one table: :func:`compare_methods` (the paired test, per-fold and
per-class differences), :func:`resolve_method` (the method a name or id prefix names), and what
``compare`` says of its test (:func:`test_lines`): which test and correction each p comes from,
the interval that inverts the test, and why the leaderboard's p of the pair differs
(:func:`leaderboard_p`: Holm over the comparisons with the best)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import pandas as pd
from sklearn.metrics import precision_recall_fscore_support

from ..core.errors import TouchbenchError
from ..results.store import PREDICTED, TRUE
from .labels import method_label
from .leaderboard import Leaderboard
from .seeds import PIGEONHOLE, compare_pair
from .results import ResultSet
from .stats import TEST_NAMES, PairedTest

__all__ = ["Comparison", "compare_methods", "leaderboard_p", "resolve_method", "test_lines"]

#: How each of the test's intervals is made, as ``compare`` says it.
TEST_CI = {"exact-conditional": "exact, given the discordant captures: Clopper-Pearson's interval of the share of "
                                "them A gets right, which inverts the test",
           "corrected-t": "corrected t, which inverts the test",
           PIGEONHOLE: "pigeonhole bootstrap over the test captures and the seeds (Owen 2007), the resamples "
                       "the test's p counts"}


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
    test, pairs = compare_pair(lb.folds, preds, ida, idb)
    pairs = pairs.assign(diff=pairs["a"] - pairs["b"])
    fa = set(lb.folds[lb.folds["method_id"] == ida]["fold_key"])
    fb = set(lb.folds[lb.folds["method_id"] == idb]["fold_key"])
    per_class = _per_class(preds, ida, idb, sorted(fa & fb))
    ra = lb.rows[lb.rows["method_id"] == ida].iloc[0].to_dict()
    rb = lb.rows[lb.rows["method_id"] == idb].iloc[0].to_dict()
    return Comparison(lb, ra, rb, test, pairs, per_class)


def _pts(v: float) -> str:
    return f"{100 * v:+.2f}"


def test_lines(t: PairedTest) -> list[str]:
    """What ``compare`` says of a test: the difference; the test, its two-sided p and that it is this
    comparison's alone (no multiple-comparison correction); the 95 % interval that inverts the test
    (it excludes 0 exactly when p < 0.05); the bootstrap over subjects where subjects are the unit,
    said to be a description, not the test's interval."""
    if t.test == "none":
        return [f"paired test: not possible ({t.n} shared {t.paired_by or 'fold'}s)"]
    out = [f"paired by {t.paired_by} (n={t.n}): mean difference A-B {_pts(t.mean_difference)} points"]
    df = f"{t.n - 1} df; " if t.test == "corrected-t" else ""
    if not math.isfinite(t.pvalue):
        out.append(f"{TEST_NAMES[t.test]}: no p-value ({t.note}: A-B {_pts(t.mean_difference)} points in every fold)")
    else:
        out.append(f"{TEST_NAMES[t.test]}, two-sided p = {t.pvalue:.4g} ({df}this comparison alone, "
                   "no multiple-comparison correction)")
    if math.isfinite(t.test_ci_low):
        out.append(f"95 % interval of A-B {_pts(t.test_ci_low)} to {_pts(t.test_ci_high)} points "
                   f"({TEST_CI[t.test_ci_method]}: it excludes 0 exactly when p < 0.05)")
    elif t.test == "mcnemar-exact":
        out.append("no interval: no discordant capture (each capture right for both methods or wrong for both)")
    if t.ci_method == "subject-bootstrap":
        out.append(f"between subjects: A-B {_pts(t.ci_low)} to {_pts(t.ci_high)} points, 95 % bootstrap over "
                   f"{t.n_subjects} subjects (resampling people, not {t.paired_by}s: how the difference varies "
                   "between people, not the test's interval, so it need not agree with p)")
    return out


def leaderboard_p(c: Comparison) -> dict[str, Any]:
    """Where the leaderboard's p of the pair comes from: the leaderboard tests each method against its
    best (``best``) only, with the same test, and Holm-adjusts over the table's ``comparisons``
    (the p-values it has). ``p_value`` / ``p_holm``: its unadjusted and adjusted p for the pair when
    one of them is the best (NaN otherwise: ``tested`` False); ``text``: this said in one line."""
    rows = c.leaderboard.rows
    best = rows.iloc[0]
    k = int(rows["p_value"].notna().sum())
    ids = (c.a["method_id"], c.b["method_id"])
    out = {"best": str(best["method_id"]), "correction": "holm", "comparisons": k, "tested": best["method_id"] in ids,
           "p_value": math.nan, "p_holm": math.nan}
    family = (f"Holm-adjusted over the table's {k} comparisons with the best" if k > 1 else
              "the table's only comparison with the best, which Holm leaves as it is")
    if not out["tested"]:
        out["text"] = (f"the leaderboard tests each method against the best ({method_label(best.to_dict())}) only, "
                       f"{family}: it has no p for A against B")
        return out
    other, tag = (c.b, "B") if ids[0] == best["method_id"] else (c.a, "A")
    row = rows[rows["method_id"] == other["method_id"]].iloc[0]
    out.update(p_value=float(row["p_value"]), p_holm=float(row["p_holm"]))
    if not math.isfinite(out["p_holm"]):
        out["text"] = f"the leaderboard has no p for {tag} against the best either"
        return out
    out["text"] = (f"the leaderboard's p for {tag} against the best is {out['p_holm']:.4g}: the same test "
                   f"(p = {out['p_value']:.4g}), {family}")
    return out
