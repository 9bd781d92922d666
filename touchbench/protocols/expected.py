"""The paper numbers a protocol compares against (``expected:``): accuracies, standard
deviations, confusion matrices and the best value of a parameter grid."""

from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import Field, field_validator, model_validator

from .entries import _Model
from .errors import _ErrorAt
from .specs import AuditVariant


CAUSE_KINDS = ("measured", "ruled_out", "unexplained")
#: what a shell reads as more than one command's arguments: a cause's command is one touchbench command
SHELL_METACHARACTERS = (";", "&&", "||", "|", "$(", "`", ">", "<")


def _touchbench_command(loc: tuple, command: str | None) -> None:
    if command is None:
        return
    if not command.startswith("touchbench "):
        raise _ErrorAt(loc, f"a command is a touchbench command (starting 'touchbench '), got {command!r}")
    found = [m for m in SHELL_METACHARACTERS if m in command]
    if found:
        raise _ErrorAt(loc, f"a command is one touchbench command, without shell operators: {command!r} has "
                            f"{' '.join(repr(m) for m in found)}; give the one command (its output goes in output "
                            "or gave)")


#: The rule that tells a ruled-out cause from an unexplained one, as REPORT.md prints it.
KIND_RULE = (
    "A number outside tolerance is *measured* when a command isolates its cause (the command and what it gave); "
    "*ruled out* when at least one candidate was run on this very row (a touchbench command that runs the row's "
    "features and classifier with the candidate changed; `row` gives what the row gave) and left the row outside "
    "tolerance: that candidate is excluded and the cause is open; *unexplained* otherwise: nothing was run on "
    "this row, or only on other rows, in a note, or with a result within tolerance (a candidate, not excluded).")


class RuledOut(_Model):
    """One candidate cause tried: what was tried, where to see it (the ``touchbench`` command that
    runs it, or else the ``source`` that reports it, such as a note under ``docs/research/``) and
    what it gave. ``row``: this row's accuracy (%) in the command's own run of this row with the
    candidate changed (of several settings, the one nearest the paper's number); a candidate whose
    ``row`` is outside the row's tolerance is excluded (:data:`KIND_RULE`). ``variant``: when the
    command is the protocol's leakage audit, the variant whose figure ``row`` is, so that a report
    which ran the audit gives this run's figure beside the one cited (the same code, data and seed
    can train a network to other weights on another machine, and so to another accuracy)."""

    tried: str = Field(min_length=1)
    command: str | None = Field(default=None, min_length=1)
    source: str | None = Field(default=None, min_length=1)
    gave: str = Field(min_length=1)
    row: float | None = None
    variant: AuditVariant | None = None

    @model_validator(mode="after")
    def _where(self) -> "RuledOut":
        if (self.command is None) == (self.source is None):
            raise _ErrorAt(("command",), "give one of command (the touchbench command that tried it) or source "
                                         "(where it is reported)")
        _touchbench_command(("command",), self.command)
        if self.row is not None and self.command is None:
            raise _ErrorAt(("row",), "row is what a run of this row gave: it needs the command that ran it "
                                     "(a source reports, it does not run the row)")
        if self.variant is not None and (self.row is None or not (self.command or "").startswith("touchbench audit ")):
            raise _ErrorAt(("variant",), "variant names the leakage audit's variant that gave row: it needs row and "
                                         "the command that ran the audit (touchbench audit PROTOCOL)")
        return self

    def this_run(self, audit: dict[str, float]) -> float | None:
        """This run's figure of the audit ``variant`` this candidate cites (``audit``: variant ->
        accuracy % of the row's method), where it rounds otherwise than the cited ``row``; else None."""
        fresh = audit.get(self.variant) if self.variant is not None and self.row is not None else None
        return fresh if fresh is not None and round(fresh, 1) != round(self.row, 1) else None

    def excludes(self, value: float, tolerance: float) -> bool:
        """Whether this candidate is excluded for a paper number ``value``: a run of the row that left
        it outside ``tolerance``."""
        return self.row is not None and abs(self.row - value) > tolerance


class Cause(_Model):
    """Why ours differs from a paper's number, and how well that is known (``kind``):

    - ``measured``: ``text`` is the cause, ``command`` the ``touchbench`` command that isolates it
      and ``output`` what it gave;
    - ``ruled_out``: the cause is open; ``ruled_out`` lists the candidates tried, at least one of
      them excluded by a run of this row (:data:`KIND_RULE`, checked by :class:`Expected`), ``text``
      what is left;
    - ``unexplained``: no cause known; no candidate excluded by a run of this row; ``text`` and
      ``ruled_out`` may say what was tried.
    """

    kind: Literal["measured", "ruled_out", "unexplained"]
    text: str | None = Field(default=None, min_length=1)
    command: str | None = Field(default=None, min_length=1)
    output: str | None = Field(default=None, min_length=1)
    ruled_out: list[RuledOut] = Field(default_factory=list)

    @model_validator(mode="before")
    @classmethod
    def _kind_given(cls, v: Any) -> Any:
        if isinstance(v, dict) and "kind" not in v:
            raise _ErrorAt(("kind",), f"a cause needs its kind: one of {', '.join(CAUSE_KINDS)}")
        return v

    @model_validator(mode="after")
    def _complete(self) -> "Cause":
        if self.kind == "measured":
            for name in ("text", "command", "output"):
                if getattr(self, name) is None:
                    raise _ErrorAt((name,), f"a measured cause needs {name}: " + _MEASURED[name])
            _touchbench_command(("command",), self.command)
            return self
        for name in ("command", "output"):
            if getattr(self, name) is not None:
                raise _ErrorAt((name,), f"{name} belongs to a measured cause; this cause is {self.kind}: list "
                                        "each thing tried under ruled_out, with its own command or source")
        if self.kind == "ruled_out" and not self.ruled_out:
            raise _ErrorAt(("ruled_out",), "a ruled_out cause lists what was excluded: "
                                           "ruled_out: [{tried, command or source, gave}]")
        return self


_MEASURED = {"text": "what the cause is", "command": "the touchbench command that isolates it",
             "output": "what that command printed or gave"}


class ExpectedResult(_Model):
    """One number from a paper: a feature combination x classifier, in percent.

    ``cause`` says why ours differs from the paper's number and of which kind
    that knowledge is (:class:`Cause`): measured, ruled out or unexplained.
    """

    features: list[str] = Field(min_length=1)
    classifier: str
    value: float
    metric: Literal["accuracy", "balanced_accuracy", "macro_f1"] | None = None
    tolerance: float | None = Field(default=None, ge=0)
    group: str | None = None
    source: str | None = None
    cause: Cause | None = None

    @field_validator("features", mode="before")
    @classmethod
    def _split(cls, v: Any) -> Any:
        if isinstance(v, str):
            return v.split("+")
        return v

    @model_validator(mode="before")
    @classmethod
    def _cause_form(cls, v: Any) -> Any:
        if not isinstance(v, dict):
            return v
        if isinstance(v.get("cause"), str):
            raise _ErrorAt(("cause",), "a cause is a mapping with its kind: {kind: measured, text, command, "
                                       "output}, {kind: ruled_out, ruled_out: [...]} or {kind: unexplained} "
                                       "(a cause as text, with measured_by, is the former form)")
        if "measured_by" in v:
            raise _ErrorAt(("measured_by",), "measured_by is now a measured cause's command: "
                                             "cause: {kind: measured, text, command, output}")
        return v


def _count(n: int, noun: str) -> str:
    return f"{n} {noun}{'' if n == 1 else 's'}"


class ExpectedDeviation(_Model):
    """A standard deviation a paper gives for one classifier's accuracy over
    the folds, in percentage points; ours is the sample standard deviation
    (ddof 1) of the accuracy of that classifier's folds."""

    classifier: str  # a classifier entry's label
    value: float = Field(ge=0)
    tolerance: float = Field(ge=0)  # percentage points
    source: str  # the table or figure


class ExpectedConfusion(_Model):
    """A confusion matrix as a paper prints it (counts of captures), compared
    per class: the paper's recall of each class against ours, from one
    classifier's predictions pooled over the folds.

    ``rows`` says what the printed rows are: ``predicted`` (the columns are
    then the true class) or ``true``. ``classes`` is the order of the rows
    and of the columns; ``matrix`` has one row per class, each with one count
    per class.
    """

    classifier: str  # a classifier entry's label
    source: str  # the table or figure
    tolerance: float = Field(ge=0)  # percentage points of per-class recall
    rows: Literal["predicted", "true"]
    classes: list[str] = Field(min_length=2)
    matrix: list[list[Annotated[int, Field(ge=0)]]]

    @model_validator(mode="after")
    def _square(self) -> "ExpectedConfusion":
        k = len(self.classes)
        twice = sorted({c for c in self.classes if self.classes.count(c) > 1})
        if twice:
            raise _ErrorAt(("classes",), f"each class once: {', '.join(twice)} repeated")
        if len(self.matrix) != k:
            raise _ErrorAt(("matrix",), f"{_count(len(self.matrix), 'row')} for {k} classes: one row per class, "
                                        f"in the order of 'classes'")
        for i, row in enumerate(self.matrix):
            if len(row) != k:
                raise _ErrorAt(("matrix", i), f"row {i + 1} ({self.classes[i]}) has {_count(len(row), 'count')} "
                                              f"for {k} classes: the matrix is square, one column per class")
        return self


class ExpectedBest(_Model):
    """The value of a swept parameter (a ``{grid: [...]}`` of a classifier)
    that gave a paper its best accuracy; ours is the grid entry with the best
    mean accuracy over the folds."""

    classifier: str  # the classifier's registered name
    parameter: str
    value: Any
    source: str  # the table or figure


class Expected(_Model):
    """Paper numbers the report compares against (``value`` in percent).

    ``results`` are single numbers (accuracies); ``standard_deviations``,
    ``confusions`` and ``best_parameters`` the papers' other numbers. Every
    one names its table or figure in ``source``.
    """

    metric: Literal["accuracy", "balanced_accuracy", "macro_f1"] = "accuracy"
    tolerance: float = Field(default=3.0, ge=0)
    aggregate: Literal["mean", "pooled"] = "mean"
    source: str | None = None
    results: list[ExpectedResult] = Field(default_factory=list)
    standard_deviations: list[ExpectedDeviation] = Field(default_factory=list)
    confusions: list[ExpectedConfusion] = Field(default_factory=list)
    best_parameters: list[ExpectedBest] = Field(default_factory=list)

    @model_validator(mode="after")
    def _not_empty(self) -> "Expected":
        if not (self.results or self.standard_deviations or self.confusions or self.best_parameters):
            raise ValueError("no paper numbers: give results, standard_deviations, confusions or best_parameters")
        for i, r in enumerate(self.results):
            _kind_follows_the_rule(i, r, self.tolerance if r.tolerance is None else r.tolerance)
        return self


def kind_by_rule(cause: Cause, value: float, tolerance: float) -> str:
    """The kind :data:`KIND_RULE` gives ``cause`` of a paper number ``value``: measured as declared,
    else ruled out when a candidate is excluded by a run of the row, else unexplained."""
    if cause.kind == "measured":
        return "measured"
    return "ruled_out" if any(t.excludes(value, tolerance) for t in cause.ruled_out) else "unexplained"


def _kind_follows_the_rule(i: int, r: ExpectedResult, tolerance: float) -> None:
    """A declared kind other than the rule's is refused, naming the field and why."""
    if r.cause is None:
        return
    kind = kind_by_rule(r.cause, r.value, tolerance)
    if kind == r.cause.kind:
        return
    if kind == "ruled_out":
        why = ("a candidate is excluded by a run of this row (a ruled_out entry whose row is more than "
               f"{tolerance:g} points from {r.value:g}): the cause is ruled_out")
    else:
        why = ("no candidate is excluded by a run of this row (no ruled_out entry with a command and a row "
               f"more than {tolerance:g} points from {r.value:g}): the cause is unexplained")
    raise _ErrorAt(("results", i, "cause", "kind"), f"kind {r.cause.kind}, but {why}")
