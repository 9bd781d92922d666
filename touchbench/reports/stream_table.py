"""The stream table of a live-recognition evaluation: one row per method and decision rule.

A stream evaluation (the ``stream`` scheme; ``touchbench.engine.live``)
stores, per task, every test stream's scores under every decision rule. The
table summarises them per method and rule, over the test streams (one per
test subject, or per recording): the statistical unit is the stream, as the
test subject is for captures.

- ``frame %``: frame accuracy, the mean over streams, with a 95 % t interval
  over them (float64; one stream: no interval); always beside
  ``idle-only %``, the accuracy of answering idle at every frame of the same
  streams, and ``bal %`` (balanced accuracy over the classes present);
- ``gesture %`` / ``idle %``: recall of gesture frames and of idle frames;
- ``@0.3 s``, ``@1 s``, ``@2 s``: the fraction of gesture events decided
  correctly that long after their onset (pooled over the streams' events);
- ``decide s``: the median time from a gesture's onset to its first correct
  decision, over the events decided; ``never %``: events never decided;
- ``FA/min``: false activations per minute of idle (pooled: every stream's
  false activations over every stream's idle minutes);
- ``CPU ms``: the median CPU time of a decision made live, one frame at a
  time (the windows' features and classifier, which a gate skips when it
  decides idle, and the rule; the first decisions of each stream), and
  ``x real time``: the streams' length over the CPU time the evaluation's
  replay spent on their decisions (the windows classified in batches),
  both on one thread of the machine the run used (its load is in the
  table's notes).

Ward, Lukowicz & Gellersen's event errors (insertions, deletions,
fragmentations, merges) are summed over streams in the JSON output.
"""

from __future__ import annotations

import inspect
import json
import math
from typing import Any

import numpy as np
import pandas as pd
from scipy import stats

from ..streams.rules import RULES
from .labels import method_label

__all__ = ["LIVE_COLUMNS", "LIVE_ESSENTIAL", "LIVE_LEGEND", "LIVE_PRIORITY", "live_cells", "live_markdown", "live_rows", "live_sources", "rule_label"]

TIMES = ("0.3", "1", "2")
EVENT_ERRORS = ("event_deleted", "event_fragmented", "event_merged", "return_inserted", "return_merging",
                "return_fragmenting")
LIVE_COLUMNS = ["method", "rule", "streams", "frame %", "95 % interval", "idle-only %", "bal %", "gesture %",
                "idle %", *(f"@{t} s" for t in TIMES), "decide s", "never %", "FA/min", "CPU ms", "x real time"]


def _mean_ci(v: np.ndarray) -> tuple[float, float, float]:
    v = np.asarray(v, dtype=np.float64)
    v = v[np.isfinite(v)]
    if v.size == 0:
        return math.nan, math.nan, math.nan
    m = float(v.mean())
    if v.size < 2:
        return m, math.nan, math.nan
    half = float(stats.t.ppf(0.975, v.size - 1) * v.std(ddof=1) / math.sqrt(v.size))
    return m, max(0.0, m - half), min(1.0, m + half)


def _pooled(num: float, den: float) -> float:
    return float(num) / float(den) if den > 0 else math.nan


def _one_rule(results: list[dict[str, Any]]) -> dict[str, Any]:
    """The summary of one method and rule over its streams (``results``: each stream's result)."""
    sc = [r["scores"] for r in results]
    col = lambda k: np.array([s.get(k, math.nan) for s in sc], dtype=np.float64)  # noqa: E731
    acc, lo, hi = _mean_ci(col("frame_accuracy"))
    events = col("decision_events")
    out = {"streams": len(sc), "frame_accuracy": acc, "ci_low": lo, "ci_high": hi,
           "idle_baseline": float(np.nanmean(col("frame_idle_baseline_accuracy"))) if sc else math.nan,
           "balanced_accuracy": float(np.nanmean(col("frame_balanced_accuracy"))) if sc else math.nan,
           "gesture_recall": float(np.nanmean(col("frame_gesture_recall"))) if sc else math.nan,
           "idle_recall": float(np.nanmean(col("frame_idle_recall"))) if sc else math.nan}
    for t in TIMES:
        out[f"accuracy_at_{t}s"] = _pooled(np.nansum(col(f"accuracy_at_{t}s") * events), events.sum())
    decided = col("decision_decided")
    med = col("time_to_decision_median_s")
    out["time_to_decision_median_s"] = float(np.nanmedian(med)) if np.isfinite(med).any() else math.nan
    out["never_decided"] = _pooled(col("decision_never").sum(), events.sum())
    out["events"] = int(events.sum()) if sc else 0
    out["decided"] = int(np.nansum(decided))
    out["false_activations_per_idle_minute"] = _pooled(col("false_activations").sum(),
                                                       col("idle_seconds").sum() / 60.0)
    for k in EVENT_ERRORS:
        out[k] = int(np.nansum(col(k)))
    cpu = np.array([r.get("decision_cpu_ms_p50", math.nan) for r in results], dtype=np.float64)
    out["decision_cpu_ms"] = float(np.nanmedian(cpu)) if np.isfinite(cpu).any() else math.nan
    replay_cpu = sum(float(r.get("cpu_s", 0.0)) for r in results)
    out["x_real_time"] = _pooled(col("seconds").sum(), replay_cpu)
    return out


def live_rows(ok: pd.DataFrame) -> pd.DataFrame | None:
    """One row per method and rule of a table's finished stream tasks (None: no stream task)."""
    if "live" not in ok.columns or not (ok["live"].astype(str) != "").any():
        return None
    rows = []
    for mid, g in ok[ok["live"].astype(str) != ""].groupby("method_id", sort=False):
        payloads = [json.loads(x) for x in g["live"]]
        rules = payloads[0]["rules"]
        for k, rule in enumerate(rules):
            results = [s["results"][k] for p in payloads for s in p["streams"]]
            row = {"method_id": mid, "method": method_label(g.iloc[0]), "rule": rule_label(rule),
                   "sources": sorted({s["source"] for p in payloads for s in p["streams"]}), **_one_rule(results)}
            rows.append(row)
    df = pd.DataFrame(rows)
    return df.sort_values("frame_accuracy", ascending=False, kind="stable", na_position="last").reset_index(drop=True)


def rule_label(rule: dict[str, Any]) -> str:
    """A rule as a person reads it: its name and the parameters it was given other than its defaults
    (``majority n=9``; ``max`` for the default threshold); the idle class and the level a gate chose
    on training captures are left out."""
    try:
        defaults = {k: p.default for k, p in inspect.signature(RULES.get(str(rule["name"]))).parameters.items()}
    except Exception:  # a rule this version does not know: every parameter
        defaults = {}
    parts = [f"{k}={v:g}" if isinstance(v, float) else f"{k}={v}" for k, v in rule.items()
             if k not in ("name", "fitted_level", "idle") and defaults.get(k, object()) != v]
    return " ".join([str(rule["name"]), *parts])


def live_sources(rows: pd.DataFrame) -> str:
    """What the streams are, for a title: ``spliced streams``, ``scene streams``, ``recorded streams``."""
    kinds = sorted({k for s in rows["sources"] for k in s})
    return " and ".join(kinds) + " streams"


def _pct(v: float) -> str:
    return "—" if v is None or not np.isfinite(v) else f"{100 * v:.1f}"


def _num(v: float, d: int = 2) -> str:
    return "—" if v is None or not np.isfinite(v) else f"{v:.{d}f}"


def live_cells(rows: pd.DataFrame) -> tuple[list[str], list[list[str]]]:
    """Header (:data:`LIVE_COLUMNS`) and formatted cells of a stream table."""
    cells = []
    for _, r in rows.iterrows():
        ci = "—" if not np.isfinite(r["ci_low"]) else f"{_pct(r['ci_low'])}–{_pct(r['ci_high'])}"
        cells.append([r["method"], r["rule"], str(r["streams"]), _pct(r["frame_accuracy"]), ci,
                      _pct(r["idle_baseline"]), _pct(r["balanced_accuracy"]), _pct(r["gesture_recall"]),
                      _pct(r["idle_recall"]), *(_pct(r[f"accuracy_at_{t}s"]) for t in TIMES),
                      _num(r["time_to_decision_median_s"]), _pct(r["never_decided"]),
                      _num(r["false_activations_per_idle_minute"], 1), _num(r["decision_cpu_ms"]),
                      _num(r["x_real_time"], 0)])
    return list(LIVE_COLUMNS), cells


LIVE_LEGEND = ("Stream table: each test stream replayed frame by frame (the unit is the stream). frame %: frame "
               "accuracy, mean over streams with its 95 % t interval, beside idle-only %, answering idle at every "
               "frame; bal %: balanced accuracy; gesture % / idle %: recall of gesture and idle frames; @t s: "
               "gesture events decided correctly t s after onset; decide s: median time from onset to the first "
               "correct decision; never %: events never decided; FA/min: false activations per minute of idle; "
               "CPU ms: median CPU time of a decision made live, one frame at a time, on one thread; x real time: "
               "stream time over the CPU time of the evaluation's replay (windows classified in batches).")


#: the columns a narrow terminal keeps; the others follow, in this order, while the table fits
#: (``reports.rendering.terminal_layout``)
LIVE_ESSENTIAL = ("method", "rule", "frame %", "idle-only %")
LIVE_PRIORITY = ("@1 s", "FA/min", "95 % interval", "@0.3 s", "@2 s", "decide s", "gesture %", "idle %", "bal %",
                 "CPU ms", "x real time", "never %", "streams")


def live_markdown(rows: pd.DataFrame) -> list[str]:
    """The stream table in Markdown lines, with its legend."""
    header, cells = live_cells(rows)
    out = ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
    out += ["| " + " | ".join(c.replace("|", "\\|") for c in row) + " |" for row in cells]
    return out + ["", LIVE_LEGEND]
