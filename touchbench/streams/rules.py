"""Decision rules: from a window's class probabilities to the label a live recogniser says.

A rule is declared like any method parameter, ``{name: majority, n: 5}``
(:func:`make_rule`), and gets, at every hop, the combined probabilities of
the windows (:func:`touchbench.streams.recognizer.combine_windows`). A rule
that ``gates`` may decide before any classifier runs, from the frames alone.

- ``max``: the most probable class, or the none label when its probability is
  under ``threshold`` (Flagg 2012, Sec. 4.5: "confidence estimates, so that
  the model is not forced to classify everything it sees").
- ``gate``: a rest/contact gate. The newest ``gate_s`` seconds' peak
  contact, ``(max value - lo) / (hi - lo)`` over their frames and cells with
  the sensor's value range (inverted for a sensor where lower means more
  pressure), under ``level`` decides the ``idle`` class without running the
  classifier; otherwise the most probable class other than ``idle``.
  ``level: auto`` is chosen on the training captures
  (:meth:`GateRule.fit`): the level that best separates the peaks of the
  idle captures' stretches of ``gate_s`` seconds from the others' (balanced
  accuracy over the stretches; ties: the lowest).
- ``majority``: the most frequent of the last ``n`` decisions of ``max``
  (ties: the most recent of the tied labels), smoothing one-hop flickers.
- ``onset`` (:mod:`touchbench.streams.onset`): the gate, and windows
  aligned to the touch's onset instead of sliding ones.
- ``touch`` (:mod:`touchbench.streams.hysteresis`): two decisions, a touch
  begun and ended with hysteresis on ``1 - P(idle)``, and the gesture most
  probable over the touch so far.
- ``hmm``: forward filtering over the classes (a hidden Markov model whose
  state stays with probability ``1 - switch`` per hop and moves to any other
  class uniformly; the classifier's probabilities are the emissions, the
  scaled-likelihood reading of hybrid recognisers, Bourlard & Morgan 1994,
  Sec. 7): the most probable class of the filtered posterior, or the none
  label under ``threshold``.

Interpretations: the gate's peak uses the raw values, so it needs a sensor
whose rest reads near the bottom of its range (HAART's pressure cells do;
a capacitive grid with a large resting offset should fit ``level: auto``,
which learns the offset's level from the training captures).
"""

from __future__ import annotations

import inspect
from collections import Counter, deque
from typing import Any, Sequence

import numpy as np

from ..core.errors import TouchbenchError
from ..core.registry import Registry

__all__ = ["DEFAULT_RULE", "RULES", "DecisionRule", "GateRule", "MaxRule", "fitted_declaration", "frame_contact", "make_rule",
           "needs_fitting", "peak_contact", "stream_rule"]

RULES: Registry = Registry("decision rule", package="touchbench.streams")


class DecisionRule:
    """The interface: :meth:`start` before a stream, :meth:`gate` (a label decided from the frames
    alone, or None) and :meth:`decide` at each hop; :meth:`fit` on training captures, when the rule
    learns something."""

    gates = False

    def fit(self, captures: Sequence[np.ndarray], labels: Sequence[str], sensor: Any) -> "DecisionRule":
        return self

    def start(self, classes: np.ndarray, none_label: str, frame_rate: float, sensor: Any = None) -> None:
        self.classes = np.asarray(classes, dtype=object)
        self.none_label = none_label
        self.frame_rate = frame_rate
        self.sensor = sensor

    def set_hop(self, hop_frames: int) -> None:
        """The recogniser's hop in frames, given after :meth:`start` (a rule that counts decisions in
        seconds converts them)."""

    def gate(self, frames: np.ndarray) -> str | None:
        """A label decided from ``frames`` (the newest frames, the longest window's) alone, or None."""
        return None

    def window_lengths(self, frames: np.ndarray, lengths: list[int]) -> list[int] | None:
        """The windows (frames, each ending at the newest) this rule decides from, given the newest
        ``frames``; None: the recogniser's sliding ``lengths``; an empty list: none yet (the none label)."""
        return None

    def decide(self, p: np.ndarray) -> str:
        raise NotImplementedError

    def describe(self) -> dict[str, Any]:
        return {"name": self.name, **self.params}  # type: ignore[attr-defined]


def make_rule(spec: dict[str, Any] | str | None, threshold: float = 0.5) -> DecisionRule:
    """A rule from its declaration (``{name: ..., params}`` or a name; None: ``max`` with ``threshold``)."""
    if spec is None:
        return MaxRule(threshold=threshold)
    if not isinstance(spec, (str, dict)):
        raise TouchbenchError(f"a decision rule is a name or a mapping such as {{name: majority, n: 5}}, got {spec!r}")
    d = {"name": spec} if isinstance(spec, str) else dict(spec)
    name = d.pop("name", None)
    if not isinstance(name, str):
        raise TouchbenchError("a decision rule needs a name: {name: max}")
    try:
        return RULES.create(name, **d)
    except TypeError as e:
        raise TouchbenchError(f"decision rule {name!r}: {_parameter_problem(RULES.get(name), d) or e}") from None


def _parameter_problem(cls: Any, given: dict[str, Any]) -> str:
    """What is wrong with ``given`` as ``cls``'s parameters, in words: a missing field or an unknown one."""
    params = dict(inspect.signature(cls).parameters)
    missing = [k for k, p in params.items() if p.default is inspect.Parameter.empty and k not in given]
    unknown = [k for k in given if k not in params]
    fields = ", ".join(params)
    if missing:
        return f"needs {', '.join(missing)} (its fields: {fields})"
    return f"has no field {', '.join(map(str, unknown))} (its fields: {fields})" if unknown else ""


#: the rule ``touchbench stream`` decides with when a model file records one (``touchbench train`` on a
#: stream evaluation writes it, with that evaluation's idle class and the level fitted on the model's
#: training captures); chosen on the HAART challenge's training subjects only
#: (docs/research/stream-rules.md). A model without it decides with ``max`` and ``--threshold``.
DEFAULT_RULE: dict[str, Any] = {"name": "hmm", "switch": 0.01}


def stream_rule(idle: str, captures: Sequence[np.ndarray], labels: Sequence[str], sensor: Any) -> dict[str, Any]:
    """:data:`DEFAULT_RULE` for a model whose idle class is ``idle``, fitted on its training
    ``captures`` (:func:`fitted_declaration`)."""
    spec = dict(DEFAULT_RULE)
    if spec["name"] in ("gate", "onset"):
        spec["idle"] = idle
    return fitted_declaration(spec, captures, labels, sensor)


def fitted_declaration(spec: dict[str, Any] | str, captures: Sequence[np.ndarray], labels: Sequence[str],
                       sensor: Any) -> dict[str, Any]:
    """The declaration ``spec`` fitted on training ``captures``: the same declaration with the fitted
    level written in as ``level`` (the gate's and onset's ``level: auto``), which ``make_rule`` builds
    again into a rule deciding as the fitted one."""
    d = {"name": spec} if isinstance(spec, str) else dict(spec)
    fitted = getattr(make_rule(d).fit(captures, labels, sensor), "fitted_level", None)
    return {**d, "level": fitted} if fitted is not None else d


def needs_fitting(rule: DecisionRule) -> bool:
    """Whether ``rule`` still needs a level chosen on training captures (``level: auto``, not fitted)."""
    return getattr(rule, "level", None) == "auto" and not hasattr(rule, "fitted_level")


def _threshold(value: Any) -> float:
    t = float(value)
    if not 0.0 <= t <= 1.0:
        raise TouchbenchError(f"threshold must be in [0, 1], got {value!r}")
    return t


@RULES.register("max", description="the most probable class, none under the threshold")
class MaxRule(DecisionRule):
    name = "max"

    def __init__(self, threshold: float = 0.5):
        self.threshold = _threshold(threshold)
        self.params = {"threshold": self.threshold}

    def decide(self, p: np.ndarray) -> str:
        k = int(np.argmax(p))
        return str(self.classes[k]) if p[k] >= self.threshold else self.none_label


def frame_contact(frames: np.ndarray, value_range: tuple[float, float], higher_is_more: bool = True) -> np.ndarray:
    """Each frame's largest contact as a fraction of the value range (0: rest at the range's bottom,
    1: full scale); for a sensor where lower means more pressure, measured from the top; zeros for a
    range of no width."""
    lo, hi = float(value_range[0]), float(value_range[1])
    a = np.asarray(frames, dtype=np.float64).reshape(len(frames), -1)
    if hi - lo <= 0 or a.size == 0:
        return np.zeros(len(a))
    return (a.max(axis=1) - lo) / (hi - lo) if higher_is_more else (hi - a.min(axis=1)) / (hi - lo)


def peak_contact(frames: np.ndarray, value_range: tuple[float, float], higher_is_more: bool = True) -> float:
    """The largest contact of ``frames`` (:func:`frame_contact`; 0 for no frame)."""
    c = frame_contact(frames, value_range, higher_is_more)
    return float(c.max()) if c.size else 0.0


@RULES.register("gate", description="a rest/contact gate decides idle before the classifier; else the best "
                "non-idle class")
class GateRule(DecisionRule):
    name = "gate"
    gates = True

    def __init__(self, idle: str, level: float | str = "auto", gate_s: float = 0.25, threshold: float = 0.0):
        if not isinstance(idle, str) or not idle:
            raise TouchbenchError("the gate needs the idle class: idle: notouch")
        if level != "auto" and not (isinstance(level, (int, float)) and 0.0 <= float(level) <= 1.0):
            raise TouchbenchError(f"the gate's level is a fraction of the value range in [0, 1] or auto, got {level!r}")
        if not (isinstance(gate_s, (int, float)) and gate_s > 0):
            raise TouchbenchError(f"the gate's gate_s must be a positive number of seconds, got {gate_s!r}")
        self.idle, self.level, self.gate_s = idle, level, float(gate_s)
        self.threshold = _threshold(threshold)
        self.params = {"idle": idle, "level": level, "gate_s": self.gate_s, "threshold": self.threshold}

    def fit(self, captures: Sequence[np.ndarray], labels: Sequence[str], sensor: Any) -> "GateRule":
        """``level: auto``: the level that best separates the peak contact of the idle captures'
        stretches of ``gate_s`` seconds from the other captures' (balanced accuracy over the
        stretches, each capture cut into consecutive ones; ties: the lowest level), the peaks the gate
        reads at each decision."""
        if self.level != "auto":
            return self
        y = np.asarray([str(v) for v in labels]) == self.idle
        if y.all() or not y.any():
            raise TouchbenchError(f"the gate's level: auto needs training captures of {self.idle!r} and of gestures")
        n = max(1, int(round(self.gate_s * float(sensor.frame_rate))))
        peaks, idle = [], []
        for c, is_idle in zip(captures, y):
            for a in range(0, max(1, len(c) - n + 1), n):
                peaks.append(peak_contact(c[a:a + n], sensor.value_range, sensor.higher_is_more_pressure))
                idle.append(is_idle)
        self.fitted_level = best_level(np.asarray(peaks), np.asarray(idle))
        return self

    def start(self, classes: np.ndarray, none_label: str, frame_rate: float, sensor: Any = None) -> None:
        super().start(classes, none_label, frame_rate, sensor)
        if self.idle not in set(self.classes):
            raise TouchbenchError(f"the gate's idle class {self.idle!r} is not one of the classes "
                                  f"({', '.join(map(str, self.classes))})")
        if self.level == "auto" and not hasattr(self, "fitted_level"):
            raise TouchbenchError("the gate's level: auto is chosen on training captures: fit the rule first")
        self._level = self.fitted_level if self.level == "auto" else float(self.level)
        self._n = max(1, int(round(self.gate_s * frame_rate)))
        self._keep = self.classes != self.idle

    def gate(self, frames: np.ndarray) -> str | None:
        s = self.sensor
        peak = peak_contact(frames[-self._n:], s.value_range, s.higher_is_more_pressure)
        return self.idle if peak < self._level else None

    def decide(self, p: np.ndarray) -> str:
        q = np.where(self._keep, p, -np.inf)
        k = int(np.argmax(q))
        return str(self.classes[k]) if p[k] >= self.threshold else self.none_label

    def describe(self) -> dict[str, Any]:
        d = super().describe()
        if self.level == "auto" and hasattr(self, "fitted_level"):
            d["fitted_level"] = self.fitted_level
        return d


def best_level(peaks: np.ndarray, idle: np.ndarray) -> float:
    """The level ``t`` maximising the balanced accuracy of "idle when peak < t" (candidates: midpoints
    between consecutive distinct peaks, and just above the largest); ties: the lowest."""
    v = np.unique(peaks)
    cands = np.r_[(v[:-1] + v[1:]) / 2.0, np.nextafter(v[-1], np.inf)] if v.size > 1 else np.array([np.nextafter(v[0], np.inf)])
    below = peaks[None, :] < cands[:, None]
    bal = 0.5 * (below[:, idle].mean(axis=1) + (~below[:, ~idle]).mean(axis=1))
    return float(cands[int(np.argmax(bal))])


@RULES.register("majority", description="the most frequent of the last n decisions of max (smoothing)")
class MajorityRule(MaxRule):
    name = "majority"

    def __init__(self, n: int = 5, threshold: float = 0.5):
        super().__init__(threshold)
        if not isinstance(n, int) or isinstance(n, bool) or n < 1:
            raise TouchbenchError(f"majority's n must be a whole number of decisions >= 1, got {n!r}")
        self.n = n
        self.params = {"n": n, "threshold": self.threshold}

    def start(self, classes: np.ndarray, none_label: str, frame_rate: float, sensor: Any = None) -> None:
        super().start(classes, none_label, frame_rate, sensor)
        self._last: deque[str] = deque(maxlen=self.n)

    def decide(self, p: np.ndarray) -> str:
        self._last.append(super().decide(p))
        counts = Counter(self._last)
        top = max(counts.values())
        return next(label for label in reversed(self._last) if counts[label] == top)


@RULES.register("hmm", description="forward filtering over the classes with a sticky transition (smoothing)")
class HmmRule(MaxRule):
    name = "hmm"

    def __init__(self, switch: float = 0.05, threshold: float = 0.5):
        super().__init__(threshold)
        if not (isinstance(switch, (int, float)) and 0.0 <= float(switch) <= 1.0):
            raise TouchbenchError(f"hmm's switch is a probability per hop in [0, 1], got {switch!r}")
        self.switch = float(switch)
        self.params = {"switch": self.switch, "threshold": self.threshold}

    def start(self, classes: np.ndarray, none_label: str, frame_rate: float, sensor: Any = None) -> None:
        super().start(classes, none_label, frame_rate, sensor)
        self._post: np.ndarray | None = None

    def decide(self, p: np.ndarray) -> str:
        C = len(p)
        if self._post is None:
            prior = np.full(C, 1.0 / C)
        else:
            move = self.switch / (C - 1) if C > 1 else 0.0
            prior = self._post * (1.0 - self.switch - move) + move * self._post.sum()
        post = prior * np.maximum(np.asarray(p, dtype=np.float64), 1e-12)
        self._post = post / post.sum()
        return super().decide(self._post)
