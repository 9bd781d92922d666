"""One task of a stream evaluation: train once, replay every test stream with every decision rule,
score each replay frame by frame.

The task (a fold of the ``stream`` scheme and a method) fits the method on
the fold's training captures, or on windows cut from them
(:func:`touchbench.streams.replay.training_samples`), fits each declared
decision rule on the same training captures (the gate's ``level: auto``),
then replays each test stream through the recogniser ``touchbench stream``
runs (:func:`touchbench.streams.replay.replay`: the windows due at every hop
classified in batches, the decisions those of stepping frame by frame) and
scores the decisions against each frame's truth
(:func:`touchbench.evaluation.stream_scores.score_stream`; the none label
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
- ``default_rule`` is not written here: when a task's payload carries it, it is
  the rule declaration ``touchbench stream`` would use for a model trained on
  the evaluation; without it, :data:`touchbench.streams.rules.DEFAULT_RULE`;
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
from typing import Any

import numpy as np

from ..evaluation.stream_scores import score_stream
from ..methods.fitting import fit_method
from ..protocols.schemes.stream import rule_specs
from ..streams.replay import LiveSpec, training_samples
from ..streams.replay import replay as replay_stream
from ..streams.rules import make_rule
from ..streams.timeline import decisions_per_frame, label_runs, rest_value, stream_frames

__all__ = ["UNDECIDED", "graded_probabilities", "live_outcome"]

#: the label of the frames before a stream's first decision (scored as idle)
UNDECIDED = "undecided"


def live_outcome(task: Any, ds: Any, y: np.ndarray) -> tuple[dict[str, Any], np.ndarray, str]:
    """Fit, replay and score one stream task: ``(row values, each test capture's label, live JSON)``."""
    fold, live = task.fold, task.fold.live
    groups = ds.meta["subject"].astype(str).to_numpy()
    train_caps = [ds.captures[i] for i in fold.train]
    X, yy, gg = training_samples(train_caps, y[fold.train], groups[fold.train], live, ds.sensor.frame_rate)
    t0 = time.perf_counter()
    fitted = fit_method(task.method.spec, task.seed, X, yy, gg, sensor=ds.sensor)
    row: dict[str, Any] = {"fit_seconds": time.perf_counter() - t0, "n_classes_train": int(len(fitted.classes))}
    rules = [make_rule(r).fit(train_caps, y[fold.train], ds.sensor) for r in rule_specs(live)]
    classes = [str(c) for c in fitted.classes]
    streams, first_rule, graded = [], [], []
    for s in live.streams:
        frames, truth = stream_frames(ds.captures, y, s, live.idle, rest_value(ds.sensor))
        replays = replay_stream(frames, fitted.window_proba, classes, ds.sensor, live, rules)
        graded.append(graded_probabilities(replays))
        per_rule = [_scored(rp, truth, ds.sensor.frame_rate, live) for rp in replays]
        first_rule.append((s, per_rule[0].pop("_decided")))
        for r in per_rule[1:]:
            r.pop("_decided")
        streams.append({"name": s.name, "subject": s.subject, "session": s.session, "source": s.source,
                        "frames": int(len(truth)), "truth": label_runs(truth), "results": per_rule})
    payload = {"rules": [r.describe() for r in rules], "idle": live.idle, "frame_rate": float(ds.sensor.frame_rate),
               "windows_s": list(live.windows_s), "hop_s": live.hop_s, "train_on": live.train_on,
               "probabilities": True if True in graded else False if False in graded else None, "streams": streams}
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


def _scored(rp: Any, truth: np.ndarray, frame_rate: float, live: LiveSpec) -> dict[str, Any]:
    """One stream's replay with one rule, scored: its scores, decisions and CPU."""
    decided = decisions_per_frame([d.frame for d in rp.decisions], [d.label for d in rp.decisions], len(truth),
                                  UNDECIDED)
    scores = score_stream(truth, decided, live.idle, frame_rate, undecided=(UNDECIDED, live.none_label))
    live_cpu = rp.live_cpu_ms
    return {"scores": scores.to_dict(), "decisions": label_runs(decided), "n_decisions": len(rp.decisions),
            "cpu_s": float(rp.decision_cpu_ms.sum()) / 1000.0, "wall_s": rp.wall_s,
            "decision_cpu_ms_p50": float(np.percentile(live_cpu, 50)) if live_cpu.size else float("nan"),
            "decision_cpu_ms_p99": float(np.percentile(live_cpu, 99)) if live_cpu.size else float("nan"),
            "classified_fraction": _fraction([d.classified for d in rp.decisions]),
            "live_classified_fraction": _fraction(rp.live_classified),
            "_decided": decided}


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
