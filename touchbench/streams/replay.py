"""Replaying streams through a fitted recogniser: what a stream evaluation's task does between
training and scoring.

- :class:`LiveSpec`: what a fold of the ``stream`` scheme carries: its test
  streams, the idle class, the recogniser's windows and hop, the decision
  rules to compare, how the method is trained (on whole captures; on
  windows of the recogniser's lengths cut from them, each labelled with its
  capture's label, as ``touchbench train --window`` does; or on windows cut
  from the training streams the way the recogniser meets them, each
  labelled with the truth of its last frame: across onsets, transitions and
  real idle stretches) and, when the rule is chosen inside the fold, its
  inner folds (:class:`InnerFold`);
- :func:`training_samples`: those training samples;
- :func:`replay`: one stream through a :class:`WindowRecognizer`, as fast as
  the recogniser goes (the windows due at every hop classified in batches:
  the same decisions as frame by frame), with the decisions, the CPU time of
  the replay, and the CPU time of a decision made live (the first ones made
  again one frame at a time).
"""

from __future__ import annotations

import hashlib
import time
from dataclasses import dataclass, field
from typing import Any, Callable, Sequence

import numpy as np

from ..core.folds import FoldExtra
from ..datasets.windows import cut_windows, seconds_to_frames
from .recognizer import Decision, WindowRecognizer
from .rules import DecisionRule, RuleSpec
from .timeline import Stream

__all__ = ["InnerFold", "LiveSpec", "Replayed", "replay", "stream_samples", "training_samples", "window_samples"]


@dataclass(frozen=True)
class InnerFold:
    """One inner fold of a stream fold's training side, for choosing the rule there: the rows it
    trains on, the streams it replays (of the held-out training subjects or sessions) and, when the
    method trains on streams, the streams of its training rows."""

    train: tuple[int, ...]
    streams: tuple[Stream, ...]
    train_streams: tuple[Stream, ...] = ()

    def digest(self) -> str:
        return repr((self.train, tuple(s.digest() for s in self.streams), tuple(s.digest() for s in self.train_streams)))


@dataclass(frozen=True)
class LiveSpec(FoldExtra):
    """A stream fold's settings and streams (module docstring): the ``stream`` scheme's fold extra."""

    streams: tuple[Stream, ...]
    idle: str
    windows_s: tuple[float, ...]
    hop_s: float
    train_on: str  # "windows", "captures" or "streams"
    train_hop_s: float | None
    rules: tuple[RuleSpec, ...]  # each rule's validated declaration
    none_label: str
    train_streams: tuple[Stream, ...] = ()  # the training side as streams (train_on: streams)
    inner: tuple[InnerFold, ...] = ()  # inner folds choosing the rule (none: no choice)
    max_false_per_min: float = 5.0  # the choice's limit on false activations per idle minute

    def digest(self) -> str:
        """What the fold's results depend on beyond its indices (task identities)."""
        rules = tuple(r.canonical for r in self.rules)
        parts = (self.idle, self.windows_s, self.hop_s, self.train_on, self.train_hop_s, rules,
                 self.none_label, tuple(s.digest() for s in self.streams))
        if self.train_streams or self.inner:
            parts += (tuple(s.digest() for s in self.train_streams), tuple(f.digest() for f in self.inner),
                      self.max_false_per_min)
        return hashlib.sha256(repr(parts).encode()).hexdigest()[:16]

    def identity(self) -> dict[str, Any]:
        return {"live": self.digest()}


def window_samples(captures: Sequence[np.ndarray], windows_s: Sequence[float], train_hop_s: float | None,
                   frame_rate: float, options: tuple[str, str] = ("--window", "--train-hop"),
                   ) -> tuple[list[np.ndarray], np.ndarray, list[int], list[int]]:
    """Windows of each length (``windows_s``, rounded to frames) cut every ``train_hop_s`` (default
    half the window) from each capture (a capture shorter than every window kept whole): ``(windows,
    the capture each comes from, lengths, hops)``. ``touchbench train --window`` and a stream task
    train on these; ``options`` names the settings in an error."""
    lengths = [seconds_to_frames(w, frame_rate, options[0]) for w in windows_s]
    hops = [seconds_to_frames(train_hop_s, frame_rate, options[1]) if train_hop_s is not None else max(1, L // 2)
            for L in lengths]
    samples, src = cut_windows(captures, lengths, hops)
    return samples, src, lengths, hops


def training_samples(captures: Sequence[np.ndarray], labels: np.ndarray, groups: np.ndarray, spec: LiveSpec,
                     frame_rate: float) -> tuple[list[np.ndarray], np.ndarray, np.ndarray]:
    """The samples a stream fold trains on, with their labels and groups: the captures, or
    :func:`window_samples` of the recogniser's lengths (for ``train_on: streams``, see
    :func:`stream_samples`)."""
    if spec.train_on == "captures":
        return list(captures), labels, groups
    windows, src, _, _ = window_samples(captures, spec.windows_s, spec.train_hop_s, frame_rate,
                                        ("windows_s", "train_hop_s"))
    return windows, np.asarray(labels)[src], np.asarray(groups)[src]


def stream_samples(streams: Sequence[tuple[np.ndarray, np.ndarray, str]], spec: LiveSpec, frame_rate: float,
                   ) -> tuple[list[np.ndarray], np.ndarray, np.ndarray]:
    """Training samples cut from streams the way the recogniser meets them: for each ``(frames,
    truth, group)`` and each window length of ``spec``, the window ending at every ``train_hop_s``
    (default: the recogniser's hop) from the first frame at which it is full, labelled with the truth
    of its last frame (the frame a decision made then is scored on), its group the stream's. Windows
    are views of the stream's frames."""
    hop = seconds_to_frames(spec.train_hop_s if spec.train_hop_s is not None else spec.hop_s, frame_rate,
                            "train_hop_s")
    samples, labels, groups = [], [], []
    for frames, truth, group in streams:
        for w in spec.windows_s:
            L = seconds_to_frames(w, frame_rate, "windows_s")
            ends = np.arange(L, len(frames) + 1, hop)
            samples.extend(frames[e - L:e] for e in ends)
            labels.extend(str(truth[e - 1]) for e in ends)
            groups.extend([group] * len(ends))
    return samples, np.asarray(labels, dtype=object), np.asarray(groups, dtype=object)


#: the decisions of a stream stepped one frame at a time, as live, to measure a live decision's CPU
LIVE_SAMPLE = 100


@dataclass
class Replayed:
    """One stream's replay with one rule: its decisions; each decision's CPU ms as the replay spent it
    (its share of its windows' batch, and the rule); the CPU ms of the first :data:`LIVE_SAMPLE`
    decisions made one frame at a time, as ``touchbench stream`` makes them; the replay's CPU and wall
    seconds (every rule's, the probabilities computed once); whether each of those timed decisions ran
    the classifier (a gate deciding idle, or a rule waiting for frames, skips it)."""

    decisions: list[Decision]
    decision_cpu_ms: np.ndarray
    live_cpu_ms: np.ndarray
    cpu_s: float
    wall_s: float
    live_classified: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=bool))


def replay(frames: np.ndarray, proba: Callable[[list[np.ndarray]], np.ndarray], classes: Sequence[str], sensor: Any,
           spec: LiveSpec, rules: Sequence[DecisionRule], timed: bool = True) -> list[Replayed]:
    """``frames`` through a recogniser of ``spec``'s windows and hop deciding with every rule of
    ``rules`` (:meth:`WindowRecognizer.replay`: the windows due at every hop classified in batches),
    one :class:`Replayed` per rule; then, when ``timed``, the first decisions again, one frame at a
    time, timed (an inner fold choosing the rule does not time them)."""
    def recogniser() -> WindowRecognizer:
        return WindowRecognizer(proba, classes, sensor, spec.windows_s, dtype=frames.dtype, hop_s=spec.hop_s,
                                none_label=spec.none_label, rule=rules)

    c_start, w_start = time.thread_time_ns(), time.perf_counter()
    decided = recogniser().replay(frames)
    cpu_s, wall_s = (time.thread_time_ns() - c_start) / 1e9, time.perf_counter() - w_start
    live: list[list[Decision]] = [[] for _ in rules]
    rec = recogniser()
    for frame in frames if timed else ():
        for k, d in enumerate(rec.step(frame) or ()):
            live[k].append(d)
        if len(live[0]) >= LIVE_SAMPLE:
            break
    return [Replayed(ds, np.array([d.cpu_ms for d in ds], dtype=np.float64),
                     np.array([d.cpu_ms for d in lv], dtype=np.float64), cpu_s, wall_s,
                     np.array([d.classified for d in lv], dtype=bool)) for ds, lv in zip(decided, live)]
