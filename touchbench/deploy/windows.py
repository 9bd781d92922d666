"""Sliding windows over frames, shared by training and live recognition.

Flagg (2012, section 4.5, "Future Work"): continuous recognition
"could involve buffering in 2-second periods. Since some gestures tend to
take more time than others, perhaps running a few buffers of different
length simultaneously could help prevent shorter gestures from getting lost
in too-long windows". Here a window is the last ``L`` frames of the stream;
several lengths run at once and a new decision is made every ``hop`` frames
(section 4.3.1's 2-second examples are windows of 100 frames at 50 Hz).

Interpretations (the thesis gives no more detail):

- lengths and hop are given in seconds and rounded to whole frames at the
  sensor's frame rate (at least one frame);
- a model meant for windows is trained on windows of the same lengths, cut
  from every training capture with a training hop (default: half the
  window), each window labelled with its capture's gesture; a capture
  shorter than every window is kept whole, so no capture is lost;
- when several windows are classified at once, the decision is the most
  confident window's (``combine="max"``: the window whose best class
  probability is highest, so a short gesture is not outvoted by a long
  window that mostly saw something else), or the mean of the windows'
  probabilities (``combine="mean"``).
"""

from __future__ import annotations

import numpy as np

from ..datasets.windows import cut_windows, seconds_to_frames

__all__ = ["COMBINE", "combine_windows", "cut_windows", "seconds_to_frames"]

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
