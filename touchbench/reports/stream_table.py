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

What keeps the table from misleading (:func:`live_table`, its notes):

- the default rule, the one ``touchbench stream`` decides with for a model
  trained on the evaluation (the payload's ``default_rule``; without it
  :data:`touchbench.streams.rules.DEFAULT_RULE`), is marked ``(default)`` in
  the rule cell (column ``default`` in CSV and JSON); a note says when it is
  not among the rules compared;
- a method without graded probabilities (the payload's ``probabilities``
  false: a one-hot per window) shows one row per set of rules that decided
  alike on every stream (the default rule's, else the first's; the others in
  ``same_as``), with a note naming the method, the rules and why;
- a ``CPU ms`` cell is marked ``‡`` when under half of the decisions timed
  ran the classifier (a gate decided idle, or a rule waited for frames): a
  note gives the share and the 99th percentile;
- a note says when the hop, or the shortest window, is longer than the
  median gesture event of the scored streams (the payload's ``truth``), with
  the figures.
"""

from __future__ import annotations

from collections import Counter
import json
import math
from typing import Any

import numpy as np
import pandas as pd
from scipy import stats

from ..streams.rules import DEFAULT_RULE, RULES, rule_defaults
from .labels import _pct, method_label

__all__ = ["LIVE_COLUMNS", "LIVE_ESSENTIAL", "LIVE_LEGEND", "LIVE_PRIORITY", "default_rule_index", "live_cells",
           "live_markdown", "live_rows", "live_sources", "live_table", "rule_label"]

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
    out.update(_cpu(results))
    replay_cpu = sum(float(r.get("cpu_s", 0.0)) for r in results)
    out["x_real_time"] = _pooled(col("seconds").sum(), replay_cpu)
    return out


def _median(results: list[dict[str, Any]], key: str, how: Any = np.nanmedian) -> float:
    v = np.array([r.get(key, math.nan) for r in results], dtype=np.float64)
    return float(how(v)) if np.isfinite(v).any() else math.nan


def _cpu(results: list[dict[str, Any]]) -> dict[str, float]:
    """A decision's CPU over the streams (the median of each stream's median and 99th percentile) and
    the share of decisions that ran the classifier (the mean over streams; NaN for older results)."""
    return {"decision_cpu_ms": _median(results, "decision_cpu_ms_p50"),
            "decision_cpu_ms_p99": _median(results, "decision_cpu_ms_p99"),
            "classified_fraction": _median(results, "classified_fraction", np.nanmean),
            "live_classified_fraction": _median(results, "live_classified_fraction", np.nanmean)}


def live_rows(ok: pd.DataFrame) -> pd.DataFrame | None:
    """One row per method and rule of a table's finished stream tasks (None: no stream task)."""
    return live_table(ok)[0]


def live_table(ok: pd.DataFrame) -> tuple[pd.DataFrame | None, list[str]]:
    """The rows of a table's finished stream tasks (one per method and rule shown; None: no stream
    task) and the notes that go with them (module docstring)."""
    if "live" not in ok.columns or not (ok["live"].astype(str) != "").any():
        return None, []
    rows: list[dict[str, Any]] = []
    notes: list[str] = []
    first: list[dict[str, Any]] = []
    for mid, g in ok[ok["live"].astype(str) != ""].groupby("method_id", sort=False):
        payloads = [json.loads(x) for x in g["live"]]
        first = first or payloads
        method = method_label(g.iloc[0])
        rules = payloads[0]["rules"]
        chosen = all("choice" in p for p in payloads)
        default = None if chosen else default_rule_index(payloads[0])
        if default is None and not chosen:
            notes.append(f"the default rule ({rule_label(_default_declaration(payloads[0]))}), which touchbench "
                         "stream decides with for a model trained on this evaluation, is not among the rules "
                         "compared")
        alike = _alike_rules(payloads, default) if payloads[0].get("probabilities") is False else \
            {k: [] for k in range(len(rules))}
        for k, same in alike.items():
            results = [s["results"][k] for p in payloads for s in p["streams"]]
            rows.append({"method_id": mid, "method": method, "rule": rule_label(rules[k]), "default": k == default,
                         "same_as": [rule_label(rules[j]) for j in same],
                         "probabilities": payloads[0].get("probabilities"),
                         "sources": sorted({s["source"] for p in payloads for s in p["streams"]}),
                         **_one_rule(results)})
        notes += _alike_note(method, rules, alike)
        if chosen:
            rows.append(_chosen_row(mid, method, payloads))
            notes.append(_chosen_note(method, payloads))
    df = pd.DataFrame(rows)
    df = df.sort_values("frame_accuracy", ascending=False, kind="stable", na_position="last").reset_index(drop=True)
    notes += _cpu_notes(df) + duration_notes(first)
    return df, list(dict.fromkeys(notes))


#: the rule cell of the row holding, per fold, the rule its inner folds chose
CHOSEN = "inner choice"


def _chosen_row(mid: Any, method: str, payloads: list[dict[str, Any]]) -> dict[str, Any]:
    """The row of the rule chosen inside each fold on its training side (``choose_rule``): each fold's
    streams scored with that fold's choice. It is the default: ``touchbench train`` chooses the same way."""
    results = [s["results"][p["choice"]["rule"]] for p in payloads for s in p["streams"]]
    return {"method_id": mid, "method": method, "rule": CHOSEN, "default": True, "same_as": [],
            "probabilities": payloads[0].get("probabilities"),
            "sources": sorted({s["source"] for p in payloads for s in p["streams"]}), **_one_rule(results)}


def _chosen_note(method: str, payloads: list[dict[str, Any]]) -> str:
    picks = Counter(rule_label(p["rules"][p["choice"]["rule"]]) for p in payloads)
    c = payloads[0]["choice"]
    return (f"{method}, {CHOSEN}: each fold's rule chosen on its training subjects alone ({c['inner_folds']} inner "
            f"folds: the best mean frame accuracy among the rules with at most {c['max_false_per_min']:g} false "
            f"activations per idle minute), never on its test streams; chosen: "
            + ", ".join(f"{k} ({v} fold{'s' if v > 1 else ''})" for k, v in picks.most_common()))


def _default_declaration(payload: dict[str, Any]) -> dict[str, Any]:
    d = payload.get("default_rule")
    return dict(d) if isinstance(d, dict) else {"name": d} if isinstance(d, str) else dict(DEFAULT_RULE)


def _rule_params(decl: dict[str, Any], idle: str) -> tuple[str, dict[str, Any]]:
    """A rule's name and every parameter (its defaults filled in; a gate's level ``auto`` as the level it
    fitted, when it did; the evaluation's idle class where the rule takes one and was not given it)."""
    d = dict(decl)
    name = str(d.pop("name", ""))
    full = rule_defaults(name)  # a rule this version does not know: its parameters as given
    if name in RULES and "idle" in RULES.get(name).Params.model_fields:
        full["idle"] = idle
    full.update(d)
    fitted = full.pop("fitted_level", None)
    if full.get("level") == "auto" and fitted is not None:
        full["level"] = fitted
    return name, {k: float(v) if isinstance(v, (int, float)) and not isinstance(v, bool) else v
                  for k, v in full.items()}


def default_rule_index(payload: dict[str, Any]) -> int | None:
    """The index, among the payload's rules, of the rule ``touchbench stream`` decides with for a model
    trained on the evaluation (the payload's ``default_rule``, else :data:`DEFAULT_RULE`): the rule with
    the same name and parameters, a gate's fitted level read for ``auto``; failing that, one that
    differs only by its level where the evaluation fitted the level (a model fits its own); None when
    no rule matches."""
    idle = str(payload.get("idle", ""))
    name, want = _rule_params(_default_declaration(payload), idle)
    have = [(_rule_params(r, idle), r.get("level") == "auto") for r in payload.get("rules", [])]
    for loose in (False, True):
        for k, ((n, params), auto) in enumerate(have):
            drop = ("level",) if loose and auto else ()
            if n == name and {a: b for a, b in params.items() if a not in drop} == \
                    {a: b for a, b in want.items() if a not in drop}:
                return k
    return None


def _alike_rules(payloads: list[dict[str, Any]], default: int | None) -> dict[int, list[int]]:
    """The rules to show (indices, in order), each with the rules that made exactly its decisions on every
    stream: the default rule shown for its set, else the set's first."""
    n = len(payloads[0]["rules"])
    decisions = [[s["results"][k]["decisions"] for p in payloads for s in p["streams"]] for k in range(n)]
    order = ([default] if default is not None else []) + [k for k in range(n) if k != default]
    shown: dict[int, list[int]] = {}
    for k in order:
        same = next((j for j in shown if decisions[j] == decisions[k]), None)
        if same is None:
            shown[k] = []
        else:
            shown[same].append(k)
    return {k: sorted(shown[k]) for k in sorted(shown)}


def _alike_note(method: str, rules: list[dict[str, Any]], alike: dict[int, list[int]]) -> list[str]:
    pairs = [(rule_label(rules[k]), [rule_label(rules[j]) for j in same]) for k, same in alike.items() if same]
    if not pairs:
        return []
    said = "; ".join(f"{', '.join(same)} as {shown}" for shown, same in pairs)
    return [f"{method} gives no graded probabilities (every window it classified had probability 1 for one "
            f"class), so a threshold or an HMM reads the same answer as max does: rules that decided exactly "
            f"alike on every stream are shown once ({said})"]


#: under this share of timed decisions running the classifier, a CPU cell is marked and noted
CLASSIFIED_NOTE_BELOW = 0.5


def _classified(r: Any) -> float:
    """The share of the timed decisions that ran the classifier (of all decisions for a result that has
    only that); NaN for older results."""
    v = r.get("live_classified_fraction", math.nan)
    return float(v) if np.isfinite(v) else float(r.get("classified_fraction", math.nan))


def _skips(r: Any) -> bool:
    f = _classified(r)
    return bool(np.isfinite(f) and f < CLASSIFIED_NOTE_BELOW)


def _cpu_notes(rows: pd.DataFrame) -> list[str]:
    out = []
    for _, r in rows.iterrows():
        if _skips(r):
            out.append(f"CPU ms of {r['method']} · {r['rule']} (‡) is mostly skipped decisions: "
                       f"{_pct(_classified(r))} % of the timed decisions ran the classifier (the others were "
                       f"decided from the frames alone, without features or classifier); median "
                       f"{_num(r['decision_cpu_ms'])} ms, 99th percentile {_num(r['decision_cpu_ms_p99'])} ms "
                       f"(medians over streams), the latter closer to a decision that classifies")
    return out


def gesture_durations(payloads: list[dict[str, Any]]) -> np.ndarray:
    """The durations (s) of the gesture events of the payloads' streams: each run of one true label other
    than the idle class (the payload's ``truth``, run-length)."""
    out = []
    for p in payloads:
        rate, idle = float(p["frame_rate"]), str(p["idle"])
        for s in p["streams"]:
            runs = s["truth"]
            for k, (a, label) in enumerate(runs):
                b = runs[k + 1][0] if k + 1 < len(runs) else s["frames"]
                if str(label) != idle:
                    out.append((int(b) - int(a)) / rate)
    return np.asarray(out, dtype=np.float64)


def duration_notes(payloads: list[dict[str, Any]]) -> list[str]:
    """A note when the hop, or the shortest window, is longer than the median gesture event of the
    scored streams (the streams of ``payloads``, one method's tasks), with the figures."""
    d = gesture_durations(payloads)
    if not d.size:
        return []
    med = float(np.median(d))
    hop = float(payloads[0]["hop_s"])
    window = float(min(payloads[0]["windows_s"]))
    out = []
    for what, v, why in (("the hop", hop, "a gesture can begin and end between two decisions"),
                         ("the shortest window", window, "every window that sees such a gesture also sees "
                          "what came before it")):
        if v > med:
            out.append(f"{what} ({v:g} s) is longer than the median gesture event of the scored streams "
                       f"({med:.2f} s; {int(np.sum(d < v))} of {d.size} events are shorter than {v:g} s): {why}")
    return out


def rule_label(rule: dict[str, Any]) -> str:
    """A rule as a person reads it: its name and the parameters it was given other than its defaults
    (``majority n=9``; ``max`` for the default threshold); the idle class and the level a gate chose
    on training captures are left out."""
    defaults = rule_defaults(str(rule["name"]))  # a rule this version does not know: every parameter
    parts = [f"{k}={v:g}" if isinstance(v, float) else f"{k}={v}" for k, v in rule.items()
             if k not in ("name", "fitted_level", "idle") and defaults.get(k, object()) != v]
    return " ".join([str(rule["name"]), *parts])


def live_sources(rows: pd.DataFrame) -> str:
    """What the streams are, for a title: ``spliced streams``, ``scene streams``, ``recorded streams``."""
    kinds = sorted({k for s in rows["sources"] for k in s})
    return " and ".join(kinds) + " streams"


def _num(v: float, d: int = 2) -> str:
    return "—" if v is None or not np.isfinite(v) else f"{v:.{d}f}"


def live_cells(rows: pd.DataFrame) -> tuple[list[str], list[list[str]]]:
    """Header (:data:`LIVE_COLUMNS`) and formatted cells of a stream table."""
    cells = []
    for _, r in rows.iterrows():
        ci = "—" if not np.isfinite(r["ci_low"]) else f"{_pct(r['ci_low'])}–{_pct(r['ci_high'])}"
        rule = f"{r['rule']} (default)" if bool(r.get("default", False)) else str(r["rule"])
        cpu = _num(r["decision_cpu_ms"]) + (" ‡" if _skips(r) else "")
        cells.append([r["method"], rule, str(r["streams"]), _pct(r["frame_accuracy"]), ci,
                      _pct(r["idle_baseline"]), _pct(r["balanced_accuracy"]), _pct(r["gesture_recall"]),
                      _pct(r["idle_recall"]), *(_pct(r[f"accuracy_at_{t}s"]) for t in TIMES),
                      _num(r["time_to_decision_median_s"]), _pct(r["never_decided"]),
                      _num(r["false_activations_per_idle_minute"], 1), cpu,
                      _num(r["x_real_time"], 0)])
    return list(LIVE_COLUMNS), cells


LIVE_LEGEND = ("Stream table: each test stream replayed frame by frame (the unit is the stream). frame %: frame "
               "accuracy, mean over streams with its 95 % t interval, beside idle-only %, answering idle at every "
               "frame; bal %: balanced accuracy; gesture % / idle %: recall of gesture and idle frames; @t s: "
               "gesture events decided correctly t s after onset; decide s: median time from onset to the first "
               "correct decision; never %: events never decided; FA/min: false activations per minute of idle; "
               "CPU ms: median CPU time of a decision made live, one frame at a time, on one thread; x real time: "
               "stream time over the CPU time of the evaluation's replay (windows classified in batches). "
               "(default): the rule touchbench stream decides with for a model trained on this evaluation; "
               "‡: under half of the timed decisions ran the classifier, so the CPU is mostly that of "
               "decisions skipped (see the note).")


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
