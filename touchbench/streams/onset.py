"""The ``onset`` decision rule: windows aligned to the onset of a touch, not sliding over it.

A sliding window that starts before a touch mixes rest with the gesture's
first frames, and one that spans two gestures mixes both; a window that
starts where the touch starts sees the gesture alone. The rule finds the
onset with the contact gate's level (:class:`touchbench.streams.rules.GateRule`,
``level: auto`` chosen on the training captures): over the newest frames
(the longest window's), each frame is in contact when its peak contact
(:func:`touchbench.streams.rules.peak_contact`) reaches the level; gaps of
contact shorter than ``bridge_s`` are bridged (a pat or a tickle lifts the
hand between contacts: one touch, not many); the onset is the start of the
last run of contact. Then:

- no contact in the newest ``gate_s`` seconds: the idle class, without the
  classifier (the gate);
- contact for less than the shortest window: the none label (too little of
  the touch seen to decide; scored as idle);
- contact for longer: one window from the onset to the newest frame, at
  most the longest window (then it slides), and the most probable class
  other than idle;
- contact throughout the newest frames: the recogniser's sliding windows.

Interpretations: the onset is found again at every decision from the
frames kept (no state), so a missed frame or a late decision cannot leave a
stale onset; the windows between the recogniser's lengths (0.5 to 1 s of a
touch) are classified by the model trained on the recogniser's lengths.
"""

from __future__ import annotations

import numpy as np
from pydantic import Field

from .rules import RULES, GateParams, GateRule, Seconds, frame_contact

__all__ = ["OnsetRule", "contact_run"]


def contact_run(contact: np.ndarray, bridge: int) -> int:
    """The number of newest frames in the last run of contact (``contact``: one bool per frame, oldest
    first), gaps of fewer than ``bridge`` frames between contacts bridged; 0 when the newest frame is
    not in contact."""
    c = np.asarray(contact, dtype=bool)
    start, i = c.size, c.size - 1
    while i >= 0:
        if c[i]:
            start, i = i, i - 1
            continue
        j = i
        while j >= 0 and not c[j]:
            j -= 1
        if start == c.size or i - j >= bridge or j < 0:
            break  # no contact at the newest frame, a gap too long to bridge, or rest back to the first frame
        i = j
    return int(c.size - start)


class OnsetParams(GateParams):
    bridge_s: Seconds = Field(0.5, description="gaps of contact shorter than this many seconds are bridged.")


@RULES.register("onset", description="windows aligned to the touch's onset (contact gate), not sliding")
class OnsetRule(GateRule):
    """The gate, and one window from the touch's onset instead of the sliding ones (module docstring).
    """

    name = "onset"
    Params = OnsetParams

    def window_lengths(self, frames: np.ndarray, lengths: list[int]) -> list[int] | None:
        peak = frame_contact(frames, self.sensor.value_range, self.sensor.higher_is_more_pressure)
        run = contact_run(peak >= self._level, max(1, int(round(self.bridge_s * self.frame_rate))))
        if run >= len(frames):
            return None  # in contact throughout: the sliding windows
        if run < lengths[0]:
            return []
        return [min(run, lengths[-1])]
