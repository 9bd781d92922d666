"""Windows cut from captures: the samples of a window-level evaluation and of windowed training.

A window is ``L`` consecutive frames of a capture; windows start every
``hop`` frames. :func:`cut_windows` is shared by ``touchbench train
--windows`` (deploy) and the ``window-kfold`` scheme, whose samples are
windows (:func:`window_dataset`: each window a capture of its own, with its
capture's labels and ``source_capture`` / ``window`` columns).

Flagg (2012, section 4.5, "Future Work"): continuous recognition "could
involve buffering in 2-second periods. Since some gestures tend to take more
time than others, perhaps running a few buffers of different length
simultaneously could help prevent shorter gestures from getting lost in
too-long windows". Here a window is the last ``L`` frames of the stream;
several lengths run at once and a new decision is made every ``hop`` frames
(section 4.3.1's 2-second examples are windows of 100 frames at 50 Hz).
Interpretations (the thesis gives no more detail):

- lengths and hop are given in seconds and rounded to whole frames at the
  sensor's frame rate (at least one frame: :func:`seconds_to_frames`);
- a model meant for windows is trained on windows of the same lengths, cut
  from every training capture with a training hop (default: half the
  window), each window labelled with its capture's gesture; a capture
  shorter than every window is kept whole, so no capture is lost;
- a live recogniser's windows and how it combines them are
  :mod:`touchbench.streams.recognizer`'s.
"""

from __future__ import annotations

from typing import Iterable, Sequence

import numpy as np

from ..core.errors import TouchbenchError
from .model import TIME_COLUMN, TouchDataset

__all__ = ["SOURCE_CAPTURE", "cut_windows", "no_frame", "seconds_to_frames", "window_dataset"]

#: the metadata column naming the capture a window was cut from
SOURCE_CAPTURE = "source_capture"


def no_frame(seconds: float, frame_rate: float) -> str | None:
    """Why ``seconds`` is no window at ``frame_rate`` (it rounds to no frame), or None.

    >>> no_frame(0.009, 50.0)
    '0.009 s is 0 frames at 50 Hz: a window is at least one frame (0.02 s)'
    >>> no_frame(0.011, 50.0) is None
    True
    """
    frames = round(float(seconds) * float(frame_rate))
    if frames >= 1:
        return None
    return f"{float(seconds):g} s is {frames} frames at {float(frame_rate):g} Hz: a window is at least one frame " \
           f"({1 / float(frame_rate):.3g} s)"


def seconds_to_frames(seconds: float, frame_rate: float, what: str = "a window length or hop") -> int:
    """``seconds`` at ``frame_rate``, rounded to whole frames (at least 1); ``what`` names the
    option in the error for a length that is not positive.

    >>> seconds_to_frames(0.5, 54.0), seconds_to_frames(0.1, 54.0), seconds_to_frames(0.001, 54.0)
    (27, 5, 1)
    """
    if not (isinstance(seconds, (int, float)) and np.isfinite(seconds) and seconds > 0):
        raise TouchbenchError(f"{what} must be a positive number of seconds, got {seconds!r}")
    return max(1, int(round(float(seconds) * float(frame_rate))))


def cut_windows(
    captures: Sequence[np.ndarray], lengths: Iterable[int], hops: Iterable[int]
) -> tuple[list[np.ndarray], np.ndarray]:
    """Every window of every capture: ``(windows, source index of each window)``.

    For each length ``L`` (frames) with its hop ``h``, the windows of a
    capture of ``T`` frames start at ``0, h, 2h, ...`` up to ``T - L``. A
    capture shorter than every length gives one window: itself. Windows are
    views (no copy).
    """
    lengths = [int(v) for v in lengths]
    hops = [int(v) for v in hops]
    if len(lengths) != len(hops) or not lengths:
        raise ValueError("one hop per window length, and at least one length")
    out: list[np.ndarray] = []
    src: list[int] = []
    for i, c in enumerate(captures):
        n = 0
        for L, h in zip(lengths, hops):
            for start in range(0, c.shape[0] - L + 1, h):
                out.append(c[start:start + L])
                src.append(i)
                n += 1
        if n == 0:
            out.append(c)
            src.append(i)
    return out, np.asarray(src, dtype=np.int64)




def window_dataset(ds: TouchDataset, frames: int, hop: int | None = None) -> TouchDataset:
    """Every window of ``frames`` frames every ``hop`` (default ``frames``: no overlap) of every
    capture of ``ds``, each a capture with its capture's metadata, ``capture_id`` ``<id>#w<k>``,
    ``source_capture`` (the capture's id) and ``window`` (k, from 0). A capture shorter than
    ``frames`` is one window: itself. Frame times, where present, are cut with their frames."""
    frames = int(frames)
    hop = frames if hop is None else int(hop)
    if frames < 1 or hop < 1:
        raise TouchbenchError(f"a window needs at least one frame and a hop of at least one (got {frames}, {hop})")
    wins, src = cut_windows(ds.captures, [frames], [hop])
    meta = ds.meta.iloc[src].reset_index(drop=True).copy()
    k = np.zeros(len(src), dtype=np.int64)
    for i in range(1, len(src)):
        k[i] = k[i - 1] + 1 if src[i] == src[i - 1] else 0
    meta[SOURCE_CAPTURE] = meta["capture_id"].astype(str)
    meta["window"] = k
    meta["capture_id"] = [f"{c}#w{j}" for c, j in zip(meta[SOURCE_CAPTURE], k)]
    if TIME_COLUMN in meta.columns:
        meta[TIME_COLUMN] = [np.asarray(t)[j * hop: j * hop + len(w)] for t, j, w in zip(meta[TIME_COLUMN], k, wins)]
    return TouchDataset(ds.name, [np.ascontiguousarray(w) for w in wins], meta, ds.sensor, provenance=ds.provenance)
