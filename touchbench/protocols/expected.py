"""The paper numbers a protocol compares against (``expected:``): accuracies, standard
deviations, confusion matrices and the best value of a parameter grid."""

from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import Field, field_validator, model_validator

from .entries import _Model
from .errors import _ErrorAt


class ExpectedResult(_Model):
    """One number from a paper: a feature combination x classifier, in percent.

    ``cause`` says why ours differs from the paper's number, as measured, and
    ``measured_by`` the ``touchbench`` command that measured it: the two come
    together (a cause nobody can rerun is not a measured one).
    """

    features: list[str] = Field(min_length=1)
    classifier: str
    value: float
    metric: Literal["accuracy", "balanced_accuracy", "macro_f1"] | None = None
    tolerance: float | None = Field(default=None, ge=0)
    group: str | None = None
    source: str | None = None
    cause: str | None = Field(default=None, min_length=1)
    measured_by: str | None = Field(default=None, min_length=1)

    @field_validator("features", mode="before")
    @classmethod
    def _split(cls, v: Any) -> Any:
        if isinstance(v, str):
            return v.split("+")
        return v

    @model_validator(mode="after")
    def _measured(self) -> "ExpectedResult":
        if self.cause is not None and self.measured_by is None:
            raise _ErrorAt(("cause",), "a cause needs measured_by: the touchbench command that measured it")
        if self.measured_by is not None and self.cause is None:
            raise _ErrorAt(("measured_by",), "measured_by needs a cause: what the command measured")
        if self.measured_by is not None and not self.measured_by.startswith("touchbench "):
            raise _ErrorAt(("measured_by",), f"measured_by is a touchbench command (starting 'touchbench '), "
                                             f"got {self.measured_by!r}")
        return self


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
        return self
