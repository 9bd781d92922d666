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
- a live recogniser's windows and how it combines them are
  :mod:`touchbench.streams.recognizer`'s.
"""

from __future__ import annotations

from ..datasets.windows import cut_windows, seconds_to_frames

__all__ = ["cut_windows", "seconds_to_frames"]
