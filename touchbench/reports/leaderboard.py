"""Leaderboards: one table per dataset, target and scheme (pairwise comparison of two methods:
:mod:`touchbench.reports.compare`; the tables as text: :mod:`touchbench.reports.rendering`).

Each row is a method (a parameter hash, see :mod:`touchbench.reports.results`):
rank by mean accuracy over folds, the spread and 95 % interval, macro F1,
balanced accuracy, the median latency per capture (features + predict of one
capture, ms), the median fit time (s per fold) and feature extraction time
(ms per capture), the paired test against the best method (Holm-adjusted
within the table; statistics in :mod:`touchbench.reports.stats`) and whether
the method is on the accuracy / latency Pareto front. A single test set scored
with several seeds shows the mean over the seeds, their spread, and an interval
and test over captures and seeds (:mod:`touchbench.reports.seeds`).

Timings and machines: accuracy does not depend on the machine and is pooled
over every run of a method. Timings do, so a table uses one *reference
machine* (the one that measured the most of its methods; ``machine=`` picks
another): a method measured there shows that machine's timings, a method
measured only elsewhere shows its own machine's, flagged in the
``timing_machine`` column, and the Pareto front is computed separately for
each machine. ``pool_machines=True`` pools every machine's timings into one
front (asked for explicitly, and said so in the table notes).

Across tables (several datasets or schemes; :mod:`touchbench.reports.across`):
:func:`touchbench.reports.across.mean_ranks` ranks the
methods present in every table within each table (by mean accuracy, ties
averaged) and averages the ranks, as MOABB and aeon rank pipelines across
datasets; :func:`touchbench.reports.across.across_tables` gives the accuracies the critical difference
diagram across tables uses, :func:`touchbench.reports.across.across_friedman` the Friedman test and
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

A table whose tasks are points of a data curve (:mod:`touchbench.reports.curves`: a learning curve
over training subjects, or calibration captures of the test subject) ranks its methods at the
curve's reference point (the full point; ``k = 0`` of a calibration curve) and carries the whole
curve in ``curve``, with the smallest size reaching ``fraction`` of the full accuracy.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from ..core.errors import TouchbenchError
from ..results.ledger import Looks
from ..results.store import NOT_RECORDED
from .breakdown import Breakdown
from .curve_table import capped_notes, reference_note
from .curves import DEFAULT_FRACTION, Curve, curve_of, reference_rows
from .labels import method_label
from .paired import _latest
from .pareto import pareto_cost, pareto_front
from .results import ResultSet, load_results, scheme_label
from .seeds import compare_pair, seed_fields
from .stats import fold_interval, holm, rank_values, wilson_interval
from .stream_table import live_sources, live_table

__all__ = [
    "Leaderboard",
    "build_leaderboards",
    "fold_values",
    "leaderboard",
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
    #: a stream evaluation's table: one row per method and decision rule (:mod:`.stream_table`)
    live: pd.DataFrame | None = None
    #: the row columns the evaluation's ``report:`` block adds (:mod:`.breakdown`: ``recall[notouch]``...)
    breakdown: list[str] = field(default_factory=list)
    #: the table's data curve, its rows at the curve's reference point (:mod:`.curves`); None off a curve
    curve: Curve | None = None
    #: the results folder the table comes from (:func:`results_name`), for file names; "" when unknown
    name: str = ""
    #: the times its Pareto fronts are on (:func:`touchbench.reports.pareto.pareto_cost`: ``latency_cpu_ms``,
    #: or ``latency_ms`` for a machine whose results have no CPU time); empty when no method was timed
    pareto_costs: list[str] = field(default_factory=list)

    @property
    def title(self) -> str:
        t = f"{self.dataset}" + (f" ({self.variant})" if self.variant else "") + f" — {self.heading or self.scheme}"
        t += f" — {live_sources(self.live)}" if self.live is not None else ""
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
    s_all, ok = reference_rows(rs.scores[rs.scores["table_key"] == key], ok_all[ok_all["table_key"] == key])
    first = s_all.iloc[0]
    folds = fold_values(ok) if len(ok) else pd.DataFrame(columns=["table_key", "method_id", "fold_key", *METRICS, "n_test",
                                                                  "n_train", "fold", "fold_group"])
    preds = rs.predictions[rs.predictions["table_key"] == key] if rs.predictions is not None else None
    if preds is not None and "task_id" in preds and (s_all["curve"] != "").any():  # a curve: its reference point
        preds = preds[preds["task_id"].isin(set(s_all["task_id"]))]
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
    report = Breakdown.of(sources)
    report = report.tested(preds) if report is not None else None
    for r in rows if report is not None else []:
        r.update(report.fields(preds, r["method_id"]))
    df = _ranked(_tuned_on_test(pd.DataFrame(rows)))
    _add_tests_against_best(df, folds, preds, alpha)
    pareto_notes, pareto_costs = _mark_pareto_fronts(df)
    notes += pareto_notes
    _add_closing_notes(df, notes)
    live, live_notes = live_table(ok)
    notes += live_notes
    fr = s_all["frame_rate"].dropna()
    return Leaderboard(
        key=key, dataset=str(first["dataset"]), dataset_hash=str(first["dataset_hash"]), target=str(first["target"]),
        scheme=str(first["scheme_label"]), rows=df, folds=folds, machines=machines, reference_machine=ref,
        pooled_machines=pool_machines, alpha=alpha, frame_rate=float(fr.iloc[0]) if len(fr) else math.nan, notes=notes,
        looks=looks_here, has_design=design.captures is not None, heading=table_heading(sources, str(first["scheme_label"])),
        adaptation=_mode(s_all["adaptation"]), live=live, breakdown=report.columns if report is not None else [],
        name=results_name(sources), pareto_costs=pareto_costs,
    )


def results_name(sources: list[dict]) -> str:
    """The name of the results folder a table comes from (the first of its sources): the folder's
    name (``results/stream-skin``: ``stream-skin``), with its run's for one evaluation of several
    (``results/touch-all/loso``: ``touch-all-loso``); "" without sources."""
    if not sources or not sources[0].get("path"):
        return ""
    path = Path(str(sources[0]["path"]))
    return f"{path.parent.name}-{path.name}" if sources[0].get("evaluation") and path.parent.name else path.name


#: in a title, a scheme's parameter value longer than this (a file-name pattern...) is written "…"
TITLE_VALUE_CHARS = 24


def table_heading(sources: list[dict], scheme: str) -> str:
    """How a table's title names its evaluation: the evaluation's name (one of several of a protocol),
    then the scheme as a person would name it (``cross-dataset: trained on haart, tested on
    other-study``: :func:`touchbench.reports.results.scheme_label` with the dataset), else with its
    long values (a file-name pattern, a test dataset's filters) written ``…`` (:data:`TITLE_VALUE_CHARS`)
    and then the protocol named; ``scheme`` (the full label) otherwise."""
    entry = next((s for s in sources if s.get("scheme") is not None), None)
    names = sorted({str(s["evaluation"]) for s in sources if s.get("evaluation")})
    if entry is not None and scheme_label(entry["scheme"], dataset=entry.get("dataset")) != scheme_label(entry["scheme"]):
        readable = scheme_label(entry["scheme"], limit=TITLE_VALUE_CHARS, dataset=entry.get("dataset"))
        return f"{', '.join(names)} — {readable}" if names else readable
    short = scheme_label(entry["scheme"], scheme, limit=TITLE_VALUE_CHARS) if entry is not None else scheme
    if not names and short != scheme:
        names = sorted({str(s["protocol"]) for s in sources if s.get("protocol")})
    return f"{', '.join(names)}: {short}" if names else short


@dataclass
class _Design:
    """The captures the table's methods were designed on, per block of design data: each block's
    captures and the methods it names (empty: all of them), and what each block's data was. No block:
    no source says."""

    blocks: list[tuple[set[str], set[str]]]
    what: list[str]

    @property
    def captures(self) -> set[str] | None:
        """Every design capture of the table (None: no source declares design data)."""
        return set().union(*(c for c, _ in self.blocks)) if self.blocks else None

    @classmethod
    def of(cls, sources: list[dict]) -> "_Design":
        """The design recorded by the sources of a table: one block, or a list of blocks."""
        blocks, what = [], []
        for s in sources:
            if s.get("design_captures") is None:
                continue
            designs, captures = s.get("design") or {}, s["design_captures"]
            if isinstance(designs, dict):
                designs, captures = [designs], [captures]
            for d, c in zip(designs, captures):
                blocks.append((set(c), set(d.get("methods", []))))
                named = ", ".join(f"{k} {', '.join(v)}" for k, v in ({"subject": d.get("subjects")} | (d.get("rows") or {})).items() if v)
                what.append(f"{named}" + (f" ({d['note']})" if d.get("note") else ""))
        return cls(blocks, what)

    def _of_row(self, row: dict[str, Any]) -> set[str] | None:
        """The captures the row's method was designed on (None: no block names it)."""
        names = {row["classifier"], method_label(row)}
        mine = [c for c, methods in self.blocks if not methods or names & methods]
        return set().union(*mine) if mine else None

    def row_fields(self, preds: pd.DataFrame | None, mid: str, row: dict[str, Any]) -> dict[str, Any]:
        """A method's accuracy on the test captures outside its design data, and whether it was designed on them."""
        if not self.blocks:
            return {}
        mine = self._of_row(row)
        held_out, n_held_out, tests_design = _held_out(preds, mid, mine if mine is not None else self.captures)
        return {"held_out_accuracy": held_out, "n_held_out": n_held_out, "designed": mine is not None and tests_design}

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
            + (f". Timings are shown for {ref} where measured there, otherwise for the machine named in "
               "'timing machine'; the Pareto front is computed per machine." if ref is not None else
               ". No method of this table has a latency per capture, so no machine's timings are chosen.")]
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
    row.update(seed_fields(g, f, preds, mid))  # one test set, several seeds: over captures and seeds
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
    return dict(accuracy=mean, accuracy_sd=sd, n_seeds=n_seeds, seed_min=math.nan, seed_max=math.nan,
                ci_low=lo, ci_high=hi, ci_method=ci_method,
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
    """The rows by accuracy (then macro F1, then id), with their rank (ties share the best rank);
    accuracies equal to :data:`touchbench.reports.stats.RANK_DIGITS` significant digits are one."""
    key = pd.DataFrame({"acc": rank_values(df["accuracy"]), "f1": rank_values(df["macro_f1"]), "id": df["method_id"]},
                       index=df.index)
    key = key.sort_values(["acc", "f1", "id"], ascending=[False, False, True], na_position="last", kind="stable")
    df = df.loc[key.index].reset_index(drop=True)
    df.insert(0, "rank", key["acc"].rank(method="min", ascending=False, na_option="bottom").astype(int).to_numpy())
    return df


def _add_tests_against_best(df: pd.DataFrame, folds: pd.DataFrame, preds: pd.DataFrame | None, alpha: float) -> None:
    """Each method's paired test against the best (the first row), Holm-adjusted over the table:
    the test's name, its unit and number of units, the difference with its interval."""
    best = df["method_id"].iloc[0]
    tests = [None if mid == best else compare_pair(folds, preds, mid, best)[0] for mid in df["method_id"]]
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


def _mark_pareto_fronts(df: pd.DataFrame) -> tuple[list[str], list[str]]:
    """The accuracy / CPU-time Pareto front, per timing machine; a note for a machine whose front
    falls back to wall-clock latency; and the times the fronts are on (each once)."""
    df["pareto"] = False
    notes, costs = [], []
    for tm, g in df.groupby("timing_machine"):
        cost = pareto_cost(g)
        if g[cost].notna().any() and cost not in costs:
            costs.append(cost)
        if cost == "latency_ms" and g["latency_ms"].notna().any():
            notes.append(f"the Pareto front{' of ' + str(tm) if df['timing_machine'].nunique() > 1 else ''} is on "
                         "wall-clock latency, which the machine's load changes: some results have no CPU time "
                         "(written before touchbench measured it)")
        mask = pareto_front(g["accuracy"].to_numpy(), g[cost].to_numpy())
        df.loc[g.index[mask], "pareto"] = True
    return notes, costs


def _add_closing_notes(df: pd.DataFrame, notes: list[str]) -> None:
    """The note on methods left untested, then each leaky evaluation's warning first of all."""
    untested = [str(r.method_id) for r in df.itertuples() if r.test == "none"]
    if untested and len(df) > 1:
        notes.append(f"{len(untested)} method(s) share neither two folds nor the predictions of one test set "
                     "with the best: not tested")
    flat = int(((df["test"] == "corrected-t") & df["p_value"].isna()).sum())
    if flat:
        notes.append(f"{flat} method(s) differ from the best by the same amount in every fold (no variance): "
                     "the corrected t-test is undefined there, so no p (—), and they are left out of Holm's family")
    leaks = sorted(set(df["leakage"]) - {""})
    for reason in leaks:
        notes.insert(0, f"LEAKY: {reason}. Its accuracy overstates accuracy on new people; never compare it "
                        "with an honest evaluation")


def build_leaderboards(rs: ResultSet, *, alpha: float = 0.05, pool_machines: bool = False,
                       machine: str | None = None, fraction: float = DEFAULT_FRACTION) -> list[Leaderboard]:
    """One :class:`Leaderboard` per dataset, target and scheme of ``rs`` (and one per adaptation to the
    test data, after the plain ones); ``fraction``: the share of the full accuracy a data curve's
    methods are asked to reach."""
    ok = rs.ok
    out = []
    for key in dict.fromkeys(rs.scores["table_key"]):
        out.append(_build_one(rs, key, ok, alpha, pool_machines, machine))
        preds = rs.predictions[rs.predictions["table_key"] == key] if rs.predictions is not None else None
        out[-1].curve = curve_of(ok[ok["table_key"] == key], preds, fraction)
        if out[-1].curve is not None:
            out[-1].notes[:0] = [reference_note(out[-1].curve), *capped_notes(out[-1].curve)]
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
                machine: str | None = None, fraction: float = DEFAULT_FRACTION) -> list[Leaderboard]:
    """The leaderboards of one or more runs, as ``touchbench leaderboard`` shows them.

    Each of ``results`` is a results directory written by a run (or a
    folder holding several), or the :class:`touchbench.engine.runner.RunResult`
    that ``run_protocol`` returned. One :class:`Leaderboard` per dataset,
    target and scheme; its ``rows`` DataFrame holds one method per row, best
    first (``rank``, ``features``, ``classifier``, ``accuracy``, ``ci_low``,
    ``ci_high``, ``macro_f1``, ``latency_ms``, ...). ``to_markdown``,
    ``to_csv`` and ``to_json`` of :mod:`touchbench.reports.rendering` format a list of them.
    """
    paths = [getattr(r, "out", r) for r in results]
    return build_leaderboards(load_results(paths), alpha=alpha, pool_machines=pool_machines, machine=machine,
                              fraction=fraction)
