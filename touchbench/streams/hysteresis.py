"""The ``touch`` decision rule: two decisions, is something touching now, and what is it.

A live robot needs two answers at every hop. A recogniser that answers
both with one argmax calls a touch whenever one window of idle frames looks
a little like a gesture (on real recordings of a robot skin: 10 to 30 false
activations per idle minute, docs/research/live-recognition.md). This rule
separates them:

1. **Touch or not, with hysteresis.** The probability of a touch is ``1 -
   P(idle)`` of the combined windows (the classifier's; the ``two-stage``
   estimator, :mod:`touchbench.classifiers.two_stage`, gives it from a
   detector of its own). From idle, a touch begins when that probability is
   at least ``begin`` for ``begin_s`` consecutive decisions; a touch ends when it
   is under ``end`` for ``end_s`` consecutive decisions. With ``end <
   begin``, a probability wavering about one level neither starts nor ends a
   touch (a Schmitt trigger; the two thresholds and the run lengths are the
   hysteresis).
2. **The gesture from the touch so far.** From the decision at which the
   touch began (its onset, as the rule saw it), the rule adds up each
   decision's log-probabilities of the gesture classes (the classes other
   than idle, renormalised); the label is the gesture with the highest sum,
   so the evidence grows with the touch and a single odd window does not
   flip the answer (the naive-Bayes reading of independent windows; an
   interpretation). ``memory`` (seconds) limits the sum to the most recent
   decisions of a long touch (0: the whole touch).

The decisions while a touch is being confirmed, and after it ended, are the
idle class. Before the first decision of a stream the rule is idle.

Interpretations: the run lengths are counted in decisions, not seconds (the
recogniser decides every hop), and converted from ``begin_s`` / ``end_s``
seconds with the hop the recogniser gives the rule (at least one decision).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from pydantic import Field, model_validator

from ..core.errors import TouchbenchError
from .rules import RULES, ClassName, DecisionRule, FieldProblem, Fraction, RuleParams, Seconds

__all__ = ["TouchRule"]

#: the smallest probability a log-probability is taken of
FLOOR = 1e-6


class TouchParams(RuleParams):
    idle: ClassName = Field(description="the idle class (no touch; in a stream evaluation, the scheme's ``idle``).")
    begin: Fraction = Field(0.6, description="a touch begins at ``P(touch) >= begin``.")
    end: Fraction = Field(0.4, description="a touch ends at ``P(touch) < end`` (``end <= begin``).")
    begin_s: Seconds = Field(0.2, description="for how long (seconds, counted in decisions) ``begin`` must hold.")
    end_s: Seconds = Field(0.3, description="for how long (seconds, counted in decisions) ``end`` must hold.")
    memory: Seconds = Field(0.0, description="seconds of the touch whose evidence decides the gesture (0: since "
                            "the onset).")

    @model_validator(mode="after")
    def _order(self) -> "TouchParams":
        if self.end > self.begin:
            raise FieldProblem("end", f"end ({self.end!r}) must not be above begin ({self.begin!r})")
        return self


@RULES.register("touch", description="two decisions: a touch begins and ends with hysteresis on P(touch); the "
                "gesture is the one most probable over the touch so far")
class TouchRule(DecisionRule):
    """Touch detection with hysteresis, then the gesture from the touch so far (module docstring).
    """

    name = "touch"
    Params = TouchParams

    def start(self, classes: np.ndarray, none_label: str, frame_rate: float, sensor: Any = None) -> None:
        super().start(classes, none_label, frame_rate, sensor)
        if self.idle not in set(self.classes):
            raise TouchbenchError(f"the touch rule's idle class {self.idle!r} is not one of the classes "
                                  f"({', '.join(map(str, self.classes))})")
        self._idle = int(np.flatnonzero(self.classes == self.idle)[0])
        self._keep = self.classes != self.idle
        self.set_hop(1)  # until the recogniser gives its hop

    def set_hop(self, hop_frames: int) -> None:
        """The recogniser's hop in frames: the run lengths in decisions (at least one each)."""
        per_s = self.frame_rate / max(1, int(hop_frames))
        self._begin = max(1, int(round(self.begin_s * per_s)))
        self._end = max(1, int(round(self.end_s * per_s)))
        self._memory = int(round(self.memory * per_s)) if self.memory > 0 else 0
        self._touch, self._run, self._evidence = False, 0, []

    def decide(self, p: np.ndarray) -> str:
        p = np.asarray(p, dtype=np.float64)
        touch = 1.0 - float(p[self._idle])
        if not self._touch:
            self._run = self._run + 1 if touch >= self.begin else 0
            self._evidence.append(p)
            self._evidence = self._evidence[-self._begin:]  # the decisions that may confirm the touch
            if self._run < self._begin:
                return self.idle
            self._touch, self._run = True, 0
        else:
            self._run = self._run + 1 if touch < self.end else 0
            if self._run >= self._end:
                self._touch, self._run, self._evidence = False, 0, []
                return self.idle
            self._evidence.append(p)
            if self._memory:
                self._evidence = self._evidence[-self._memory:]
        return self._gesture()

    def _gesture(self) -> str:
        """The gesture with the highest summed log-probability over the touch's decisions (renormalised
        over the gesture classes)."""
        g = np.stack(self._evidence)[:, self._keep]
        g = g / np.maximum(g.sum(axis=1, keepdims=True), FLOOR)
        k = int(np.argmax(np.log(np.maximum(g, FLOOR)).sum(axis=0)))
        return str(self.classes[self._keep][k])
