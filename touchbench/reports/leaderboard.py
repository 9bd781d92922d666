"""Leaderboards: one table per dataset, target and scheme; and pairwise comparison.

Each row is a method (a parameter hash, see :mod:`touchbench.reports.results`):
rank by mean accuracy over folds, the spread and 95 % interval, macro F1,
balanced accuracy, the median latency per capture (features + predict of one
capture, ms), the median fit time (s per fold) and feature extraction time
(ms per capture), the paired test against the best method (Holm-adjusted
within the table; statistics in :mod:`touchbench.reports.stats`) and whether
the method is on the accuracy / latency Pareto front.

Timings and machines: accuracy does not depend on the machine and is pooled
over every run of a method. Timings do, so a table uses one *reference
machine* (the one that measured the most of its methods; ``machine=`` picks
another): a method measured there shows that machine's timings, a method
measured only elsewhere shows its own machine's, flagged in the
``timing_machine`` column, and the Pareto front is computed separately for
each machine. ``pool_machines=True`` pools every machine's timings into one
front (asked for explicitly, and said so in the table notes).

Across tables (several datasets or schemes): :func:`mean_ranks` ranks the
methods present in every table within each table (by mean accuracy, ties
averaged) and averages the ranks, as MOABB and aeon rank pipelines across
datasets; :func:`across_tables` gives the accuracies the critical difference
diagram across tables uses, :func:`across_friedman` the Friedman test and
Nemenyi critical difference over the tables (each table one data set, never
its folds; :mod:`touchbench.reports.stats`). Titles carry the dataset, scheme and target
(two tables of different data with one name are told apart as ``data 2``,
``data 3``...); failed methods are shown as failed with their error; rows
that would read the same show their feature (then classifier) parameters.

Methods adapted to the test data (the results' ``adaptation``: a method
that re-centres each test subject by that subject's unlabelled captures)
are a figure of another kind: they get a table of their own (their rows'
``table_key`` carries the adaptation, :mod:`touchbench.reports.results`),
titled and explained as such, ranked, tested and put on a Pareto front
among themselves only, and left out of every comparison across tables.
"""

from __future__ import annotations

import json
import math
import os
import sys
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Iterable

import numpy as np
import pandas as pd
from rich.cells import cell_len
from rich.console import Console
from rich.markup import escape
from rich.table import Table
from scipy.stats import rankdata
from sklearn.metrics import precision_recall_fscore_support

from ..core.atomic import atomic_write_bytes
from ..core.errors import TouchbenchError
from ..methods.base import METHODS
from ..results.ledger import Looks
from ..results.store import NOT_RECORDED, PREDICTED, TRUE
from .pareto import pareto_cost, pareto_front
from .results import ResultSet, load_results, scheme_label
from .stats import (
    TEST_SHORT,
    Friedman,
    PairedTest,
    corrected_resampled_t,
    fold_interval,
    friedman,
    holm,
    mcnemar_exact,
    no_test,
    subject_bootstrap,
    wilson_interval,
)

__all__ = [
    "Leaderboard",
    "across_friedman",
    "across_note",
    "across_tables",
    "build_leaderboards",
    "compare_methods",
    "fold_values",
    "leaderboard",
    "mean_ranks",
    "method_label",
    "method_labels",
    "owns_input",
    "plain_tables",
    "ranks_across",
    "resolve_method",
    "subject_values",
    "to_csv",
    "to_json",
    "to_markdown",
]

METRICS = ["accuracy", "balanced_accuracy", "macro_f1"]


@dataclass
class Leaderboard:
    """One table: the methods evaluated on one dataset (content hash), target and scheme."""

    key: str
    dataset: str
    dataset_hash: str
    target: str
    scheme: str
    rows: pd.DataFrame
    folds: pd.DataFrame
    machines: dict[str, str]
    reference_machine: str | None
    pooled_machines: bool
    alpha: float
    frame_rate: float
    notes: list[str] = field(default_factory=list)
    #: tells apart tables of different data under one dataset name ("data 2"); empty when unique
    variant: str = ""
    #: how often the table's test set was scored (from the ledger), None when no ledger names it
    looks: Looks | None = None
    #: the table declares design data: rows carry ``held_out_accuracy`` and ``designed``
    has_design: bool = False
    #: how the title names the evaluation (:func:`table_heading`); ``scheme`` when empty
    heading: str = ""
    #: what the table's methods adapted to at test time ("" for the plain methods' table)
    adaptation: str = ""

    @property
    def title(self) -> str:
        t = f"{self.dataset}" + (f" ({self.variant})" if self.variant else "") + f" — {self.heading or self.scheme}"
        t = t if self.target == "gesture" else f"{t} — target {self.target}"
        t += " — adapted to each test session" if self.adaptation else ""
        return t + (" — LEAKY evaluation" if self.is_leaky else "")

    @property
    def is_leaky(self) -> bool:
        """Every method of the table was evaluated with a leak (a leaky scheme)."""
        return bool(len(self.rows)) and bool((self.rows["leakage"] != "").all())

    @property
    def is_early(self) -> bool:
        return self.rows["early_frames"].notna().any()


def _mode(s: pd.Series) -> str:
    v = s.astype(str).value_counts()
    return str(v.index[0]) if len(v) else ""


def _first_error(g: pd.DataFrame) -> str:
    """The first line of the first failed task's error ("" when none failed)."""
    failed = g[g["status"] != "ok"]
    if failed.empty or "error" not in failed:
        return ""
    return str(failed["error"].iloc[0]).strip().splitlines()[0] if str(failed["error"].iloc[0]).strip() else "failed"


def fold_values(ok: pd.DataFrame) -> pd.DataFrame:
    """Per method and fold: metrics averaged over duplicate seeds (replicates of a fold)."""
    agg = {m: "mean" for m in METRICS}
    agg.update(n_test="first", n_train="first", fold="first", fold_group="first")
    ok = ok if "n_train" in ok else ok.assign(n_train=np.nan)  # results that did not record it: no t-test
    out = ok.groupby(["table_key", "method_id", "fold_key"], sort=False).agg(agg).reset_index()
    return out


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
    captures, :func:`paired_captures`), else the corrected t interval."""
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


def _held_out(preds: pd.DataFrame | None, mid: str, design: set[str]) -> tuple[float, int, bool]:
    """Mean over folds of ``mid``'s accuracy on the test captures outside the design data (folds
    without such a capture left out), how many such captures were tested, and whether any
    design capture was tested (else the usual figure is already a held-out one)."""
    if preds is None or preds.empty:
        return math.nan, 0, False
    mine = preds[preds["method_id"] == mid]
    inside = mine["capture_id"].astype(str).isin(design)
    p = mine[~inside]
    if p.empty:
        return math.nan, 0, bool(inside.any())
    p = _latest(p)
    per_fold = p.groupby(["fold_key", "seed"])["correct"].mean().groupby(level=0).mean()
    return float(per_fold.mean()), int(p["capture_id"].nunique()), bool(inside.any())


def _tuned_on_test(df: pd.DataFrame) -> pd.DataFrame:
    """Entries whose grid is chosen on test accuracy (``selection``): only the best of each grid
    is kept, its label the entry's, what was chosen in its parameters."""
    if "selection" not in df or not (df["selection"] != "").any():
        return df
    keep = []
    for sel, g in df.groupby("selection", sort=False):
        if sel == "":
            keep += list(g.index)
            continue
        best = g.sort_values(["accuracy", "method_id"], ascending=[False, True], na_position="last").index[0]
        df.loc[best, "classifier"] = f"{sel}: {df.loc[best, 'classifier']}"
        keep.append(best)
    return df.loc[sorted(keep)].reset_index(drop=True)


def _timings(s: pd.DataFrame) -> dict[str, float]:
    return {
        "latency_ms": float(s["latency_ms"].median()) if s["latency_ms"].notna().any() else math.nan,
        "latency_cpu_ms": float(s["latency_cpu_ms"].median()) if s["latency_cpu_ms"].notna().any() else math.nan,
        "fit_seconds": float(s["fit_seconds"].median()) if s["fit_seconds"].notna().any() else math.nan,
        "feature_ms": 1000.0 * float(s["feature_seconds_per_capture"].median())
        if s["feature_seconds_per_capture"].notna().any() else math.nan,
    }


def _build_one(rs: ResultSet, key: str, ok_all: pd.DataFrame, alpha: float, pool_machines: bool,
               machine: str | None) -> Leaderboard:
    """The leaderboard of table ``key`` of ``rs``."""
    s_all = rs.scores[rs.scores["table_key"] == key]
    ok = ok_all[ok_all["table_key"] == key]
    first = s_all.iloc[0]
    folds = fold_values(ok) if len(ok) else pd.DataFrame(columns=["table_key", "method_id", "fold_key", *METRICS, "n_test",
                                                                  "n_train", "fold", "fold_group"])
    preds = rs.predictions[rs.predictions["table_key"] == key] if rs.predictions is not None else None
    machines = dict(zip(s_all["machine"], s_all["machine_desc"]))
    sources = [rs.source(p) for p in dict.fromkeys(s_all["source"])] if "source" in s_all else []
    design = _Design.of(sources)
    notes, looks_here = _source_notes(sources)
    ref = _reference_machine(ok, machines, machine, first)
    notes += _machines_notes(machines, ref, pool_machines) + _busy_notes(ok)
    rows = [_method_row(mid, g_all, ok[ok["method_id"] == mid], folds[folds["method_id"] == mid], preds,
                        ref, pool_machines, design)
            for mid, g_all in s_all.groupby("method_id", sort=False)]
    notes += design.row_notes(rows)
    df = _ranked(_tuned_on_test(pd.DataFrame(rows)))
    _add_tests_against_best(df, folds, preds, alpha)
    notes += _mark_pareto_fronts(df)
    _add_closing_notes(df, notes)
    fr = s_all["frame_rate"].dropna()
    return Leaderboard(
        key=key, dataset=str(first["dataset"]), dataset_hash=str(first["dataset_hash"]), target=str(first["target"]),
        scheme=str(first["scheme_label"]), rows=df, folds=folds, machines=machines, reference_machine=ref,
        pooled_machines=pool_machines, alpha=alpha, frame_rate=float(fr.iloc[0]) if len(fr) else math.nan, notes=notes,
        looks=looks_here, has_design=design.captures is not None, heading=table_heading(sources, str(first["scheme_label"])),
        adaptation=_mode(s_all["adaptation"]),
    )


#: in a title, a scheme's parameter value longer than this (a file-name pattern...) is written "…"
TITLE_VALUE_CHARS = 24


def table_heading(sources: list[dict], scheme: str) -> str:
    """How a table's title names its evaluation: the evaluation's name (one of several of a protocol)
    and the scheme, its long values (a file-name pattern, a test dataset's filters) written ``…``
    (:data:`TITLE_VALUE_CHARS`) and then the protocol named; ``scheme`` (the full label) otherwise."""
    entries = [s["scheme"] for s in sources if s.get("scheme") is not None]
    short = scheme_label(entries[0], scheme, limit=TITLE_VALUE_CHARS) if entries else scheme
    names = sorted({str(s["evaluation"]) for s in sources if s.get("evaluation")})
    if not names and short != scheme:
        names = sorted({str(s["protocol"]) for s in sources if s.get("protocol")})
    return f"{', '.join(names)}: {short}" if names else short


@dataclass
class _Design:
    """The captures the table's methods were designed on (None: no source says), the methods so
    designed (empty: all of them) and what each source's design data was."""

    captures: set[str] | None
    methods: set[str]
    what: list[str]

    @classmethod
    def of(cls, sources: list[dict]) -> "_Design":
        """The design recorded by the sources of a table."""
        designs = [s for s in sources if s.get("design_captures") is not None]
        captures = {c for s in designs for c in s["design_captures"]} if designs else None
        methods = {m for s in designs for m in (s.get("design") or {}).get("methods", [])}
        what = []
        for s in designs:
            d = s.get("design") or {}
            named = ", ".join(f"{k} {', '.join(v)}" for k, v in ({"subject": d.get("subjects")} | (d.get("rows") or {})).items() if v)
            what.append(f"{named}" + (f" ({d['note']})" if d.get("note") else ""))
        return cls(captures, methods, what)

    def row_fields(self, preds: pd.DataFrame | None, mid: str, row: dict[str, Any]) -> dict[str, Any]:
        """A method's accuracy on the test captures outside the design data, and whether it was designed on them."""
        if self.captures is None:
            return {}
        held_out, n_held_out, tests_design = _held_out(preds, mid, self.captures)
        designed = tests_design and (not self.methods or bool({row["classifier"], method_label(row)} & self.methods))
        return {"held_out_accuracy": held_out, "n_held_out": n_held_out, "designed": designed}

    def row_notes(self, rows: list[dict[str, Any]]) -> list[str]:
        """One note per source's design data: which methods it flatters, if any."""
        notes = []
        for what in self.what:
            if any(r.get("designed") for r in rows):
                notes.append(f"methods marked † were designed on {what}: their usual figure includes that data; "
                             "'held out' is the accuracy on the other test captures")
            else:
                notes.append(f"the methods were designed on {what}; no test capture of this table is among them, "
                             "so the usual figure is already a held-out one")
        return notes


def _source_notes(sources: list[dict]) -> tuple[list[str], Looks | None]:
    """The notes the sources carry (files changed since the run, methods left out, the looks at the
    test set) and the ledger's count of looks of the source with the most runs."""
    notes = list(dict.fromkeys(n for s in sources for n in [*(s.get("changed") or []), *(s.get("left_out") or [])]))
    table_looks = [s["looks"] for s in sources if s.get("looks") is not None]
    looks_here = max(table_looks, key=lambda x: x.runs) if table_looks else None
    if looks_here is not None:
        notes.append(looks_here.describe() + " (ledger of test-set looks): the more methods compared and the more "
                     "runs, the more the best of them flatters")
    return notes, looks_here


def _reference_machine(ok: pd.DataFrame, machines: dict[str, str], machine: str | None, first: pd.Series) -> str | None:
    """The machine whose timings the table shows: ``machine`` if given, else the one that measured the
    most methods (ties: smallest id)."""
    timed = ok[ok["latency_ms"].notna()]
    per_machine = timed.groupby("machine")["method_id"].nunique().sort_index()
    if machine is not None:
        if machine not in machines:
            raise TouchbenchError(f"machine {machine!r} has no runs in {first['dataset']} / {first['scheme_label']}; "
                                  f"machines: {', '.join(sorted(machines))}")
        return machine
    if len(per_machine):
        return str(per_machine.sort_values(ascending=False, kind="stable").index[0])
    return None


def _machines_notes(machines: dict[str, str], ref: str | None, pool_machines: bool) -> list[str]:
    """The note on timings from several machines: shown per machine, or pooled."""
    if len(machines) > 1 and not pool_machines:
        return [
            "results from several machines: " + "; ".join(f"{k} = {v}" for k, v in sorted(machines.items()))
            + f". Timings are shown for {ref} where measured there, otherwise for the machine named in "
              "'timing machine'; the Pareto front is computed per machine."]
    if len(machines) > 1:
        return ["timings of several machines are pooled (asked with --pool-machines): "
                + "; ".join(f"{k} = {v}" for k, v in sorted(machines.items()))]
    return []


def _busy_notes(ok: pd.DataFrame) -> list[str]:
    """A note per results folder whose latencies were measured on a machine busier than its CPUs (its
    1-minute load average above the number of CPUs the run could use)."""
    timed = ok[ok["latency_ms"].notna() & ok["load_avg"].notna() & ok["usable_cpus"].notna()]
    notes = []
    for source, g in timed.groupby("source", sort=False):
        busiest = g.loc[(g["load_avg"] / g["usable_cpus"]).idxmax()]
        if busiest["load_avg"] > busiest["usable_cpus"]:
            notes.append(f"{source} was measured on a machine busier than its CPUs (load average "
                         f"{busiest['load_avg']:.1f} on {int(busiest['usable_cpus'])} usable CPUs): its wall-clock "
                         "timings are slower than on an idle machine; CPU times much less so")
    return notes


def _method_row(mid: str, g_all: pd.DataFrame, g: pd.DataFrame, f: pd.DataFrame, preds: pd.DataFrame | None,
                ref: str | None, pool_machines: bool, design: _Design) -> dict[str, Any]:
    """A method's row: its description, accuracy over its folds ``f``, timings and design."""
    row: dict[str, Any] = {
        "method_id": mid,
        "features": _mode(g_all["features"]),
        "classifier": _mode(g_all["classifier"]),
        "classifier_name": _mode(g_all["classifier_name"]),
        "feature_params": _mode(g_all["feature_params"]),
        "classifier_params": _mode(g_all["classifier_params"]),
        "early_frames": float(g_all["early_frames"].iloc[0]) if g_all["early_frames"].notna().any() else math.nan,
        "n_folds": int(len(f)),
        "n_failed": int((g_all["status"] != "ok").sum()),
        "error": _first_error(g_all),
        "runs": int(g_all["run_id"].nunique()),
        "protocols": ",".join(sorted(set(g_all["protocol"].astype(str)))),
        "leakage": _mode(g_all["leakage"]) if "leakage" in g_all else NOT_RECORDED,
        "selection": _mode(g_all["selection"]) if "selection" in g_all else "",
    }
    row.update(_accuracy_fields(g, f))
    tm = _timing_machine(g, ref, pool_machines)
    gt = g if pool_machines else g[g["machine"] == tm]
    row["timing_machine"] = tm
    row.update(_timings(gt))
    row.update(design.row_fields(preds, mid, row))
    return row


def _accuracy_fields(g: pd.DataFrame, f: pd.DataFrame) -> dict[str, Any]:
    """A method's accuracy over its folds ``f`` (mean, spread, 95 % interval) and its other metrics;
    a single fold: the Wilson interval over its captures, the spread over its seeds (scores ``g``)."""
    mean, sd, lo, hi = fold_interval(f["accuracy"].to_numpy())
    ci_method = "t"
    n_seeds = 1
    if len(f) == 1:
        n = int(f["n_test"].iloc[0])
        lo, hi = wilson_interval(int(round(mean * n)), n)
        ci_method = "wilson"
        # one fold evaluated with several seeds (repetitions): the spread over the seeds
        per_seed = g.groupby(["repetition", "seed"])["accuracy"].mean()
        n_seeds = int(len(per_seed))
        if n_seeds > 1:
            sd = float(per_seed.std(ddof=1))
    return dict(accuracy=mean, accuracy_sd=sd, n_seeds=n_seeds, ci_low=lo, ci_high=hi, ci_method=ci_method,
                balanced_accuracy=float(f["balanced_accuracy"].mean()) if len(f) else math.nan,
                macro_f1=float(f["macro_f1"].mean()) if len(f) else math.nan,
                n_test=int(f["n_test"].sum()) if len(f) else 0)


def _timing_machine(g: pd.DataFrame, ref: str | None, pool_machines: bool) -> str:
    """The machine whose timings a method shows: the reference machine where it was measured there,
    else the machine that measured it most; ``"pooled"`` when machines are pooled."""
    if pool_machines:
        return "pooled"
    measured = g[g["latency_ms"].notna()]
    if ref is not None and (measured["machine"] == ref).any():
        return ref
    if len(measured):
        return _mode(measured["machine"])
    return ref or ""


def _ranked(df: pd.DataFrame) -> pd.DataFrame:
    """The rows by accuracy (then macro F1, then id), with their rank (ties share the best rank)."""
    df = df.sort_values(["accuracy", "macro_f1", "method_id"], ascending=[False, False, True], na_position="last",
                        kind="stable").reset_index(drop=True)
    df.insert(0, "rank", df["accuracy"].rank(method="min", ascending=False, na_option="bottom").astype(int))
    return df


def _add_tests_against_best(df: pd.DataFrame, folds: pd.DataFrame, preds: pd.DataFrame | None, alpha: float) -> None:
    """Each method's paired test against the best (the first row), Holm-adjusted over the table:
    the test's name, its unit and number of units, the difference with its interval."""
    best = df["method_id"].iloc[0]
    tests = [None if mid == best else _compare(folds, preds, mid, best)[0] for mid in df["method_id"]]
    pvals = [t.pvalue if t is not None else math.nan for t in tests]
    adj = holm(pvals)
    df["test"] = [t.test if t is not None else "best" for t in tests]
    df["paired_by"] = [t.paired_by if t is not None else "" for t in tests]
    df["n_pairs"] = [t.n if t is not None else 0 for t in tests]
    df["n_subjects"] = [t.n_subjects if t is not None else 0 for t in tests]
    df["diff_vs_best"] = [t.mean_difference if t is not None else 0.0 for t in tests]
    df["diff_ci_low"] = [t.ci_low if t is not None else math.nan for t in tests]
    df["diff_ci_high"] = [t.ci_high if t is not None else math.nan for t in tests]
    df["diff_ci_method"] = [t.ci_method if t is not None else "" for t in tests]
    df["p_value"] = pvals
    df["p_holm"] = adj
    df["differs"] = [bool(np.isfinite(p) and p < alpha) for p in adj]


def _mark_pareto_fronts(df: pd.DataFrame) -> list[str]:
    """The accuracy / CPU-time Pareto front, per timing machine; a note for a machine whose front
    falls back to wall-clock latency."""
    df["pareto"] = False
    notes = []
    for tm, g in df.groupby("timing_machine"):
        cost = pareto_cost(g)
        if cost == "latency_ms" and g["latency_ms"].notna().any():
            notes.append(f"the Pareto front{' of ' + str(tm) if df['timing_machine'].nunique() > 1 else ''} is on "
                         "wall-clock latency, which the machine's load changes: some results have no CPU time "
                         "(written before touchbench measured it)")
        mask = pareto_front(g["accuracy"].to_numpy(), g[cost].to_numpy())
        df.loc[g.index[mask], "pareto"] = True
    return notes


def _add_closing_notes(df: pd.DataFrame, notes: list[str]) -> None:
    """The note on methods left untested, then each leaky evaluation's warning first of all."""
    untested = [str(r.method_id) for r in df.itertuples() if r.test == "none"]
    if untested and len(df) > 1:
        notes.append(f"{len(untested)} method(s) share neither two folds nor the predictions of one test set "
                     "with the best: not tested")
    leaks = sorted(set(df["leakage"]) - {""})
    for reason in leaks:
        notes.insert(0, f"LEAKY: {reason}. Its accuracy overstates accuracy on new people; never compare it "
                        "with an honest evaluation")


def build_leaderboards(rs: ResultSet, *, alpha: float = 0.05, pool_machines: bool = False,
                       machine: str | None = None) -> list[Leaderboard]:
    """One :class:`Leaderboard` per dataset, target and scheme of ``rs`` (and one per adaptation to the
    test data, after the plain ones)."""
    ok = rs.ok
    out = []
    for key in dict.fromkeys(rs.scores["table_key"]):
        out.append(_build_one(rs, key, ok, alpha, pool_machines, machine))
    out.sort(key=lambda lb: bool(lb.adaptation))  # the plain tables first, each adapted one after them
    seen: dict[tuple[str, str, str], list[str]] = {}
    for lb in out:  # one dataset name, different data: "data 2", "data 3"... in the order met
        hashes = seen.setdefault((lb.dataset, lb.scheme, lb.target), [])
        if lb.dataset_hash not in hashes:
            hashes.append(lb.dataset_hash)
        lb.variant = f"data {hashes.index(lb.dataset_hash) + 1}" if hashes.index(lb.dataset_hash) else ""
    for lb in out:
        if len(seen[(lb.dataset, lb.scheme, lb.target)]) > 1 and not lb.variant:
            lb.variant = "data 1"
    return out


def leaderboard(*results: Any, alpha: float = 0.05, pool_machines: bool = False,
                machine: str | None = None) -> list[Leaderboard]:
    """The leaderboards of one or more runs, as ``touchbench leaderboard`` shows them.

    Each of ``results`` is a results directory written by a run (or a
    folder holding several), or the :class:`touchbench.engine.runner.RunResult`
    that ``run_protocol`` returned. One :class:`Leaderboard` per dataset,
    target and scheme; its ``rows`` DataFrame holds one method per row, best
    first (``rank``, ``features``, ``classifier``, ``accuracy``, ``ci_low``,
    ``ci_high``, ``macro_f1``, ``latency_ms``, ...). ``to_markdown``,
    ``to_csv`` and ``to_json`` of this module format a list of them.
    """
    paths = [getattr(r, "out", r) for r in results]
    return build_leaderboards(load_results(paths), alpha=alpha, pool_machines=pool_machines, machine=machine)


def plain_tables(lbs: list[Leaderboard]) -> list[Leaderboard]:
    """The tables of methods that did not adapt to the test data: the only ones compared across tables."""
    return [lb for lb in lbs if not lb.adaptation]


def across_tables(lbs: list[Leaderboard]) -> pd.DataFrame:
    """Mean accuracy of each method (by label) in each table (rows: table titles); only methods
    present, with an accuracy, in every table; only the plain tables (:func:`plain_tables`)."""
    cols = {}
    for lb in plain_tables(lbs):
        labels = method_labels(lb.rows)
        r = lb.rows[lb.rows["accuracy"].notna()]
        cols[lb.title] = pd.Series(r["accuracy"].to_numpy(float), index=[labels[m] for m in r["method_id"]])
    acc = pd.DataFrame(cols).T
    return acc.dropna(axis=1)


def across_friedman(lbs: list[Leaderboard]) -> Friedman | None:
    """The Friedman test and Nemenyi critical difference over the tables (each table one data set, at
    the tables' alpha) of the methods present in every table; None with fewer than two of either."""
    acc = across_tables(lbs)
    if acc.shape[0] < 2 or acc.shape[1] < 2:
        return None
    return friedman(acc.to_numpy(np.float64), lbs[0].alpha)


def across_note(f: Friedman) -> str:
    """What the Friedman test and the critical difference say across the tables, in one paragraph."""
    test = (f"Friedman test over N = {f.n_datasets} tables of {f.k} methods: chi2 = {f.statistic:.2f}, "
            f"p = {_p(f.pvalue)}" if np.isfinite(f.pvalue) else
            f"no Friedman test: it needs three methods (here {f.k}) and two tables (here {f.n_datasets})")
    cd = f"Nemenyi critical difference at α={f.alpha:g}: {f.cd:.2f} mean ranks"
    if f.can_separate:
        return f"{test}. {cd}."
    return (f"{test}. {cd}: with {f.n_datasets} tables even the largest possible difference ({f.k - 1}) is below it, "
            f"so no two methods can be told apart and no diagram is drawn; {f.k} methods need at least "
            f"{f.datasets_needed} tables (datasets or evaluations).")


def ranks_across(lbs: list[Leaderboard]) -> pd.DataFrame | None:
    """:func:`mean_ranks` of ``lbs`` when they hold at least two plain tables (:func:`plain_tables`:
    the only ones compared across tables), else None: the section across tables of every report."""
    return mean_ranks(lbs) if len(plain_tables(lbs)) > 1 else None


def mean_ranks(lbs: list[Leaderboard]) -> pd.DataFrame:
    """Methods present in every table, ranked within each table (1 = best accuracy; ties get the
    average of their ranks) and the ranks averaged over the tables: columns ``method``,
    ``mean_rank``, ``tables``, ``mean_accuracy``; best first."""
    acc = across_tables(lbs)
    if acc.empty:
        return pd.DataFrame(columns=["method", "mean_rank", "tables", "mean_accuracy"])
    ranks = np.vstack([rankdata(-row.to_numpy(float), method="average") for _, row in acc.iterrows()])
    out = pd.DataFrame({"method": list(acc.columns), "mean_rank": ranks.mean(axis=0), "tables": len(acc),
                        "mean_accuracy": acc.mean(axis=0).to_numpy(float)})
    return out.sort_values(["mean_rank", "method"], kind="stable").reset_index(drop=True)


# ----------------------------------------------------------------- method lookup and compare
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


# ----------------------------------------------------------------- rendering
def _pct(v: float, d: int = 1) -> str:
    return "—" if v is None or not np.isfinite(v) else f"{100 * v:.{d}f}"


def _num(v: float, d: int = 2) -> str:
    if v is None or not np.isfinite(v):
        return "—"
    if abs(v) >= 100:
        return f"{v:.0f}"
    return f"{v:.{d}g}" if abs(v) < 0.01 else f"{v:.{d}f}"


def _p(v: float) -> str:
    if v is None or not np.isfinite(v):
        return "—"
    return "<0.001" if v < 0.001 else f"{v:.3f}"


def owns_input(r: Any) -> bool:
    """Whether a row's method brings its own input (a registered method, an estimator on the
    captures): its label names it alone, where a feature combination's row is ``features / label``."""
    return str(r.get("classifier_name", "")) in METHODS.names() or str(r["features"]).startswith("captures")


def method_label(r: Any) -> str:
    """A row's name: its label for a method that brings its own input, else ``features / label``;
    with the frames an early cut saw."""
    lab = str(r["classifier"]) if owns_input(r) else f"{r['features']} / {r['classifier']}"
    if np.isfinite(r.get("early_frames", math.nan)):
        lab += f" @ {int(r['early_frames'])} frames"
    return lab


def _params(text: Any) -> str:
    """Parameters as stored (canonical JSON) in a short readable form: ``{"bins": 8}`` -> ``bins=8``."""
    try:
        value = json.loads(str(text))
    except (TypeError, ValueError):
        return str(text)
    if isinstance(value, dict):
        return ", ".join(f"{k}={_params(json.dumps(v))}" for k, v in value.items())
    if isinstance(value, list):
        return "; ".join(p for p in (_params(json.dumps(v)) for v in value) if p)
    return str(value)


def _label_parts(rows: pd.DataFrame) -> dict[str, list[str]]:
    """Per method id, what its readable label adds to ``features / method``: the feature parameters,
    then the method's parameters, where two rows would otherwise read the same, and a ``#2`` suffix if
    they still do (``[feature part, method part, suffix]``)."""
    base = {r["method_id"]: method_label(r) for _, r in rows.iterrows()}
    parts = {mid: ["", "", ""] for mid in base}
    for i, extra in enumerate(("feature_params", "classifier_params")):
        full = {mid: base[mid] + "".join(parts[mid]) for mid in base}
        counts = pd.Series(list(full.values())).value_counts()
        for _, r in rows.iterrows():
            if counts.get(full[r["method_id"]], 0) > 1 and r.get(extra) not in (None, "", "{}", "[]"):
                p = _params(r[extra])
                if p:
                    parts[r["method_id"]][i] += f" ({'features' if i == 0 else 'method'}: {p})"
    seen: dict[str, int] = {}
    for mid in base:
        lab = base[mid] + "".join(parts[mid])
        seen[lab] = seen.get(lab, 0) + 1
        if seen[lab] > 1:
            parts[mid][2] = f" #{seen[lab]}"
    return parts


def method_labels(rows: pd.DataFrame) -> dict[str, str]:
    """A readable label per method id: ``features / method`` (and frames), with the feature
    parameters, then the method's parameters, where two rows would otherwise read the same; a
    ``#2`` suffix if they still do."""
    parts = _label_parts(rows)
    return {r["method_id"]: method_label(r) + "".join(parts[r["method_id"]]) for _, r in rows.iterrows()}


def display_rows(lb: Leaderboard) -> tuple[list[str], list[list[str]]]:
    """Header and formatted cells of a leaderboard (terminal, Markdown, HTML)."""
    header = ["#", "method", "features", "estimator", "folds", "accuracy % (±sd)", "95 % interval",
              "macro F1 %", "latency ms", "fit s", "features ms", "vs best: Δ pp, p (Holm)", "Pareto"]
    show_machine = len(set(lb.rows["timing_machine"])) > 1
    if show_machine:
        header.insert(11, "timing machine")
    show_leak = bool((lb.rows["leakage"] != "").any())
    if lb.has_design:
        header.insert(7, "held out %")
    if show_leak:
        header.insert(2, "evaluation")
    cells = []
    parts = _label_parts(lb.rows)
    for _, r in lb.rows.iterrows():
        feats = _features_cell(r, parts[r["method_id"]][0], lb.frame_rate)
        acc, ci = _accuracy_cells(r)
        failed_all = r["n_folds"] == 0 and r["n_failed"] > 0
        if failed_all:
            acc, ci = "failed", "—"
        vs = _versus_best_cell(r, failed_all)
        row = [str(r["rank"]), _name_cell(r, parts[r["method_id"]]), feats, str(r["classifier_name"]),
               f"{r['n_folds']}" + (f" (+{r['n_failed']} failed)" if r["n_failed"] else ""), acc, ci,
               _pct(r["macro_f1"]), _num(r["latency_ms"]), _num(r["fit_seconds"]), _num(r["feature_ms"]), vs,
               "★" if r["pareto"] else ""]
        if show_machine:
            row.insert(11, str(r["timing_machine"]))
        if lb.has_design:
            if r.get("designed"):
                row[5] += " †"
            row.insert(7, _pct(r["held_out_accuracy"]) + (f" (n={int(r['n_held_out'])})" if r.get("n_held_out") else ""))
        if show_leak:
            row.insert(2, f"LEAKY: {r['leakage']}" if r["leakage"] else "honest")
        cells.append(row)
    return header, cells


def _name_cell(r: pd.Series, parts: list[str]) -> str:
    """A row's readable name: its label for a method that brings its own input (a registered method,
    an estimator on the captures), else ``features / label``; with the parameters that tell colliding
    rows apart and its early cut, so that the name alone tells the rows apart."""
    feat_extra, method_extra, suffix = parts
    name = str(r["classifier"]) + method_extra + suffix
    if not owns_input(r):
        name = f"{r['features']}{feat_extra} / {name}"
    if np.isfinite(r["early_frames"]):
        name += f" @ {int(r['early_frames'])} frames"
    return name


def _features_cell(r: pd.Series, extra: str, frame_rate: float) -> str:
    """A row's feature sets, with the parameters ``extra`` that tell colliding rows apart and its early
    cut (frames, and seconds where the frame rate is known)."""
    feats = str(r["features"]) + extra  # parameters shown where rows would collide
    if np.isfinite(r["early_frames"]):
        secs = f", {r['early_frames'] / frame_rate:.2g} s" if np.isfinite(frame_rate) and frame_rate > 0 else ""
        feats += f" @ {int(r['early_frames'])} frames{secs}"
    return feats


def _accuracy_cells(r: pd.Series) -> tuple[str, str]:
    """A row's accuracy (± sd, and the seeds behind a single fold's spread) and its 95 % interval."""
    acc = _pct(r["accuracy"]) + (f" ± {_pct(r['accuracy_sd'])}" if np.isfinite(r["accuracy_sd"]) else "")
    if r["ci_method"] == "wilson" and r.get("n_seeds", 1) > 1:
        acc += f" ({int(r['n_seeds'])} seeds)"
    ci = f"{_pct(r['ci_low'])}–{_pct(r['ci_high'])}" if np.isfinite(r["ci_low"]) else "—"
    if r["ci_method"] == "wilson" and np.isfinite(r["ci_low"]):
        ci += " (Wilson)"
    return acc, ci


def _versus_best_cell(r: pd.Series, failed_all: bool) -> str:
    """A row's comparison with the best method: the difference, its Holm-adjusted p and test."""
    if failed_all:
        return f"failed: {r.get('error') or 'see the scores'}"
    if r["test"] == "best":
        return "best"
    if r["test"] == "none":
        return f"{100 * r['diff_vs_best']:+.1f}, not tested (n={r['n_pairs']})" if np.isfinite(r["diff_vs_best"]) else "not tested"
    star = " *" if r["differs"] else ""
    return (f"{100 * r['diff_vs_best']:+.1f}, p={_p(r['p_holm'])}{star} "
            f"({TEST_SHORT.get(r['test'], r['test'])}, n={r['n_pairs']} {r['paired_by']}s)")


def legend(lb: Leaderboard) -> str:
    return (f"Accuracy: mean over folds (± sample sd; for a single fold evaluated with several seeds, the sd over "
            f"the seeds); interval: Student t over folds (Wilson over captures for a "
            f"single fold). Latency: median over folds of the time to compute the features of one capture and "
            f"predict it; fit: median seconds per fold; features: median ms per capture. Δ: mean paired difference "
            f"to the best method in percentage points; p: McNemar's exact test on the test captures (one test set) "
            f"or the corrected resampled t-test over folds, Holm-adjusted over the table; * = differs at α={lb.alpha:g}. ★ = on the accuracy / "
            f"latency Pareto front (latency as the CPU time of labelling one capture, which the machine's load "
            f"changes far less than the wall-clock latency shown)."
            + (" † = the method was designed on part of this data (see the note); held out: accuracy on the "
               "test captures outside the design data (mean over folds)." if lb.has_design else "")
            + (" LEAKY rows: the evaluation let test data inform training (see the notes)."
               if bool((lb.rows["leakage"] != "").any()) else "")
            + (f" ADAPTED: every method of this table adapted to each test session using that session's "
               f"unlabelled captures ({lb.adaptation}; never their labels): a figure of another kind, ranked "
               f"and tested only against each other, never against the plain methods." if lb.adaptation else ""))


def _md_escape(s: str) -> str:
    return s.replace("|", "\\|")


def to_markdown(lbs: list[Leaderboard], title: str | None = "Leaderboard") -> str:
    out = [f"# {title}", ""] if title else []
    for lb in lbs:
        out.append(f"## {lb.title}")
        out.append("")
        header, cells = display_rows(lb)
        out.append("| " + " | ".join(header) + " |")
        out.append("|" + "|".join("---" for _ in header) + "|")
        for c in cells:
            out.append("| " + " | ".join(_md_escape(x) for x in c) + " |")
        out.append("")
        out.append(legend(lb))
        for n in lb.notes:
            out.append("")
            out.append(f"Note: {n}")
        out.append("")
    ranks = ranks_across(lbs)
    if ranks is not None and len(ranks):
        out += [f"## Mean rank across {int(ranks['tables'].iloc[0])} tables", "",
                "| method | mean rank | mean accuracy % |", "|---|---|---|"]
        out += [f"| {_md_escape(r.method)} | {r.mean_rank:.2f} | {_pct(r.mean_accuracy)} |" for r in ranks.itertuples()]
        out += ["", RANK_LEGEND, ""]
        f = across_friedman(lbs)
        out += [across_note(f), ""] if f is not None else []
    return "\n".join(out)


RANK_LEGEND = ("Rank: within each table by mean accuracy (1 = best; ties share the average of their ranks), "
               "averaged over the tables; only methods present in every table.")


def _records(lb: Leaderboard) -> list[dict[str, Any]]:
    recs = []
    for r in lb.rows.to_dict(orient="records"):
        clean = {}
        for k, v in r.items():
            if isinstance(v, (np.floating, float)):
                v = None if not np.isfinite(v) else float(v)
            elif isinstance(v, np.integer):
                v = int(v)
            elif isinstance(v, np.bool_):
                v = bool(v)
            clean[k] = v
        recs.append(clean)
    return recs


def to_json(lbs: list[Leaderboard]) -> str:
    tables = []
    for lb in lbs:
        tables.append({
            "dataset": lb.dataset, "dataset_hash": lb.dataset_hash, "target": lb.target, "scheme": lb.scheme,
            "alpha": lb.alpha, "machines": lb.machines, "reference_machine": lb.reference_machine,
            "pooled_machines": lb.pooled_machines, "notes": lb.notes, "rows": _records(lb),
            "leaky": lb.is_leaky, "looks": None if lb.looks is None else vars(lb.looks),
            "adaptation": lb.adaptation,
        })
    return json.dumps({"tables": tables}, indent=2) + "\n"


def method_names(rows: pd.DataFrame) -> dict[str, str]:
    """A table's readable name per method id, as its rows show it (:func:`display_rows`)."""
    parts = _label_parts(rows)
    return {r["method_id"]: _name_cell(r, parts[r["method_id"]]) for _, r in rows.iterrows()}


def to_csv(lbs: list[Leaderboard]) -> str:
    """Every table's rows, a method named by its readable name (its id, and the data's hash, only in
    the JSON document)."""
    frames = []
    for lb in lbs:
        d = lb.rows.copy()
        d.insert(1, "method", d["method_id"].map(method_names(lb.rows)))
        d = d.drop(columns="method_id")
        d.insert(0, "scheme", lb.scheme)
        d.insert(0, "target", lb.target)
        d.insert(0, "variant", lb.variant)
        d.insert(0, "dataset", lb.dataset)
        d["adaptation"] = lb.adaptation
        frames.append(d)
    return pd.concat(frames, ignore_index=True).to_csv(index=False)


#: the columns a terminal always shows (the name, the accuracy and its interval, the test's verdict;
#: which rows are leaky), then the others in the order a wider terminal adds them
TERMINAL_ESSENTIAL = ("#", "method", "evaluation", "accuracy % (±sd)", "95 % interval", "vs best: Δ pp, p (Holm)")
TERMINAL_PRIORITY = ("held out %", "features", "estimator", "macro F1 %", "latency ms", "Pareto", "folds",
                     "timing machine", "fit s", "features ms")
#: headers broken over two lines in a terminal, so that a header is no wider than its numbers
_TERMINAL_HEADERS = {"accuracy % (±sd)": "accuracy %\n(±sd)", "95 % interval": "95 %\ninterval",
                     "vs best: Δ pp, p (Holm)": "vs best: Δ pp,\np (Holm)", "macro F1 %": "macro\nF1 %",
                     "latency ms": "latency\nms", "features ms": "features\nms", "held out %": "held out\n%",
                     "timing machine": "timing\nmachine"}
#: columns a narrow terminal may wrap (at spaces) when even the essential ones do not fit
_TERMINAL_WRAPPING = {"evaluation", "accuracy % (±sd)", "95 % interval", "vs best: Δ pp, p (Holm)"}


def fitting_columns(widths: dict[str, int], available: int, essential: Iterable[str]) -> list[str]:
    """The columns a terminal table of ``available`` characters shows, in ``widths``' order (its
    priority): every essential one, then the others while the table still fits with every column at
    its own width (``widths``: the widest cell or header line). A rich table takes 3 characters per
    column (padding and a border) and 1 for its left edge."""
    essential = set(essential)
    shown = [h for h in widths if h in essential]
    used = 1 + sum(widths[h] + 3 for h in shown)
    for h in (h for h in widths if h not in essential):
        if used + widths[h] + 3 > available:
            break
        shown.append(h)
        used += widths[h] + 3
    return shown


def _terminal_table(lb: Leaderboard, width: int) -> Table:
    """The table of ``lb`` as a terminal of ``width`` characters shows it (:func:`fitting_columns`)."""
    header, cells = display_rows(lb)
    heads = [_TERMINAL_HEADERS.get(h, h) for h in header]
    widths = {h: max([cell_len(x) for x in head.split("\n")] + [cell_len(c[i]) for c in cells])
              for i, (h, head) in enumerate(zip(header, heads))}
    order = [h for h in (*TERMINAL_ESSENTIAL, *TERMINAL_PRIORITY) if h in widths]
    order += [h for h in header if h not in order]
    shown = set(fitting_columns({h: widths[h] for h in order}, width, TERMINAL_ESSENTIAL))
    keep = [i for i, h in enumerate(header) if h in shown]
    t = Table(title=escape(lb.title), show_lines=False)  # a name like "[b5830b]" is text, not markup
    for i in keep:
        wrap = header[i] in _TERMINAL_WRAPPING
        t.add_column(escape(heads[i]), overflow="fold", no_wrap=not wrap, min_width=None if wrap else widths[header[i]])
    for c in cells:
        t.add_row(*(escape(c[i]) for i in keep))
    return t


def _terminal_width() -> int | None:
    """The console width: ``COLUMNS`` or the terminal's own (None lets rich read them), 250 for a
    pipe or a file (the whole table)."""
    return None if sys.stdout.isatty() or os.environ.get("COLUMNS", "").isdigit() else 250


def print_terminal(lbs: list[Leaderboard], console=None) -> None:
    """The leaderboards in a terminal: on a narrow one the rank, name, accuracy, interval and test
    verdict of every method; a wider one adds columns (``TERMINAL_PRIORITY``)."""
    console = console or Console(width=_terminal_width())
    for lb in lbs:
        console.print(_terminal_table(lb, console.width))
        console.print(escape(legend(lb)), style="dim")
        for n in lb.notes:
            console.print(escape(f"Note: {n}"), style="yellow")
        console.print()
    ranks = ranks_across(lbs)
    if ranks is not None and len(ranks):
        t = Table(title=f"Mean rank across {int(ranks['tables'].iloc[0])} tables")
        for h in ("method", "mean rank", "mean accuracy %"):
            t.add_column(h)
        for r in ranks.itertuples():
            t.add_row(escape(r.method), f"{r.mean_rank:.2f}", _pct(r.mean_accuracy))
        console.print(t)
        console.print(RANK_LEGEND, style="dim")
        f = across_friedman(lbs)
        if f is not None:
            console.print(escape(across_note(f)), style="dim")


def write_text(path: Path, text: str) -> Path:
    """Write ``text`` atomically (temporary file + rename), with the mode the umask gives."""

    atomic_write_bytes(Path(path), text.encode())
    return Path(path)


def write_outputs(lbs: list[Leaderboard], out: Path, formats: Iterable[str]) -> list[Path]:
    """Write ``leaderboard.{md,csv,json}`` into ``out`` for the chosen formats."""
    written = []
    for fmt in formats:
        text = {"md": to_markdown, "csv": to_csv, "json": to_json}[fmt](lbs)
        written.append(write_text(Path(out) / f"leaderboard.{fmt}", text))
    return written
