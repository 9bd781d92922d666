"""One task of a stream evaluation: train once, replay every test stream with every decision rule,
score each replay frame by frame.

The task (a fold of the ``stream`` scheme and a method) fits the method on
the fold's training captures, on windows cut from them
(:func:`touchbench.streams.replay.training_samples`), or on windows cut from
the training side's streams (:func:`touchbench.streams.replay.stream_samples`);
an estimator that takes the idle class (``idle``: the two-stage recogniser)
gets the scheme's when its entry does not name one. When the fold has inner
folds (``choose_rule``), the same is done on each inner fold and its
streams replayed with every rule, and the rule is chosen there
(:func:`choose_rule`). It fits each declared
decision rule on the same training captures (the gate's ``level: auto``),
then replays each test stream through the recogniser ``touchbench stream``
runs (:func:`touchbench.streams.replay.replay`: the windows due at every hop
classified in batches, the decisions those of stepping frame by frame) and
scores the decisions against each frame's truth
(:func:`touchbench.scoring.streams.score_stream`; the none label
and the frames before the first decision count as idle).

What it returns, plain data for the results store:

- the scores row's ``live`` column: JSON with the rules and, per stream and
  rule, the scores, the decisions in run-length form (``[[first frame,
  label], ...]``, frames counted from 0), the replay's CPU and wall seconds
  and a live decision's CPU time (median and 99th percentile, ms, over the
  stream's first decisions made one frame at a time), and the fraction of
  decisions that ran the classifier (``classified_fraction``, over all of
  the stream's decisions; ``live_classified_fraction``, over the timed
  ones: a gate deciding idle, or a rule waiting for frames, skips the
  classifier, so their CPU is a skipped decision's);
- ``probabilities``: whether the fitted method gave graded probabilities
  (:func:`graded_probabilities`: read from the probabilities of the windows
  it classified in the replays; None when it classified none), so that a
  report can tell rules that could not differ from rules that did not;
- with inner folds, ``choice`` (:func:`choose_rule`: the chosen rule's index,
  each rule's inner mean frame accuracy and false activations per idle
  minute) and ``default_rule`` (that rule's declaration: what ``touchbench
  train`` would make a model's default the same way); without them the
  default is :data:`touchbench.streams.rules.DEFAULT_RULE`;
- a predictions table with one row per test capture: the first rule's
  decision held over most of the frames where the capture is shown (the
  segment's majority); the row's ``accuracy`` is over those captures, so the
  capture-level columns of a stream evaluation read "the segments, decided
  live".
"""

from __future__ import annotations

import json
import time
from collections import Counter
from dataclasses import replace
from typing import Any, Sequence

import numpy as np

from ..classifiers.base import CLASSIFIERS
from ..scoring.streams import score_stream
from ..methods.base import MethodSpec
from ..methods.fitting import fit_method
from ..streams.replay import LiveSpec, stream_samples, training_samples
from ..streams.replay import replay as replay_stream
from ..streams.rules import make_rule
from ..streams.timeline import Stream, decisions_per_frame, label_runs, rest_value, stream_frames

__all__ = ["UNDECIDED", "choose_rule", "pick_rule", "fit_live", "fitted_rules", "graded_probabilities", "live_outcome", "live_samples", "with_idle"]

#: the label of the frames before a stream's first decision (scored as idle)
UNDECIDED = "undecided"


def with_idle(spec: MethodSpec, idle: str) -> MethodSpec:
    """``spec`` with the stream's idle class given to an estimator that takes one (``idle`` among its
    registered defaults) and was not given one."""
    defaults = CLASSIFIERS.entry(spec.estimator).tags.get("defaults") or {}
    if "idle" not in defaults or spec.estimator_params.get("idle") is not None:
        return spec
    return replace(spec, estimator_params={**spec.estimator_params, "idle": idle})


def live_samples(ds: Any, y: np.ndarray, rows: Any, live: LiveSpec, train_streams: Sequence[Stream],
                 ) -> tuple[list[np.ndarray], np.ndarray, np.ndarray]:
    """The samples a fold trains on (``live.train_on``), with their labels and groups: from the training
    ``rows``' captures, or from ``train_streams``."""
    groups = ds.meta["subject"].astype(str).to_numpy()
    if live.train_on == "streams":
        made = [(*stream_frames(ds.captures, y, s, live.idle, rest_value(ds.sensor)), s.subject) for s in train_streams]
        return stream_samples(made, live, ds.sensor.frame_rate)
    return training_samples([ds.captures[i] for i in rows], y[rows], groups[rows], live, ds.sensor.frame_rate)


def fit_live(spec: MethodSpec, seed: int | None, ds: Any, y: np.ndarray, rows: Any, live: LiveSpec,
             train_streams: Sequence[Stream]) -> Any:
    """The method fitted on the training ``rows`` as the fold trains it (:func:`live_samples`)."""
    X, yy, gg = live_samples(ds, y, rows, live, train_streams)
    return fit_method(with_idle(spec, live.idle), seed, X, yy, gg, sensor=ds.sensor)


def fitted_rules(live: LiveSpec, ds: Any, y: np.ndarray, rows: Any) -> list:
    """Every declared rule, fitted on the training ``rows``' captures (the gate's level)."""
    return [make_rule(r).fit([ds.captures[i] for i in rows], y[rows], ds.sensor) for r in live.rules]


def live_outcome(task: Any, ds: Any, y: np.ndarray) -> tuple[dict[str, Any], np.ndarray, str]:
    """Fit, replay and score one stream task: ``(row values, each test capture's label, live JSON)``."""
    fold = task.fold
    live = fold.extra(LiveSpec)
    assert live is not None, "a stream task's fold carries its stream settings"
    t0 = time.perf_counter()
    fitted = fit_live(task.method.spec, task.seed, ds, y, fold.train, live, live.train_streams)
    row: dict[str, Any] = {"fit_seconds": time.perf_counter() - t0, "n_classes_train": int(len(fitted.classes))}
    rules = fitted_rules(live, ds, y, fold.train)
    streams, first_rule, graded = [], [], []
    for s in live.streams:
        per_rule, decided, truth, g = _replayed(fitted, rules, ds, y, s, live, timed=True)
        graded.append(g)
        first_rule.append((s, decided[0]))
        streams.append({"name": s.name, "subject": s.subject, "session": s.session, "source": s.source,
                        "frames": int(len(truth)), "truth": label_runs(truth), "results": per_rule})
    payload = {"rules": [r.describe() for r in rules], "idle": live.idle, "frame_rate": float(ds.sensor.frame_rate),
               "windows_s": list(live.windows_s), "hop_s": live.hop_s, "train_on": live.train_on,
               "probabilities": True if True in graded else False if False in graded else None, "streams": streams}
    if live.inner:
        payload["choice"] = choose_rule(task.method.spec, task.seed, ds, y, live)
        payload["default_rule"] = payload["rules"][payload["choice"]["rule"]]
    labels = _segment_labels(fold.test, first_rule, {UNDECIDED, live.none_label}, live.idle)
    return row, labels, json.dumps(payload, default=float)


#: a window's best probability at least this close to 1 reads as a one-hot row
ONE_HOT_TOLERANCE = 1e-9


def graded_probabilities(replays: list[Any]) -> bool | None:
    """Whether the classifier gave graded probabilities on the windows it classified in ``replays``
    (one stream's, every rule's): True when some window's best class probability is below 1 (a row of
    probabilities summing to 1 that is not one-hot), False when every window's is 1, None when no
    window was classified (every decision gated, or waiting for frames).

    Read from the probabilities the rules received, not from the estimator's type: an estimator's
    ``predict_proba`` may be a one-hot of its prediction (aeon's MiniRocket, a ridge classifier), and
    one without ``predict_proba`` is given a one-hot
    (:meth:`touchbench.classifiers.fitting.FittedMethod.proba_rows`), so having the method says less
    than its values. With one-hot probabilities a threshold or an HMM decides as ``max`` does."""
    best = [w["probability"] for rp in replays for d in rp.decisions if d.classified for w in d.windows]
    if not best:
        return None
    return bool(min(best) < 1.0 - ONE_HOT_TOLERANCE)


def _fraction(flags: Any) -> float:
    a = np.asarray(flags, dtype=np.float64)
    return float(a.mean()) if a.size else float("nan")


def _replayed(fitted: Any, rules: list, ds: Any, y: np.ndarray, s: Stream, live: LiveSpec,
              timed: bool) -> tuple[list[dict[str, Any]], list[np.ndarray], np.ndarray, bool | None]:
    """One stream replayed with every rule and scored: one JSON-ready result per rule, each rule's
    decision per frame beside them, the stream's truth, and whether the probabilities were graded
    (:func:`graded_probabilities`)."""
    frames, truth = stream_frames(ds.captures, y, s, live.idle, rest_value(ds.sensor))
    classes = [str(c) for c in fitted.classes]
    replays = replay_stream(frames, fitted.window_proba, classes, ds.sensor, live, rules, timed=timed)
    scored = [_scored(rp, truth, ds.sensor.frame_rate, live) for rp in replays]
    return [r for r, _ in scored], [d for _, d in scored], truth, graded_probabilities(replays)


def pick_rule(accuracy: np.ndarray, false_per_min: np.ndarray, most: float) -> int:
    """The index of the rule with the best ``accuracy`` among those with ``false_per_min`` at most
    ``most``; when none is, the one with the fewest false activations (ties: the first). A NaN
    accuracy never wins over a number."""
    acc = np.where(np.isfinite(accuracy), accuracy, -np.inf)
    ok = np.flatnonzero(np.asarray(false_per_min) <= most)
    return int(ok[np.argmax(acc[ok])]) if ok.size else int(np.argmin(false_per_min))


def choose_rule(spec: MethodSpec, seed: int | None, ds: Any, y: np.ndarray, live: LiveSpec) -> dict[str, Any]:
    """The rule chosen on the fold's training side alone: for each inner fold the method is fitted on
    its training rows and its held-out streams replayed with every rule; per rule, the mean frame
    accuracy and the false activations per idle minute (pooled) over those streams. The choice is the
    best mean frame accuracy among the rules at most ``live.max_false_per_min``, else the rule with
    the fewest false activations (ties: the first declared)."""
    n = len(live.rules)
    acc: list[list[float]] = [[] for _ in range(n)]
    false, idle_min = np.zeros(n), 0.0
    for inner in live.inner:
        fitted = fit_live(spec, seed, ds, y, np.asarray(inner.train, dtype=np.int64), live, inner.train_streams)
        rules = fitted_rules(live, ds, y, np.asarray(inner.train, dtype=np.int64))
        for s in inner.streams:
            per_rule, _, _, _ = _replayed(fitted, rules, ds, y, s, live, timed=False)
            for k, r in enumerate(per_rule):
                acc[k].append(r["scores"]["frame_accuracy"])
                false[k] += r["scores"]["false_activations"]
            idle_min += per_rule[0]["scores"]["idle_seconds"] / 60.0
    mean_acc = np.array([float(np.mean(a)) if a else float("nan") for a in acc])
    fa = false / idle_min if idle_min > 0 else np.zeros(n)
    k = pick_rule(mean_acc, fa, live.max_false_per_min)
    return {"rule": k, "inner_folds": len(live.inner), "frame_accuracy": mean_acc.tolist(),
            "false_per_idle_min": fa.tolist(), "max_false_per_min": live.max_false_per_min}


def _scored(rp: Any, truth: np.ndarray, frame_rate: float, live: LiveSpec) -> tuple[dict[str, Any], np.ndarray]:
    """One stream's replay with one rule, scored: its scores, decisions (run-length) and CPU, and
    beside them the decision at every frame."""
    decided = decisions_per_frame([d.frame for d in rp.decisions], [d.label for d in rp.decisions], len(truth),
                                  UNDECIDED)
    scores = score_stream(truth, decided, live.idle, frame_rate, undecided=(UNDECIDED, live.none_label))
    live_cpu = rp.live_cpu_ms
    return ({"scores": scores.to_dict(), "decisions": label_runs(decided), "n_decisions": len(rp.decisions),
            "cpu_s": float(rp.decision_cpu_ms.sum()) / 1000.0, "wall_s": rp.wall_s,
            "decision_cpu_ms_p50": float(np.percentile(live_cpu, 50)) if live_cpu.size else float("nan"),
            "decision_cpu_ms_p99": float(np.percentile(live_cpu, 99)) if live_cpu.size else float("nan"),
            "classified_fraction": _fraction([d.classified for d in rp.decisions]),
            "live_classified_fraction": _fraction(rp.live_classified)}, decided)


def _segment_labels(test: np.ndarray, first_rule: list, idle_like: set[str], idle: str) -> np.ndarray:
    """Each test capture's label: the decision held over most of the frames where it is shown (the
    labels of ``idle_like``, the none label and the undecided frames, read as ``idle``; ties: the
    first of the tied labels shown)."""
    votes: dict[int, Counter] = {int(i): Counter() for i in test}
    for stream, decided in first_rule:
        at = 0
        for i, a, b in stream.segments:
            if int(i) in votes:
                votes[int(i)].update(idle if v in idle_like else str(v) for v in decided[at:at + (b - a)])
            at += b - a
    out = np.empty(len(test), dtype=object)
    for k, i in enumerate(test):
        c = votes[int(i)]
        out[k] = c.most_common(1)[0][0] if c else idle
    return out
