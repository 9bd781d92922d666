"""Sliding windows over a stream of frames -> decisions: the one recogniser that
``touchbench stream`` runs live and a stream evaluation replays.

Flagg (2012, section 4.5, "Future Work") asks for "continuous gesture
recognition that works with ongoing sequences of data, rather than
fixed-length windows", "buffering in 2-second periods", "a few buffers of
different length simultaneously", and "confidence estimates, so that the
model is not forced to classify everything it sees in terms of its known
gesture types". Here:

- :class:`WindowRecognizer` keeps the last frames; once the shortest window
  is full, and then every ``hop`` frames, it asks its ``proba`` function for
  the class probabilities of the last ``L`` frames for every window length
  ``L`` already full, in one batch, and combines them
  (:func:`combine_windows`);
- the combined probabilities go to the decision rule
  (:mod:`touchbench.streams.rules`; default ``max``: the best class, or the
  none label when its probability is under the rule's threshold);
- a decision's latency is the time from the arrival of the frame that
  completed the hop to the decision being ready (features of every window,
  classifier, combination, rule).

The recogniser knows nothing of model files: it takes a function from a
list of windows to an ``(n, C)`` probability array over ``classes``
(``touchbench.deploy.stream`` gives a model file's; a stream evaluation
gives the fitted method of its task), so live labelling and a scored
replay run the same code on the same frames.

Combining windows (interpretations; the thesis gives no more detail): the
decision is the most confident window's (``combine="max"``: the window whose
best class probability is highest, so a short gesture is not outvoted by a
long window that mostly saw something else), or the mean of the windows'
probabilities (``combine="mean"``).
"""

from __future__ import annotations

import json
import math
import time
from dataclasses import asdict, dataclass, field
from typing import Any, Callable, Iterable, Iterator, Sequence

import numpy as np

from ..core.errors import TouchbenchError
from ..datasets.model import SensorSpec
from ..datasets.windows import seconds_to_frames
from .rules import DecisionRule, MaxRule

__all__ = ["COMBINE", "Decision", "WindowRecognizer", "combine_windows", "decide_all"]

COMBINE = ("max", "mean")


def combine_windows(P: np.ndarray, how: str = "max") -> tuple[np.ndarray, int | None]:
    """One probability row from the rows of ``P`` (one per window).

    ``max``: the row of the window whose best probability is highest (ties:
    the first, that is the shortest when rows are ordered by length), and
    its index. ``mean``: the mean row, and None.
    """
    P = np.asarray(P, dtype=np.float64)
    if how == "max":
        k = int(np.argmax(P.max(axis=1)))
        return P[k], k
    if how == "mean":
        return P.mean(axis=0), None
    raise ValueError(f"unknown combination {how!r} (known: {', '.join(COMBINE)})")


@dataclass
class Decision:
    frame: int  # frames received when the decision was made (1-based count: the 10th frame is 10)
    t: float  # stream time of that frame, seconds (frame / frame rate)
    label: str  # the decided class, or the none label
    probability: float  # the best class's probability (also when under the threshold)
    best: str  # the best class, even when the decision is "none"
    window_s: float | None  # the deciding window (combine="max"), None for "mean"
    latency_ms: float
    cpu_ms: float = float("nan")  # CPU time of this thread for the decision (features, classifier, rule)
    windows: list[dict[str, Any]] = field(default_factory=list)  # per window: length, best class, probability
    classified: bool = True  # whether the classifier ran for it (False: a gate, or a rule waiting for frames)

    def to_json(self) -> str:
        return json.dumps(asdict(self), default=float)

    def to_text(self) -> str:
        w = f"window {self.window_s:g} s" if self.window_s is not None else "mean of windows"
        return f"{self.t:8.3f} s  {self.label:12s} {self.probability:5.2f}  ({w}, {self.latency_ms:.2f} ms)"


class WindowRecognizer:
    """Sliding windows over incoming frames -> decisions (module docstring).

    ``proba(windows)`` gives an ``(n, C)`` array over ``classes``; ``windows_s``
    are the window lengths in seconds, rounded to whole frames at the
    sensor's frame rate; ``dtype`` is the frames' type (the training
    captures'); ``rule`` decides from the combined probabilities (default:
    :class:`touchbench.streams.rules.MaxRule` with ``threshold``), or several rules do, each
    from the same probabilities (:meth:`step`; :meth:`push` gives the first rule's decision).
    """

    def __init__(self, proba: Callable[[list[np.ndarray]], np.ndarray], classes: Sequence[str], sensor: SensorSpec,
                 windows_s: Iterable[float], *, dtype: Any = np.float64, hop_s: float = 0.5,
                 threshold: float = 0.5, combine: str = "max", none_label: str = "none",
                 rule: DecisionRule | Sequence[DecisionRule] | None = None,
                 buffer_check: Callable[..., None] | None = None):
        self.proba = proba
        self.sensor = sensor
        self.frame_rate = float(sensor.frame_rate)
        self.windows_s = sorted(float(w) for w in windows_s)
        if not self.windows_s:
            raise TouchbenchError("give at least one window length")
        self.lengths = [seconds_to_frames(w, self.frame_rate, "--window") for w in self.windows_s]
        self.hop = seconds_to_frames(hop_s, self.frame_rate, "--hop")
        if not 0.0 <= threshold <= 1.0:
            raise TouchbenchError(f"threshold must be in [0, 1], got {threshold}")
        if combine not in COMBINE:
            raise TouchbenchError(f"unknown --combine {combine!r} (known: {', '.join(COMBINE)})")
        classes = [str(c) for c in classes]
        if none_label in classes:
            raise TouchbenchError(f"the none label {none_label!r} is one of the model's classes; choose another")
        self.classes = np.array(classes, dtype=object)
        self.threshold = float(threshold)
        self.combine = combine
        self.none_label = none_label
        rules = [MaxRule(threshold=self.threshold)] if rule is None else (
            [rule] if isinstance(rule, DecisionRule) else list(rule))
        if not rules:
            raise TouchbenchError("give at least one decision rule")
        for r in rules:
            r.start(self.classes, none_label, self.frame_rate, sensor)
            r.set_hop(self.hop)
        self.rules = rules
        self.dtype = np.dtype(dtype)
        self.grid = sensor.grid
        self._cap = 2 * max(self.lengths)
        if buffer_check is not None:
            buffer_check(self._cap, self.grid, self.dtype, self.frame_rate)
        self._buf = np.zeros((self._cap, *self.grid), dtype=self.dtype)
        self._n = 0  # frames in the buffer
        self.seen = 0  # frames seen in total

    def warm_up(self) -> None:
        """Classify one window of each length once (constant frames at the sensor's minimum), so
        that one-off costs (imports, the forest's flat arrays) do not count as a decision's latency."""
        lo = self.sensor.value_range[0]
        self.proba([np.full((L, *self.grid), lo, dtype=self.dtype) for L in self.lengths])

    def push(self, frame: np.ndarray, arrived: float | None = None) -> Decision | None:
        """Add one ``(H, W)`` frame; the first rule's :class:`Decision` when one is due, else None."""
        out = self.step(frame, arrived)
        return None if out is None else out[0]

    def step(self, frame: np.ndarray, arrived: float | None = None) -> list[Decision] | None:
        """Add one ``(H, W)`` frame; when a decision is due, one :class:`Decision` per rule (the
        windows' probabilities computed once, when a rule needs them), else None."""
        arrived = time.perf_counter() if arrived is None else arrived
        if self._n == self._cap:
            keep = max(self.lengths) - 1
            self._buf[:keep] = self._buf[self._n - keep:self._n]
            self._n = keep
        self._buf[self._n] = frame
        self._n += 1
        self.seen += 1
        first = self.lengths[0]
        if self.seen < first or (self.seen - first) % self.hop:
            return None
        full = [(w, L) for w, L in zip(self.windows_s, self.lengths) if self.seen >= L]
        plans = self._plan(self._buf[self._n - full[-1][1]:self._n], full)
        probas: dict[tuple, tuple[np.ndarray, float]] = {}  # windows -> their probabilities, computed once
        for _, windows in plans:
            if windows and tuple(windows) not in probas:
                c0 = time.thread_time_ns()
                P = np.asarray(self.proba([self._buf[self._n - L:self._n] for _, L in windows]), dtype=np.float64)
                probas[tuple(windows)] = (P, (time.thread_time_ns() - c0) / 1e6)
        return [self._decide(rule, gated, *probas.get(tuple(windows), (None, 0.0)), windows, arrived)
                for rule, (gated, windows) in zip(self.rules, plans)]

    def _plan(self, newest: np.ndarray, full: list[tuple[float, int]]) -> list[tuple[str | None, list]]:
        """What each rule needs at this decision, from the newest frames (the longest full window's):
        ``(label decided from the frames alone, None)`` or ``(None, the windows to classify)``."""
        out = []
        for rule in self.rules:
            gated = rule.gate(newest) if rule.gates else None
            wanted = None if gated is not None else rule.window_lengths(newest, [L for _, L in full])
            windows = [] if gated is not None else full if wanted is None else [(L / self.frame_rate, L) for L in wanted]
            if gated is None and not windows:
                gated = self.none_label  # the rule wants more frames before it decides
            out.append((gated, windows))
        return out

    def replay(self, frames: np.ndarray, batch: int = 256) -> list[list[Decision]]:
        """Every decision of a recorded stream ``frames`` (from a fresh recogniser), one list per rule:
        the decisions :meth:`step` would make frame by frame, the windows due at every hop classified
        ``batch`` at a time (the features and the classifier of a window do not depend on the other
        windows of its batch), then each rule deciding in order. A decision's ``cpu_ms`` is its share
        of its windows' batch and its rule's own time; ``latency_ms`` is not measured (NaN)."""
        due = np.arange(self.lengths[0], len(frames) + 1, self.hop)
        plans = []
        for s in due:
            full = [(w, L) for w, L in zip(self.windows_s, self.lengths) if s >= L]
            plans.append(self._plan(frames[s - full[-1][1]:s], full))
        wanted = sorted({(int(s), L) for s, plan in zip(due, plans) for _, ws in plan for _, L in ws})
        rows, cpu = self._batched_proba(frames, wanted, batch)
        out: list[list[Decision]] = [[] for _ in self.rules]
        for s, plan in zip(due, plans):
            self.seen = int(s)
            for k, (rule, (gated, windows)) in enumerate(zip(self.rules, plan)):
                P = np.stack([rows[(int(s), L)] for _, L in windows]) if windows else None
                out[k].append(self._decide(rule, gated, P, sum(cpu[(int(s), L)] for _, L in windows), windows,
                                           math.nan))
        return out

    def _batched_proba(self, frames: np.ndarray, wanted: list[tuple[int, int]], batch: int):
        """The probabilities of every window ``(end frame, length)`` of ``wanted``, classified ``batch``
        windows of one length at a time, and each window's share of its batch's CPU ms."""
        rows: dict[tuple[int, int], np.ndarray] = {}
        cpu: dict[tuple[int, int], float] = {}
        for L in sorted({L for _, L in wanted}):
            keys = [k for k in wanted if k[1] == L]
            for a in range(0, len(keys), batch):
                part = keys[a:a + batch]
                c0 = time.thread_time_ns()
                P = np.asarray(self.proba([frames[s - L:s] for s, _ in part]), dtype=np.float64)
                share = (time.thread_time_ns() - c0) / 1e6 / len(part)
                for key, row in zip(part, P):
                    rows[key], cpu[key] = row, share
        return rows, cpu

    def _decide(self, rule: DecisionRule, gated: str | None, P: np.ndarray | None, proba_cpu: float, full: list,
                arrived: float) -> Decision:
        """One rule's decision from the windows' probabilities ``P`` (or its gate's label ``gated``, decided
        from the frames alone: no classifier ran for it); its CPU time adds the probabilities' when it used them."""
        c0 = time.thread_time_ns()
        if gated is not None:
            P, full = (self.classes == gated).astype(np.float64)[None, :], full[:1]
            if not full:  # the rule wants more frames: no window was classified
                full = [(self.windows_s[0], self.lengths[0])]
        p, k = combine_windows(P, self.combine)
        best = int(np.argmax(p))
        label = gated if gated is not None else rule.decide(p)
        cpu = (time.thread_time_ns() - c0) / 1e6 + (proba_cpu if gated is None else 0.0)
        per = [{"window_s": w, "label": str(self.classes[int(np.argmax(P[i]))]), "probability": float(P[i].max())}
               for i, (w, _) in enumerate(full)]
        return Decision(frame=self.seen, t=self.seen / self.frame_rate, label=label, probability=float(p[best]),
                        best=str(self.classes[best]) if p[best] > 0 else label,
                        window_s=None if k is None else full[k][0],
                        latency_ms=1000.0 * (time.perf_counter() - arrived) if math.isfinite(arrived) else math.nan,
                        cpu_ms=cpu, windows=per, classified=gated is None)


def decide_all(recognizer: WindowRecognizer, frames: Iterable[tuple[np.ndarray, float]]) -> Iterator[Decision]:
    """Feed ``(frame, arrival time)`` pairs to ``recognizer``, yielding each decision as it is made:
    the loop ``touchbench stream`` runs live and a stream evaluation replays."""
    for frame, arrived in frames:
        d = recognizer.push(frame, arrived)
        if d is not None:
            yield d
