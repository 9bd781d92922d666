"""Scores of a live recognition stream: per-frame truth against the recogniser's standing decision.

The input is two equal-length sequences of class labels, one per frame: the true class of each
frame (one class is the idle class, e.g. HAART's ``notouch``) and the decision standing at that
frame (the last decision the recogniser made at or before it, expanded to frames by the caller).
Frames before the first decision carry an *undecided* label; every label of ``undecided`` is
scored as the idle class (the recogniser has claimed no gesture there), so ``d`` below is the
decision with those labels replaced by ``idle``. A caller that wants the recogniser's
under-threshold "none" label scored as idle passes it in ``undecided`` too.

Scores (:func:`score_stream` gives them all):

- frame scores (:func:`frame_scores`): accuracy and balanced accuracy, always beside the idle-only
  baseline (idle answered at every frame), gesture-frame and idle-frame recall;
- the segment (frame) errors of Ward, Lukowicz & Gellersen (2011) (:func:`segment_errors`);
- their event errors (:func:`event_errors`);
- time to decision and accuracy at fixed times after onset (:func:`decision_timing`);
- false activations per minute of idle (:func:`false_activations`).

Reference: J. A. Ward, P. Lukowicz, H. W. Gellersen, "Performance metrics for activity
recognition", ACM Trans. Intell. Syst. Technol. 2(1), article 6, 2011
(doi:10.1145/1889681.1889687): the segments and their error categories (insertion, merge,
overfill; deletion, fragmentation, underfill; substitution in the multi-class case), the frame
totals of those categories (their error division diagram) and the event analysis (their event
analysis diagram: C, D, F, M, FM; C, I', F', M', FM'). They are defined there for one class
against the rest (the NULL class: here the idle class); the multi-class reading used here is
stated in each function.

Events: a ground-truth event is a maximal run of frames with the same non-idle true label; a
returned event is a maximal run of frames with the same non-idle decision. Degenerate input has
defined values: an empty stream gives NaN for every rate and 0 for every count; a stream without
gesture events gives zero event counts, NaN times to decision and a defined false-activation rate.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field

import numpy as np

from touchbench.core.errors import DataError
from touchbench.scoring.metrics import metrics

__all__ = ["SEGMENT_KINDS", "TRUTH_EVENT_KINDS", "RETURN_EVENT_KINDS", "FrameScores", "SegmentErrors",
           "EventErrors", "DecisionTiming", "StreamScores", "prepare", "runs", "frame_scores",
           "segment_errors", "event_errors", "decision_timing", "false_activations", "score_stream"]

#: the kinds of segment, each frame has exactly one (Ward et al. 2011, segment error categories;
#: substitution: their multi-class case). "correct" is a true positive of a gesture class,
#: "correct_idle" a true negative.
SEGMENT_KINDS = ("correct", "correct_idle", "substitution", "insertion", "merge", "overfill_start",
                 "overfill_end", "deletion", "fragmentation", "underfill_start", "underfill_end")
#: ground-truth event kinds (Ward et al. 2011, event analysis): C, D, F, M, FM
TRUTH_EVENT_KINDS = ("correct", "deleted", "fragmented", "merged", "fragmented_merged")
#: returned event kinds (Ward et al. 2011, event analysis): C, I', F', M', FM'
RETURN_EVENT_KINDS = ("correct", "inserted", "fragmenting", "merging", "fragmenting_merging")

_NAN = float("nan")
_EPS = 1e-9  # onset + t on a frame boundary (0.3 s at 10 Hz) is that frame, not the one before


def prepare(truth: Sequence[str] | np.ndarray, decided: Sequence[str] | np.ndarray, idle: str,
            undecided: str | Iterable[str] = ("undecided",)) -> tuple[np.ndarray, np.ndarray]:
    """The truth and the decisions as string arrays, the ``undecided`` labels of the decisions
    replaced by ``idle`` (they count as idle for every score). Raises :class:`DataError` when the
    two are not one-dimensional sequences of the same length, or an undecided label is a true
    class other than the idle one."""
    t = np.asarray(truth).astype(str)
    d = np.asarray(decided).astype(str)
    if t.ndim != 1 or d.ndim != 1 or len(t) != len(d):
        raise DataError(f"stream scores need one truth label and one decision per frame: "
                        f"{len(t) if t.ndim == 1 else t.shape} truth labels, "
                        f"{len(d) if d.ndim == 1 else d.shape} decisions")
    labels = {undecided} if isinstance(undecided, str) else set(map(str, undecided))
    labels.discard(str(idle))
    clash = sorted(labels & set(np.unique(t).tolist()))
    if clash:
        raise DataError(f"the undecided label {clash[0]!r} is also a true class of the stream; "
                        "choose another")
    if labels:
        d = np.where(np.isin(d, sorted(labels)), str(idle), d)
    return t, d


def runs(*labels: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The maximal runs over which none of the (equal-length) label sequences changes:
    (start, stop) frame indices, stop exclusive."""
    n = len(labels[0])
    if not n:
        return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
    change = np.flatnonzero(np.any([x[1:] != x[:-1] for x in labels], axis=0)) + 1
    starts = np.concatenate([[0], change]).astype(np.int64)
    stops = np.concatenate([change, [n]]).astype(np.int64)
    return starts, stops


def _events(labels: np.ndarray, idle: str) -> tuple[np.ndarray, np.ndarray]:
    """The events of one label sequence: maximal runs of the same non-idle label."""
    starts, stops = runs(labels)
    keep = labels[starts] != idle if len(starts) else np.zeros(0, dtype=bool)
    return starts[keep], stops[keep]


def _ratio(num: float, den: float) -> float:
    return float(num) / float(den) if den else _NAN


@dataclass
class FrameScores:
    """Frame-by-frame scores beside the idle-only baseline (see :func:`frame_scores`)."""
    accuracy: float = _NAN
    balanced_accuracy: float = _NAN
    idle_baseline_accuracy: float = _NAN
    idle_baseline_balanced_accuracy: float = _NAN
    gesture_recall: float = _NAN
    idle_recall: float = _NAN


def frame_scores(t: np.ndarray, d: np.ndarray, idle: str) -> FrameScores:
    """Accuracy (frames whose decision equals the truth / frames) and balanced accuracy (mean
    per-class recall over the classes present in the truth, the idle class included:
    :func:`touchbench.scoring.metrics.metrics`), each beside the same score of the idle-only
    baseline, which answers idle at every frame (its accuracy is the idle share of the frames,
    its balanced accuracy 1 / number of true classes when idle is one of them, else 0).
    Gesture-frame recall: frames with a non-idle truth whose decision equals it / frames with a
    non-idle truth; idle-frame recall: idle frames decided idle / idle frames. NaN where the
    denominator is 0 (every score of an empty stream)."""
    if not len(t):
        return FrameScores()
    ours = metrics(t, d)
    base = metrics(t, np.full(len(t), idle))
    gesture = t != idle
    return FrameScores(
        accuracy=ours["accuracy"], balanced_accuracy=ours["balanced_accuracy"],
        idle_baseline_accuracy=base["accuracy"], idle_baseline_balanced_accuracy=base["balanced_accuracy"],
        gesture_recall=_ratio(np.sum((d == t) & gesture), np.sum(gesture)),
        idle_recall=_ratio(np.sum((d == idle) & ~gesture), np.sum(~gesture)))


@dataclass
class SegmentErrors:
    """Per segment kind (:data:`SEGMENT_KINDS`): the number of segments and of frames."""
    counts: dict[str, int] = field(default_factory=lambda: dict.fromkeys(SEGMENT_KINDS, 0))
    frames: dict[str, int] = field(default_factory=lambda: dict.fromkeys(SEGMENT_KINDS, 0))


def segment_errors(t: np.ndarray, d: np.ndarray, idle: str) -> SegmentErrors:
    """Ward et al. (2011), segment error categories: a segment is a maximal run of frames over
    which neither the truth nor the decision changes; each gets one kind, and the frames of each
    kind are totalled (their error division diagram).

    In the two-class case a false-positive segment (decision positive, truth NULL) is an
    insertion when neither neighbouring segment is a true positive, a merge when both are, an
    overfill at the start (Oα) when only the next one is and at the end (Oω) when only the
    previous one is; a false-negative segment (truth positive, decision NULL) is likewise a
    deletion, fragmentation, underfill at the start (Uα) or at the end (Uω). Multi-class reading
    used here: a segment whose truth and decision are both gestures of different classes is a
    substitution; the class of an error segment is its one gesture label (the decision's of a
    false positive, the truth's of a false negative), and a neighbour counts as a true positive
    only when it is a correct segment *of that class*. The stream's two ends count as non-true-
    positive neighbours. Every frame lies in one segment, so the frame totals sum to the length.
    """
    out = SegmentErrors()
    starts, stops = runs(t, d)
    if not len(starts):
        return out
    lt, ld = t[starts], d[starts]
    cls = np.where(lt == idle, ld, lt)  # the gesture class of an error segment
    tp = lt == ld
    prev_tp = np.concatenate([[False], tp[:-1] & (lt[:-1] == cls[1:])])
    next_tp = np.concatenate([tp[1:] & (lt[1:] == cls[:-1]), [False]])
    fp, fn = (lt == idle) & ~tp, (ld == idle) & ~tp
    kinds = np.select(
        [tp & (lt != idle), tp, fp & ~prev_tp & ~next_tp, fp & prev_tp & next_tp, fp & next_tp, fp,
         fn & ~prev_tp & ~next_tp, fn & prev_tp & next_tp, fn & next_tp, fn],
        ["correct", "correct_idle", "insertion", "merge", "overfill_start", "overfill_end",
         "deletion", "fragmentation", "underfill_start", "underfill_end"], default="substitution")
    lengths = stops - starts
    for kind in SEGMENT_KINDS:
        mask = kinds == kind
        out.counts[kind] = int(mask.sum())
        out.frames[kind] = int(lengths[mask].sum())
    return out


@dataclass
class EventErrors:
    """Ward et al. (2011), event analysis: ground-truth events by kind (:data:`TRUTH_EVENT_KINDS`) and
    returned events by kind (:data:`RETURN_EVENT_KINDS`)."""
    truth: dict[str, int] = field(default_factory=lambda: dict.fromkeys(TRUTH_EVENT_KINDS, 0))
    returned: dict[str, int] = field(default_factory=lambda: dict.fromkeys(RETURN_EVENT_KINDS, 0))


def _event_ids(labels: np.ndarray, idle: str) -> tuple[np.ndarray, int]:
    """Per frame, the index of the event it belongs to (-1 on idle frames), and the event count."""
    ids = np.full(len(labels), -1, dtype=np.int64)
    starts, stops = _events(labels, idle)
    for i, (a, b) in enumerate(zip(starts, stops)):
        ids[a:b] = i
    return ids, len(starts)


def _overlaps(t: np.ndarray, d: np.ndarray, idle: str) -> tuple[np.ndarray, np.ndarray, int, int]:
    """The (ground-truth event, returned event) pairs that share a frame of the same class."""
    tid, nt = _event_ids(t, idle)
    did, nd = _event_ids(d, idle)
    hit = (t == d) & (t != idle)
    pairs = np.unique(tid[hit] * max(nd, 1) + did[hit])
    return pairs // max(nd, 1), pairs % max(nd, 1), nt, nd


def event_errors(t: np.ndarray, d: np.ndarray, idle: str) -> EventErrors:
    """Ward et al. (2011), event analysis (event analysis diagram), per class against the rest and summed over the
    gesture classes: a ground-truth event and a returned event *match* when they share a frame
    and have the same class (a return of another class over the event is a substitution at frame
    level, :func:`segment_errors`, and matches nothing here).

    A ground-truth event is deleted (D) when no return matches it; fragmented (F) when two or
    more returns match it (Ward: it holds a fragmentation segment); merged (M) when a return
    that matches it also matches another event (Ward: that return holds a merge segment);
    fragmented and merged (FM) when both; correct (C) otherwise: exactly one return matches it
    and that return matches nothing else. A returned event is an insertion (I') when it matches
    no event; merging (M') when it matches two or more; fragmenting (F') when an event it
    matches is fragmented; FM' when both; correct (C) otherwise. The correct counts of both
    sides are equal, and each side's kinds partition its events.
    """
    te, re_, nt, nd = _overlaps(t, d, idle)
    returns_per_event = np.bincount(te, minlength=nt)
    events_per_return = np.bincount(re_, minlength=nd)
    fragmented = returns_per_event >= 2
    merging = events_per_return >= 2
    merged = np.zeros(nt, dtype=bool)
    merged[te[merging[re_]]] = True
    fragmenting = np.zeros(nd, dtype=bool)
    fragmenting[re_[fragmented[te]]] = True
    deleted, inserted = returns_per_event == 0, events_per_return == 0
    out = EventErrors()
    out.truth.update(
        deleted=int(deleted.sum()), fragmented=int((fragmented & ~merged).sum()),
        merged=int((merged & ~fragmented).sum()), fragmented_merged=int((fragmented & merged).sum()),
        correct=int((~deleted & ~fragmented & ~merged).sum()))
    out.returned.update(
        inserted=int(inserted.sum()), merging=int((merging & ~fragmenting).sum()),
        fragmenting=int((fragmenting & ~merging).sum()),
        fragmenting_merging=int((fragmenting & merging).sum()),
        correct=int((~inserted & ~fragmenting & ~merging).sum()))
    return out


@dataclass
class DecisionTiming:
    """Time to decision over the ground-truth gesture events and accuracy at fixed times after
    onset (see :func:`decision_timing`)."""
    events: int = 0
    decided: int = 0
    never: int = 0
    fraction_decided: float = _NAN
    median_s: float = _NAN
    p90_s: float = _NAN
    accuracy_at: dict[float, float] = field(default_factory=dict)
    ended_before: dict[float, int] = field(default_factory=dict)


def decision_timing(t: np.ndarray, d: np.ndarray, idle: str, frame_rate: float,
                    times: Iterable[float] = (0.3, 1.0, 2.0)) -> DecisionTiming:
    """Time to decision and accuracy at fixed times after onset, over the ground-truth gesture
    events (maximal runs of one non-idle true label).

    Time to decision of an event: (first frame inside the event whose decision equals its class
    - its first frame) / ``frame_rate``, in seconds (0 when the decision is right at onset). An
    event with no such frame is *never* decided: it is counted in ``never`` and left out of the
    median and 90th percentile (numpy's linear interpolation), which are over the decided events
    only; ``fraction_decided`` is decided / events. NaN with no event (or no decided one).

    Accuracy at ``t`` seconds: the fraction of events whose decision at onset + t equals their
    class. The decision at onset + t is that of frame ``onset + floor(t * frame_rate)`` (the last
    frame at or before that time). When the event is over by then, its last frame's decision is
    used (the decision standing when the gesture ended), so every event counts at every t;
    ``ended_before[t]`` says how many events were that short. NaN with no event.
    """
    starts, stops = _events(t, idle)
    out = DecisionTiming(events=len(starts))
    delays = []
    for a, b in zip(starts, stops):
        hit = np.flatnonzero(d[a:b] == t[a])
        if len(hit):
            delays.append(hit[0] / frame_rate)
    out.decided, out.never = len(delays), len(starts) - len(delays)
    out.fraction_decided = _ratio(out.decided, out.events)
    if delays:
        out.median_s = float(np.median(np.asarray(delays, dtype=np.float64)))
        out.p90_s = float(np.percentile(np.asarray(delays, dtype=np.float64), 90))
    for s in times:
        at = starts + int(math.floor(float(s) * frame_rate + _EPS))
        out.ended_before[float(s)] = int(np.sum(at > stops - 1))
        at = np.minimum(at, stops - 1)
        out.accuracy_at[float(s)] = _ratio(np.sum(d[at] == t[starts]), len(starts))
    return out


def false_activations(t: np.ndarray, d: np.ndarray, idle: str, frame_rate: float) -> tuple[int, float]:
    """False activations and their rate per minute of idle truth.

    A false activation is a returned event (maximal run of one non-idle decision) that starts
    on an idle-truth frame and matches no ground-truth event of its class (Ward's insertion I',
    :func:`event_errors`); a return that starts early but runs into an event of its class is an
    overfill, not a false activation, and one that starts inside a gesture of another class is
    a substitution. Rate: their number / (idle-truth frames / ``frame_rate`` / 60); NaN when
    the stream has no idle frame."""
    _, re_, _, nd = _overlaps(t, d, idle)
    starts, _ = _events(d, idle)
    matched = np.bincount(re_, minlength=nd) > 0
    count = int(np.sum(~matched & (t[starts] == idle)))
    idle_minutes = np.sum(t == idle) / frame_rate / 60.0
    return count, _ratio(count, idle_minutes)


@dataclass
class StreamScores:
    """Every score of one stream (:func:`score_stream`); :meth:`to_dict` flattens them."""
    frames: int
    frame_rate: float
    idle_frames: int
    frame: FrameScores
    segments: SegmentErrors
    events: EventErrors
    timing: DecisionTiming
    false_activations: int
    false_activations_per_idle_minute: float

    def to_dict(self) -> dict[str, float | int]:
        """A flat dict: counts as ints, everything else as (float64) floats; seconds are frames
        / frame rate."""
        out: dict[str, float | int] = {
            "frames": self.frames, "seconds": self.frames / self.frame_rate,
            "idle_seconds": self.idle_frames / self.frame_rate}
        out.update({f"frame_{k}": float(v) for k, v in vars(self.frame).items()})
        for kind in SEGMENT_KINDS:
            out[f"segment_{kind}_count"] = self.segments.counts[kind]
            out[f"segment_{kind}_frames"] = self.segments.frames[kind]
            out[f"segment_{kind}_seconds"] = self.segments.frames[kind] / self.frame_rate
        out.update({f"event_{k}": v for k, v in self.events.truth.items()})
        out["event_total"] = sum(self.events.truth.values())
        out.update({f"return_{k}": v for k, v in self.events.returned.items()})
        out["return_total"] = sum(self.events.returned.values())
        tm = self.timing
        out.update({"decision_events": tm.events, "decision_decided": tm.decided,
                    "decision_never": tm.never, "decision_fraction_decided": tm.fraction_decided,
                    "time_to_decision_median_s": tm.median_s, "time_to_decision_p90_s": tm.p90_s})
        for s, acc in tm.accuracy_at.items():
            out[f"accuracy_at_{s:g}s"] = float(acc)
            out[f"ended_before_{s:g}s"] = tm.ended_before[s]
        out["false_activations"] = self.false_activations
        out["false_activations_per_idle_minute"] = float(self.false_activations_per_idle_minute)
        return out


def score_stream(truth: Sequence[str] | np.ndarray, decided: Sequence[str] | np.ndarray, idle: str,
                 frame_rate: float, times: Iterable[float] = (0.3, 1.0, 2.0), *,
                 undecided: str | Iterable[str] = ("undecided",)) -> StreamScores:
    """Every score of one stream: per-frame ``truth`` and per-frame ``decided`` labels (the
    decision standing at each frame; ``undecided`` labels count as ``idle``, see :func:`prepare`),
    the idle class, the frame rate (Hz) and the times after onset for accuracy-at-t (seconds).

    Sources: :func:`frame_scores`, :func:`segment_errors` and :func:`event_errors` (Ward,
    Lukowicz & Gellersen 2011), :func:`decision_timing`, :func:`false_activations`.
    Raises :class:`DataError` for a frame rate that is not a positive number, a time that is
    negative or not finite, or input :func:`prepare` refuses."""
    rate = float(frame_rate)
    if not math.isfinite(rate) or rate <= 0:
        raise DataError(f"stream scores need a positive frame rate, got {frame_rate!r}")
    times = tuple(float(s) for s in times)
    if any(not math.isfinite(s) or s < 0 for s in times):
        raise DataError(f"the times after onset must be finite and not negative, got {times!r}")
    t, d = prepare(truth, decided, str(idle), undecided)
    count, per_minute = false_activations(t, d, str(idle), rate)
    return StreamScores(
        frames=len(t), frame_rate=rate, idle_frames=int(np.sum(t == str(idle))),
        frame=frame_scores(t, d, str(idle)), segments=segment_errors(t, d, str(idle)),
        events=event_errors(t, d, str(idle)), timing=decision_timing(t, d, str(idle), rate, times),
        false_activations=count, false_activations_per_idle_minute=per_minute)
