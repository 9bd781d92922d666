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

from collections import Counter, deque
from dataclasses import dataclass, field
from typing import Annotated, Any, ClassVar, Sequence, Union

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, PlainValidator, Strict, ValidationError

from ..core.errors import TouchbenchError, UnknownNameError
from ..core.hashing import canonical_json
from ..core.paramdoc import of_model
from ..core.registry import Registry
from ..core.suggest import did_you_mean

__all__ = ["DEFAULT_RULE", "RULES", "DecisionRule", "FieldProblem", "GateRule", "HmmRule", "MajorityRule", "MaxRule", "RuleError",
           "RuleParams", "RuleSpec", "fitted_declaration", "frame_contact", "make_rule", "needs_fitting", "peak_contact",
           "rule_class", "rule_defaults", "rule_spec", "stream_rule"]

RULES: Registry = Registry("decision rule", package="touchbench.streams", params_of=of_model)


class RuleParams(BaseModel):
    """The base of every rule's parameter model: unknown parameters refused, booleans never read as
    numbers nor strings as numbers (strict types)."""

    model_config = ConfigDict(extra="forbid", frozen=True)


class RuleError(TouchbenchError):
    """A decision rule's declaration that is not valid: ``issues`` lists ``(location in the
    declaration, message)`` for each problem (a location such as ``("switch",)``)."""

    def __init__(self, message: str, issues: list[tuple[tuple, str]]):
        super().__init__(message)
        self.issues = issues


class FieldProblem(ValueError):
    """Raised by a parameter model's validator about one of its fields (``field``), so that the
    problem is reported at that field."""

    def __init__(self, field: str, message: str):
        super().__init__(message)
        self.field = field


#: a probability or a fraction, in [0, 1] (an integer 0 or 1 is read as a number; a boolean is refused)
Fraction = Annotated[float, Strict(), Field(ge=0.0, le=1.0, allow_inf_nan=False)]
#: a run length in seconds a rule counts (at most an hour: a stream holds far less)
MAX_RULE_S = 3600.0
Seconds = Annotated[float, Strict(), Field(ge=0.0, lt=MAX_RULE_S, allow_inf_nan=False)]
PositiveSeconds = Annotated[float, Strict(), Field(gt=0.0, lt=MAX_RULE_S, allow_inf_nan=False)]
#: a class name (a boolean such as YAML's ``no`` is refused, not read as a name)
ClassName = Annotated[str, Strict(), Field(min_length=1)]


def _level(v: Any) -> float | str:
    if v == "auto" and isinstance(v, str):
        return v
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not 0.0 <= float(v) <= 1.0:
        raise ValueError(f"the level is a fraction of the value range in [0, 1], or auto; got {v!r}")
    return float(v)


#: the gate's level: a fraction of the value range in [0, 1], or ``auto`` (chosen on training captures)
Level = Annotated[Union[float, str], PlainValidator(_level)]


class DecisionRule:
    """The interface: :meth:`start` before a stream, :meth:`gate` (a label decided from the frames
    alone, or None) and :meth:`decide` at each hop; :meth:`fit` on training captures, when the rule
    learns something.

    A rule declares its parameters once, as the pydantic model ``Params``; a rule is built from its
    validated parameters (:meth:`from_params`, what :func:`make_rule` does), or as
    ``Rule(value, ..., name=value)`` (the model's fields in order), which validates them the same
    way (:class:`RuleError`). Each parameter is an attribute of the rule, and ``params`` all of them.
    """

    name: ClassVar[str] = ""
    Params: ClassVar[type[RuleParams]] = RuleParams
    gates = False

    def __init__(self, *args: Any, **given: Any):
        fields = list(self.Params.model_fields)
        if len(args) > len(fields):
            raise TypeError(f"{type(self).__name__} takes at most {len(fields)} positional parameters ({', '.join(fields)})")
        self._set(rule_spec({**dict(zip(fields, args)), **given, "name": self.name}).params)

    @classmethod
    def from_params(cls, params: RuleParams) -> "DecisionRule":
        """The rule with the validated ``params`` (an instance of :attr:`Params`)."""
        rule = cls.__new__(cls)
        rule._set(params)
        return rule

    def _set(self, params: RuleParams) -> None:
        self.settings = params
        self.params = params.model_dump()
        for k, v in self.params.items():
            setattr(self, k, v)

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


def rule_class(name: Any) -> type["DecisionRule"]:
    """The registered rule ``name`` (an unknown name: :class:`RuleError` at ``name``, with the nearest)."""
    if not isinstance(name, str):
        raise RuleError("a decision rule needs a name: {name: max}", [(("name",), "a decision rule needs a name: "
                                                                              "{name: max}")])
    try:
        return RULES.get(name)
    except UnknownNameError as e:
        raise RuleError(str(e), [(("name",), str(e))]) from None


@dataclass(frozen=True)
class RuleSpec:
    """A decision rule's declaration, validated once: its rule class, its parameters (an instance of
    the class's ``Params``) and the parameters as declared (defaults not filled in: what identifies
    the declaration, and what a fitted declaration writes back)."""

    rule: type["DecisionRule"]
    params: RuleParams
    declared: dict[str, Any]
    #: the declaration in canonical form (what identifies it in task identities), computed once
    canonical: str = field(default="", compare=False, repr=False)

    @property
    def name(self) -> str:
        return self.rule.name

    def declaration(self) -> dict[str, Any]:
        """The declaration as written: ``{name: ..., parameters given}``."""
        return {"name": self.rule.name, **self.declared}

    def build(self) -> "DecisionRule":
        """A new rule with these parameters."""
        return self.rule.from_params(self.params)


def rule_spec(spec: "dict[str, Any] | str | RuleSpec") -> RuleSpec:
    """The validated declaration ``spec`` (``{name: ..., params}`` or a name); :class:`RuleError`
    naming every field in the wrong."""
    if isinstance(spec, RuleSpec):
        return spec
    if not isinstance(spec, (str, dict)):
        msg = f"a decision rule is a name or a mapping such as {{name: majority, n: 5}}, got {spec!r}"
        raise RuleError(msg, [((), msg)])
    d = {"name": spec} if isinstance(spec, str) else dict(spec)
    cls = rule_class(d.pop("name", None))
    try:
        return RuleSpec(cls, cls.Params.model_validate(d), d, canonical_json({"name": cls.name, **d}))
    except ValidationError as e:
        issues = [_issue(err, cls.Params) for err in e.errors()]
        text = "; ".join(f"{'.'.join(map(str, loc)) or '(rule)'}: {msg}" for loc, msg in issues)
        raise RuleError(f"decision rule {cls.name!r}: {text}", issues) from None


def _issue(err: Any, model: type[RuleParams]) -> tuple[tuple, str]:
    """One pydantic error as ``(location, message)``: an unknown field with the nearest names, a
    value shown beside what it should be."""
    loc, msg = tuple(err["loc"]), str(err["msg"]).removeprefix("Value error, ")
    at = (err.get("ctx") or {}).get("error")
    if isinstance(at, FieldProblem):
        loc += (at.field,)
    if err["type"] == "extra_forbidden":
        fields = list(model.model_fields)
        return loc, f"unknown field{did_you_mean(str(loc[-1]), fields)} (allowed: {', '.join(fields)})"
    if err["type"] == "missing":
        return loc, "missing required field"
    value = err.get("input")
    if err["type"] != "value_error" and (isinstance(value, (str, int, float, bool)) or value is None):
        msg = f"{msg}, got {value!r}"
    return loc, msg


def make_rule(spec: RuleSpec | dict[str, Any] | str | None, threshold: float = 0.5) -> DecisionRule:
    """A rule from its validated declaration (:class:`RuleSpec`), or from a declaration (``{name: ...,
    params}`` or a name) validated first (:func:`rule_spec`); None: ``max`` with ``threshold``."""
    if spec is None:
        return MaxRule(threshold=threshold)
    return (spec if isinstance(spec, RuleSpec) else rule_spec(spec)).build()


def rule_defaults(name: str) -> dict[str, Any]:
    """The parameters of rule ``name`` that have a default, with it ({} for a rule not registered)."""
    if name not in RULES:
        return {}
    fields = RULES.get(name).Params.model_fields
    return {k: f.default for k, f in fields.items() if not f.is_required()}


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


def fitted_declaration(spec: RuleSpec | dict[str, Any] | str, captures: Sequence[np.ndarray], labels: Sequence[str],
                       sensor: Any) -> dict[str, Any]:
    """The declaration ``spec`` fitted on training ``captures``: the declaration as written with the
    fitted level written in as ``level`` (the gate's and onset's ``level: auto``), which ``make_rule``
    builds again into a rule deciding as the fitted one."""
    r = rule_spec(spec)
    fitted = getattr(r.build().fit(captures, labels, sensor), "fitted_level", None)
    return {**r.declaration(), "level": fitted} if fitted is not None else r.declaration()


def needs_fitting(rule: DecisionRule) -> bool:
    """Whether ``rule`` still needs a level chosen on training captures (``level: auto``, not fitted)."""
    return getattr(rule, "level", None) == "auto" and not hasattr(rule, "fitted_level")


class MaxParams(RuleParams):
    threshold: Fraction = Field(0.5, description="the least probability of the most probable class to name it "
                                "(0: always the most probable class).")


@RULES.register("max", description="the most probable class, none under the threshold")
class MaxRule(DecisionRule):
    """The most probable class, or the none label when its probability is under ``threshold``.

    Examples
    --------
    >>> rule = MaxRule(threshold=0.5)
    >>> rule.start(["a", "b", "c"], none_label="none", frame_rate=54.0)
    >>> rule.decide([0.2, 0.7, 0.1]), rule.decide([0.4, 0.3, 0.3])
    ('b', 'none')
    """

    name = "max"
    Params = MaxParams

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


class GateParams(RuleParams):
    idle: ClassName = Field(description="the idle class (in a stream evaluation, the scheme's ``idle``).")
    level: Level = Field("auto", description="the peak contact, a fraction of the sensor's value range in [0, 1], "
                         "under which the gate decides idle; ``auto``: chosen on the training captures (``fit``).")
    gate_s: PositiveSeconds = Field(0.25, description="the newest seconds whose peak the gate reads.")
    threshold: Fraction = Field(0.0, description="the least probability of the class named (0: always one).")


@RULES.register("gate", description="a rest/contact gate decides idle before the classifier; else the best "
                "non-idle class")
class GateRule(DecisionRule):
    """A rest/contact gate: the idle class without the classifier while the newest ``gate_s``
    seconds' peak contact is under ``level``; otherwise the most probable class other than idle.
    """

    name = "gate"
    Params = GateParams
    gates = True

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


class MajorityParams(RuleParams):
    n: Annotated[int, Strict(), Field(ge=1)] = Field(5, description="how many of the latest decisions vote "
                                                     "(1: ``max`` itself).")
    threshold: Fraction = Field(0.5, description="``max``'s threshold.")


@RULES.register("majority", description="the most frequent of the last n decisions of max (smoothing)")
class MajorityRule(MaxRule):
    """The most frequent of the last ``n`` decisions of ``max`` (ties: the most recent of the tied
    labels).

    Examples
    --------
    >>> rule = MajorityRule(n=3)
    >>> rule.start(["a", "b"], none_label="none", frame_rate=54.0)
    >>> [rule.decide(p) for p in ([0.9, 0.1], [0.2, 0.8], [0.3, 0.7], [0.9, 0.1])]
    ['a', 'b', 'b', 'b']
    """

    name = "majority"
    Params = MajorityParams

    def start(self, classes: np.ndarray, none_label: str, frame_rate: float, sensor: Any = None) -> None:
        super().start(classes, none_label, frame_rate, sensor)
        self._last: deque[str] = deque(maxlen=self.n)

    def decide(self, p: np.ndarray) -> str:
        self._last.append(super().decide(p))
        counts = Counter(self._last)
        top = max(counts.values())
        return next(label for label in reversed(self._last) if counts[label] == top)


class HmmParams(RuleParams):
    switch: Fraction = Field(0.05, description="the probability per hop of moving to another class (0: the "
                             "first decision's class is kept as long as every class has some probability).")
    threshold: Fraction = Field(0.5, description="the least filtered probability of the class named.")


@RULES.register("hmm", description="forward filtering over the classes with a sticky transition (smoothing)")
class HmmRule(MaxRule):
    """Forward filtering over the classes: a hidden Markov model whose state stays with probability
    ``1 - switch`` per hop and moves to each other class with ``switch / (C - 1)``; the most probable
    class of the filtered posterior, or the none label under ``threshold``.
    """

    name = "hmm"
    Params = HmmParams

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
