"""What a protocol's methods are evaluated on and how: the dataset (:class:`DatasetSpec`), the
scheme (:class:`SchemeSpec`), the design data (:class:`DesignSpec`), the leaderboard's extra
columns (:class:`ReportSpec`), the evaluations
(:class:`EvaluationSpec`) and the leakage audit (:class:`AuditSpec`)."""

from __future__ import annotations

import re
from typing import Any, Literal, get_args

from pydantic import BaseModel, ConfigDict, Field, field_validator, model_validator

from ..datasets.registry import WRITE_LOCATIONS
from .entries import _Model, _registry_check
from .errors import _ErrorAt
from .schemes import SPLITTERS

_NAME_RE = re.compile(r"^[A-Za-z0-9][A-Za-z0-9._-]*$")


def _folder_name(v: str) -> str:
    """A protocol's or an evaluation's name: it names the results folder."""
    if not _NAME_RE.match(v):
        raise ValueError(f"name {v!r} must be letters, digits, '.', '_' or '-' (it names the results folder)")
    return v


def _coerce_str_lists(v: Any) -> Any:
    """A mapping of column -> values (filters, design rows) with every value list coerced."""
    if isinstance(v, dict):
        return {k: _coerce_str_list(x) for k, x in v.items()}
    return v


def _coerce_str_list(v: Any) -> Any:
    if isinstance(v, (str, int, float, bool)):
        return [str(v)]
    if isinstance(v, list):
        return [x if isinstance(x, (dict, list)) else str(x) for x in v]
    return v


class DatasetSpec(_Model):
    """Which captures: a dataset reference and metadata filters."""

    name: str = Field(min_length=1)
    #: a registered file format (``haart-raw``, ``table``...): ``name`` is then a file or folder its
    #: reader reads, with ``options`` as the reader's options
    format: str | None = None
    filters: dict[str, list[str]] = Field(default_factory=dict)
    exclude: dict[str, list[str]] = Field(default_factory=dict)
    options: dict[str, Any] = Field(default_factory=dict)

    _lists = field_validator("filters", "exclude", mode="before")(_coerce_str_lists)

    @model_validator(mode="after")
    def _reads_only(self) -> "DatasetSpec":
        for k in self.options:
            if k in WRITE_LOCATIONS:
                raise _ErrorAt(("options", k), f"a protocol cannot choose where touchbench writes: remove {k}; "
                                               "set the TOUCHBENCH_CACHE_DIR environment variable to move the cache")
        return self


class SchemeSpec(BaseModel):
    """``name`` of a registered scheme; the other keys are its parameters."""

    model_config = ConfigDict(extra="allow")
    name: str

    @field_validator("name")
    @classmethod
    def _known(cls, v: str) -> str:
        return _registry_check(SPLITTERS, v)

    @property
    def params(self) -> dict[str, Any]:
        return dict(self.model_extra or {})


class DesignSpec(_Model):
    """The data its methods were designed on (features, parameters chosen by looking at it).

    ``subjects`` (or any metadata ``rows``: ``{split: [train]}``) name the
    captures; ``methods`` the labels of the entries designed on them (empty:
    every entry). The leaderboard then gives, beside each method's usual
    figure, its accuracy on the captures outside the design data, and marks
    the usual figure of a designed method as including them.
    """

    subjects: list[str] = Field(default_factory=list)
    rows: dict[str, list[str]] = Field(default_factory=dict)
    methods: list[str] = Field(default_factory=list)
    note: str = ""

    _strs = field_validator("subjects", "methods", mode="before")(_coerce_str_list)

    _lists = field_validator("rows", mode="before")(_coerce_str_lists)

    @model_validator(mode="after")
    def _some_rows(self) -> "DesignSpec":
        if not self.subjects and not self.rows:
            raise ValueError("design needs subjects (or rows): the data the methods were designed on")
        return self

    def filters(self) -> dict[str, list[str]]:
        """The design data as metadata filters (a capture is design data when it matches all)."""
        return {**({"subject": list(self.subjects)} if self.subjects else {}), **self.rows}


def design_blocks(design: "DesignSpec | list[DesignSpec] | None") -> list[DesignSpec]:
    """A protocol's ``design`` as a list of blocks: methods designed on different data (one block
    per kind of design data) are declared as a list, one method in one block at most."""
    if design is None:
        return []
    return list(design) if isinstance(design, list) else [design]


def _one_block_a_method(design: "DesignSpec | list[DesignSpec] | None") -> "DesignSpec | list[DesignSpec] | None":
    blocks = design_blocks(design)
    if len(blocks) > 1:
        if any(not b.methods for b in blocks):
            raise ValueError("several design blocks each name their methods (methods: [...])")
        seen: set[str] = set()
        for b in blocks:
            twice = sorted(seen & set(b.methods))
            if twice:
                raise ValueError(f"method(s) {twice} are in two design blocks: one block a method")
            seen |= set(b.methods)
    return design


class ReportSpec(_Model):
    """Columns the leaderboard adds to the evaluation's table (:mod:`touchbench.reports.breakdown`):
    the recall of each class of ``recall`` (a value of the target), and the accuracy on the test
    captures of each value of each metadata column of ``by`` (``cover``...). Results do not
    depend on it."""

    recall: list[str] = Field(default_factory=list)
    by: list[str] = Field(default_factory=list)

    _strs = field_validator("recall", "by", mode="before")(_coerce_str_list)

    @model_validator(mode="after")
    def _something(self) -> "ReportSpec":
        if not self.recall and not self.by:
            raise ValueError("report needs recall (classes) or by (metadata columns): report: {recall: [notouch]}")
        for field_name in ("recall", "by"):
            if len(set(getattr(self, field_name))) != len(getattr(self, field_name)):
                raise _ErrorAt((field_name,), "a value is named twice")
        return self


class EvaluationSpec(_Model):
    """One (dataset, scheme) pair a protocol's methods are evaluated under; results in
    ``<results>/<protocol>/<name>/``. Fields not given are the protocol's."""

    name: str
    dataset: DatasetSpec | None = None
    scheme: SchemeSpec
    target: str | None = None
    repetitions: int | None = Field(default=None, ge=1)
    design: DesignSpec | list[DesignSpec] | None = None
    report: ReportSpec | None = None

    _design_ok = field_validator("design")(_one_block_a_method)

    @model_validator(mode="before")
    @classmethod
    def _shorthands(cls, d: Any) -> Any:
        if isinstance(d, dict):
            d = dict(d)
            for k in ("dataset", "scheme"):
                if isinstance(d.get(k), str):
                    d[k] = {"name": d[k]}
        return d

    _name_ok = field_validator("name")(_folder_name)


#: the leakage audit's variants (:mod:`touchbench.engine.audit`), in the order it runs them
AuditVariant = Literal["honest", "capture-kfold", "window-kfold", "subject-id", "tuned-on-test", "stopped-on-test"]
AUDIT_VARIANTS: tuple[str, ...] = get_args(AuditVariant)


class AuditSpec(_Model):
    """How ``touchbench audit`` and ``papers reproduce --audit`` audit this protocol: the leaky
    variants to run, the folds of the k-fold ones, the window of window-kfold, the grid tuned on test."""

    variants: list[AuditVariant] = Field(default_factory=lambda: list(AUDIT_VARIANTS))
    k: int = Field(default=10, ge=2)
    window_seconds: float = Field(default=2.0, gt=0)
    tune: dict[str, list[Any]] = Field(default_factory=dict)


#: fields an evaluation may set for itself (the protocol's are the default)
EVALUATION_FIELDS = ("dataset", "scheme", "target", "repetitions", "design", "report")
