"""Streams as data: a recording of frames with a true label per frame, a subject and a session.

A stream is held as plain data, :class:`Stream`: the ordered segments of a
dataset's captures it is made of, each ``(capture index, first frame, stop
frame)``; its frames are those segments end to end and each frame's truth is
its capture's label. Three sources, each named in :attr:`Stream.source` and
in every table that shows a stream's figures:

- ``recorded``: a user's continuous recordings labelled frame by frame, read
  as one capture per run of one label (the ``table`` format with
  ``frame_labels``: columns ``recording`` and ``start_frame``);
  :func:`recorded_streams` puts each recording's segments back in order.
- ``spliced``: a dataset's captures of one subject put end to end in a
  seeded random order, separated by stretches of that subject's own idle
  captures (HAART's ``notouch``), or, where the subject has none, of the
  sensor's rest (frames at the bottom of its value range; a capture index
  of :data:`REST`). The splice points are artificial: a real touch does not
  start or end at a capture's edge (:func:`spliced_streams`).
- ``scene``: a synthetic scene's sessions (a person performs gestures with
  pauses of rest in between), spliced the same way from the scene's
  captures and rest.

Interpretations: a capture's frames all carry its label (the data labels
captures, not frames; a gesture capture's first frames before contact are
counted as the gesture); an idle stretch of ``g`` seconds is a window of
``g`` seconds of one idle capture, at a random offset (the whole capture
when it is shorter), the idle captures taken in a seeded random rotation.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass
from typing import Sequence

import numpy as np
import pandas as pd

from ..core.errors import TouchbenchError

__all__ = ["REST", "SOURCES", "Stream", "decisions_per_frame", "label_runs", "recorded_streams", "rest_value", "spliced_streams",
           "stream_frames"]

#: the capture index of a stretch of the sensor's rest (frames at the bottom of its value range)
REST = -1
SOURCES = ("recorded", "spliced", "scene")


@dataclass(frozen=True)
class Stream:
    """One stream: its name, subject, session and source, and its segments in order."""

    name: str
    subject: str
    session: str
    source: str
    segments: tuple[tuple[int, int, int], ...]  # (capture index or REST, first frame, stop frame)

    @property
    def n_frames(self) -> int:
        return int(sum(b - a for _, a, b in self.segments))

    @property
    def captures(self) -> np.ndarray:
        """The dataset's captures this stream shows (sorted, each once; the sensor's rest left out)."""
        return np.unique(np.array([i for i, _, _ in self.segments if i != REST], dtype=np.int64))

    def digest(self) -> str:
        return hashlib.sha256(repr((self.name, self.subject, self.session, self.source,
                                    self.segments)).encode()).hexdigest()[:16]


def rest_value(sensor) -> float:
    """The value a cell reads at rest: the bottom of the sensor's range, or its top for a sensor where
    lower means more pressure (the frames of a stretch of :data:`REST`)."""
    lo, hi = sensor.value_range
    return float(lo if sensor.higher_is_more_pressure else hi)


def stream_frames(captures: Sequence[np.ndarray], labels: Sequence[str], stream: Stream, idle: str,
                  rest_value: float) -> tuple[np.ndarray, np.ndarray]:
    """The stream's frames ``(T, H, W)`` and each frame's true label ``(T,)``; a rest stretch is
    frames at ``rest_value`` labelled ``idle``."""
    like = captures[stream.captures[0]] if len(stream.captures) else None
    if like is None:
        raise TouchbenchError(f"stream {stream.name!r} shows no capture")
    parts, truth = [], []
    for i, a, b in stream.segments:
        if i == REST:
            parts.append(np.full((b - a, *like.shape[1:]), rest_value, dtype=like.dtype))
            truth.append(np.full(b - a, idle, dtype=object))
        else:
            parts.append(captures[i][a:b])
            truth.append(np.full(b - a, str(labels[i]), dtype=object))
    return np.concatenate(parts), np.concatenate(truth)


def recorded_streams(meta: pd.DataFrame, n_frames: np.ndarray, rows: np.ndarray) -> list[Stream]:
    """The recordings among ``rows`` (positions in ``meta``), each a stream of its segments ordered by
    ``start_frame``; a recording whose segments leave a gap or overlap is refused, naming it."""
    missing = [c for c in ("recording", "start_frame") if c not in meta.columns]
    if missing:
        raise TouchbenchError("recorded streams need the columns 'recording' and 'start_frame' (a table read with "
                              f"frame labels); this dataset lacks {', '.join(missing)}")
    rows = np.asarray(rows, dtype=np.int64)
    recs = meta["recording"].astype(str).to_numpy()[rows]
    starts = pd.to_numeric(meta["start_frame"]).to_numpy(np.int64)[rows]
    out = []
    for rec in sorted(set(recs)):
        mine = rows[recs == rec]
        order = np.argsort(starts[recs == rec], kind="stable")
        mine, first = mine[order], starts[recs == rec][order]
        ends = first + n_frames[mine]
        if first[0] != 0 or np.any(first[1:] != ends[:-1]):
            raise TouchbenchError(f"recording {rec!r}: its segments do not follow one another (a gap or an overlap)")
        row = meta.iloc[int(mine[0])]
        session = str(row["session"]) if "session" in meta.columns else rec
        segs = tuple((int(i), 0, int(n_frames[i])) for i in mine)
        out.append(Stream(rec, str(row["subject"]), session, "recorded", segs))
    return out


def spliced_streams(meta: pd.DataFrame, n_frames: np.ndarray, rows: np.ndarray, target: str, idle: str,
                    gap_frames: tuple[int, int], rng: np.random.Generator, source: str = "spliced",
                    per_stream: int | None = None) -> list[Stream]:
    """One stream per subject of ``rows`` (positions in ``meta``): its captures other than ``idle``
    in a random order (``per_stream`` of them, drawn at random, when given), each followed by an idle
    stretch of ``gap_frames[0]..gap_frames[1]`` frames (uniform) cut from the subject's idle captures
    (module docstring), or of the sensor's rest when it has none; the stream starts with one too."""
    lo, hi = int(gap_frames[0]), int(gap_frames[1])
    if lo < 1 or hi < lo:
        raise TouchbenchError(f"an idle stretch must be at least one frame long, got {lo}..{hi} frames")
    labels = meta[target].astype(str).to_numpy()
    subjects = meta["subject"].astype(str).to_numpy()
    out = []
    for subject in sorted(set(subjects[rows])):
        mine = np.asarray(rows)[subjects[rows] == subject]
        gestures = mine[labels[mine] != idle]
        idles = list(rng.permutation(mine[labels[mine] == idle]))
        order = rng.permutation(gestures)
        if per_stream is not None:
            order = order[:per_stream]
        segs: list[tuple[int, int, int]] = []
        for k, i in enumerate([None, *order]):
            if i is not None:
                segs.append((int(i), 0, int(n_frames[i])))
            g = int(rng.integers(lo, hi + 1))
            segs.append(_idle_stretch(idles, k, g, n_frames, rng))
        out.append(Stream(subject, subject, subject, source, tuple(segs)))
    return out


def _idle_stretch(idles: list, k: int, g: int, n_frames: np.ndarray, rng: np.random.Generator) -> tuple[int, int, int]:
    """``g`` frames of the ``k``-th idle capture in rotation (at a random offset), or of the rest."""
    if not idles:
        return (REST, 0, g)
    i = int(idles[k % len(idles)])
    n = int(n_frames[i])
    if n <= g:
        return (i, 0, n)
    a = int(rng.integers(0, n - g + 1))
    return (i, a, a + g)


def decisions_per_frame(frames: Sequence[int], labels: Sequence[str], n_frames: int, undecided: str) -> np.ndarray:
    """Each frame's decision: the label of the last decision made at or before it (``frames``:
    1-based counts of frames received, increasing), ``undecided`` before the first."""
    out = np.full(n_frames, undecided, dtype=object)
    f = np.asarray(frames, dtype=np.int64)
    for k, (a, label) in enumerate(zip(f, labels)):
        b = f[k + 1] if k + 1 < len(f) else n_frames + 1
        out[a - 1:b - 1] = label
    return out


def label_runs(labels: Sequence[str]) -> list[tuple[int, str]]:
    """Run-length form of a label sequence: ``[(first index, label), ...]`` for each run."""
    a = np.asarray(labels, dtype=object)
    if a.size == 0:
        return []
    starts = np.flatnonzero(np.r_[True, a[1:] != a[:-1]])
    return [(int(s), str(a[s])) for s in starts]
