"""The protocol file: a YAML document validated by a pydantic schema.

A protocol names everything a benchmark run needs::

    name: haart-loso-msd-rf            # default: the file name without .yaml
    description: one line shown by `touchbench protocols list`
    dataset:                           # or just `dataset: haart`
      name: haart                      # registered name, scene:NAME, or a .parquet path
      filters: {gesture: [pat, rub]}   # keep only these values (any metadata column)
      exclude: {subject: [s03]}        # drop these values
      options: {}                      # keyword arguments of the loader / scene generator
    target: gesture                    # or subject (person identification, Flagg 2012), or any metadata column
    metrics: [f1_weighted]             # optional: scikit-learn scorer names, computed for every task
    scheme: {name: loso}               # or just `scheme: loso`; parameters beside name
    features:                          # a list of combinations; each is concatenated
      - [msd]
      - [sd, bmh]
      - [{name: smmhh, params: {...}}]
    classifiers:
      - gaus-rf
      - {name: gaus-rf, params: {n_estimators: 100}, label: rf100}
      - {name: cnn, params: {epochs: {grid: [10, 20]}}}   # a grid: one entry per value
    seed: 0                            # every randomness is derived from it
    repetitions: 1                     # the whole evaluation repeated with derived seeds
    expected:                          # optional: the paper's numbers, in percent
      metric: accuracy
      tolerance: 3.0                   # percentage points
      results:
        - {features: [msd], classifier: gaus-rf, value: 54.82}
      standard_deviations:             # of the accuracy over the folds
        - {classifier: gaus-rf, value: 13, tolerance: 5, source: Table 2}
      confusions:                      # a confusion matrix as printed
        - classifier: gaus-rf
          source: Table 6
          tolerance: 10                # points of per-class recall
          rows: predicted              # the paper's rows: predicted (or true) class
          classes: [pat, rub]          # the order of its rows and columns
          matrix: [[30, 2], [6, 34]]
      best_parameters:                 # the best value of a parameter grid
        - {classifier: cnn, parameter: L, value: 30, source: Fig. 5}

**Parameter grids.** A feature or classifier parameter written
``{grid: [v1, v2, ...]}`` expands to one entry per value (the cartesian
product when several parameters have grids). Expanded entries are labelled
``name(param=value)``. A plain list is a list-valued parameter, never a grid.

**Errors.** The YAML is composed with node positions, so every error names
the file, the line and the field: ``protocols/x.yaml:12: classifiers[1].name:
unknown classifier 'gaus-fr'; did you mean 'gaus-rf'?``. The file is read
with bounds (:mod:`touchbench.core.yamlsafe`: size, aliases, expanded
values, depth; duplicate keys refused). Validation happens in passes: the
shape (pydantic; ``repetitions`` at most :data:`MAX_REPETITIONS`), the
number of entries the grids expand to (at most :data:`MAX_ENTRIES`, counted
before anything is expanded), then the scheme's own parameters (each
scheme has a pydantic ``Params`` model), feature and classifier parameter
names (against the constructors) and values (the feature sets' own checks;
classifiers are built with their parameters and asked scikit-learn's
parameter validation; a missing optional extra is refused with its install
command), and the ``expected`` references. Checks that need the data
(filter values, metadata columns) run in :mod:`touchbench.engine.runner`
before any work and report through :meth:`Protocol.error_at`.
"""

from __future__ import annotations

import copy
import hashlib
import inspect
import itertools
import json
import math
import re
import typing
from pathlib import Path
from typing import Annotated, Any, Iterator, Literal

import yaml
from pydantic import (
    BaseModel,
    ConfigDict,
    Field,
    PrivateAttr,
    ValidationError,
    field_validator,
    model_validator,
)

from ..catalog import DatasetRef, dataset_ref_problem, format_ref_problem, parse_dataset_ref
from ..datasets.formats import FORMATS
from ..classifiers import CLASSIFIERS
from ..core.errors import TouchbenchError
from ..core.hashing import canonical_json
from ..core.suggest import did_you_mean
from ..core.versions import missing_extra
from ..core.yamlsafe import MAX_BYTES, load_bounded, yaml_problem
from ..datasets.registry import WRITE_LOCATIONS
from ..features import FEATURES
from ..features.base import FeatureInputError, SensorNeededError, make_feature_set
from ..methods import CAPTURES, METHODS, Method, features_label, resolve_entry
from ..methods.base import takes_captures
from .seeding import derive_seed
from .schemes import SPLITTERS, SplitError, Splitter, make_splitter

__all__ = [
    "ClassifierEntry",
    "did_you_mean",
    "FeatureCombination",
    "Protocol",
    "ProtocolError",
    "UnknownEvaluation",
    "canonical_json",
    "expand_grid",
    "load_protocol",
    "parse_protocol",
]

METRICS = ("accuracy", "balanced_accuracy", "macro_f1")
#: bounds checked before anything is expanded: a protocol is a plan of work,
#: and a typo (an extra zero, a grid of a grid) must not plan years of it
MAX_REPETITIONS = 1000
MAX_ENTRIES = 10_000  # feature combinations x classifier entries + methods, grids expanded
_NAME_RE = re.compile(r"^[A-Za-z0-9][A-Za-z0-9._-]*$")


class UnknownEvaluation(TouchbenchError):
    """An evaluation name the protocol does not have (``--evaluation``)."""


class ProtocolError(TouchbenchError):
    """An invalid protocol: every line names the file, line and field."""

    def __init__(self, message: str, issues: list[tuple[str, int | None, str, str]] | None = None):
        super().__init__(message)
        self.issues = issues or []


class _ErrorAt(ValueError):
    """Raised by a model validator about one of the model's fields (``loc``
    below the model), so that the error names that field's line."""

    def __init__(self, loc: tuple, message: str):
        super().__init__(message)
        self.loc = loc


# ----------------------------------------------------------------- helpers
def _is_grid(v: Any) -> bool:
    return isinstance(v, dict) and set(v) == {"grid"}


def expand_grid(params: dict[str, Any]) -> list[dict[str, Any]]:
    """Expand ``{p: {grid: [a, b]}}`` values into one parameter dict per combination.

    >>> expand_grid({"a": 1, "b": {"grid": [2, 3]}})
    [{'a': 1, 'b': 2}, {'a': 1, 'b': 3}]
    """
    keys = [k for k, v in params.items() if _is_grid(v)]
    if not keys:
        return [dict(params)]
    out = []
    for combo in itertools.product(*(params[k]["grid"] for k in keys)):
        d = dict(params)
        d.update(zip(keys, combo))
        out.append(d)
    return out


def _fmt_value(v: Any) -> str:
    return json.dumps(v, default=str) if not isinstance(v, str) else v


def _label(name: str, params: dict[str, Any], keys: list[str] | None = None) -> str:
    keys = sorted(params) if keys is None else keys
    if not keys:
        return name
    return f"{name}(" + ",".join(f"{k}={_fmt_value(params[k])}" for k in keys) + ")"


# ----------------------------------------------------------------- YAML with lines
def _nodes(root: yaml.Node | None) -> Iterator[tuple[tuple, yaml.Node, int]]:
    """(path, node, 1-based line) of every node of a composed YAML document, a mapping's keys by their
    key's line. The document comes from the bounded loader (``core.yamlsafe``): its aliases, once
    expanded, stand for a bounded number of nodes, and none is recursive, so this walk is bounded too."""
    stack = [((), root, root.start_mark.line + 1)] if root is not None else []
    while stack:
        path, node, line = stack.pop()
        yield path, node, line
        if isinstance(node, yaml.MappingNode):
            stack += [(path + (str(k.value),), v, k.start_mark.line + 1) for k, v in reversed(node.value)]
        elif isinstance(node, yaml.SequenceNode):
            stack += [(path + (i,), v, v.start_mark.line + 1) for i, v in reversed(list(enumerate(node.value)))]


def _line_map(root: yaml.Node | None) -> dict[tuple, int]:
    """Path (tuple of keys / indices) -> 1-based line of every node of a composed YAML document."""
    return {path: line for path, _, line in _nodes(root)}


def _boolean_map(root: yaml.Node | None) -> dict[tuple, str]:
    """Path -> what was written, for every value YAML read as a boolean (``no``, ``on``, ``yes``...)."""
    return {path: node.value for path, node, _ in _nodes(root)
            if isinstance(node, yaml.ScalarNode) and node.tag == "tag:yaml.org,2002:bool"}


def _boolean_hint(loc: tuple, booleans: dict[tuple, str]) -> str:
    """For an issue at ``loc`` on (or just above) a value YAML read as a boolean: what was written, quoted."""
    for at, text in booleans.items():
        if at == loc or (loc and at[:-1] == loc):
            return (f" ({text!r} was read as a YAML boolean, {text.lower() in _TRUE}: quote it, \"{text}\", "
                    "where a name or text is meant)")
    return ""


_TRUE = {"y", "yes", "true", "on"}


def _loc_str(loc: tuple) -> str:
    s = ""
    for part in loc:
        if isinstance(part, int):
            s += f"[{part}]"
        else:
            s += ("." if s else "") + str(part)
    return s or "(top level)"


# ----------------------------------------------------------------- models
class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid")


def _registry_check(reg, name: str) -> str:
    if name not in reg:
        raise ValueError(reg.suggest(name))
    return name


class FeatureRef(_Model):
    """One feature set of a combination: a registered name and its parameters."""

    name: str
    params: dict[str, Any] = Field(default_factory=dict)

    @field_validator("name")
    @classmethod
    def _known(cls, v: str) -> str:

        return _registry_check(FEATURES, v)


class ClassifierSpec(_Model):
    """A classifier entry: registered name, parameters (may hold grids), label.

    The name is a registered classifier, or a registered method
    (:data:`touchbench.methods.METHODS`, e.g. ``touch-et``): a method brings
    its own feature sets and takes the captures as recorded, so it is paired
    with the ``[raw-window]`` combination, and its parameters go to its
    estimator."""

    name: str
    params: dict[str, Any] = Field(default_factory=dict)
    label: str | None = None
    #: leaky variant: of the grid in ``params``, only the value with the best mean test accuracy
    #: is reported (see :class:`MethodRef`)
    tuned_on_test: bool = False

    @field_validator("name")
    @classmethod
    def _known(cls, v: str) -> str:

        return v if v in METHODS else _registry_check(CLASSIFIERS, v)

    @model_validator(mode="after")
    def _grid_to_tune(self) -> "ClassifierSpec":
        if self.tuned_on_test and not any(_is_grid(v) for v in self.params.values()):
            raise _ErrorAt(("tuned_on_test",), "tuned_on_test chooses among a grid: give a parameter {grid: [values]}")
        return self


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


class MethodRef(_Model):
    """An entry of ``methods:``: a registered method, or an inline pipeline.

    ``name``: a registered method (``touch-et``...), which brings its own
    feature sets and takes the captures as recorded, or a classifier that
    takes captures itself (``minirocket``, ``cnn``...); ``params`` go to its
    estimator. Or ``features`` (a combination, concatenated) and
    ``estimator`` (a registered classifier) with its ``params``. ``params``
    may hold grids; ``label`` names the entry in results.
    """

    name: str | None = None
    features: list[FeatureRef] | None = Field(default=None, min_length=1)
    estimator: str | None = None
    params: dict[str, Any] = Field(default_factory=dict)
    label: str | None = None
    #: leaky variant: each capture's subject (one-hot over the dataset's subjects) appended to the
    #: feature matrix, as Cang et al. 2015 did with the participant id
    subject_id_feature: bool = False
    #: leaky variant: of the grid in ``params``, only the value with the best mean test accuracy is
    #: reported (a parameter chosen on the test folds, as Al-mashhadani et al. chose the frame length)
    tuned_on_test: bool = False

    @model_validator(mode="after")
    def _variants(self) -> "MethodRef":
        if self.tuned_on_test and not any(_is_grid(v) for v in self.params.values()):
            raise _ErrorAt(("tuned_on_test",), "tuned_on_test chooses among a grid: give a parameter {grid: [values]}")
        if self.subject_id_feature and self.features is None and self.name is not None and self.name not in METHODS:
            raise _ErrorAt(("subject_id_feature",), f"{self.name!r} takes the captures themselves: no feature "
                                                    "matrix to append the subject id to")
        return self

    @model_validator(mode="before")
    @classmethod
    def _shorthand(cls, d: Any) -> Any:
        if isinstance(d, str):
            return {"name": d}
        if isinstance(d, dict) and isinstance(d.get("features"), list):
            d = {**d, "features": [{"name": f} if isinstance(f, str) else f for f in d["features"]]}
        return d

    @field_validator("name")
    @classmethod
    def _known_method(cls, v: str | None) -> str | None:
        if v is None or v in METHODS or takes_captures(v):
            return v
        capture_estimators = [n for n in CLASSIFIERS.names() if takes_captures(n)]
        names = sorted([*METHODS.names(), *capture_estimators])
        raise ValueError(f"unknown method {v!r}{did_you_mean(v, names)} (registered methods: "
                         f"{', '.join(METHODS.names())}; estimators that take captures: {', '.join(capture_estimators)})")

    @field_validator("estimator")
    @classmethod
    def _known_estimator(cls, v: str | None) -> str | None:
        return None if v is None else _registry_check(CLASSIFIERS, v)

    @model_validator(mode="after")
    def _one_form(self) -> "MethodRef":
        if (self.name is None) == (self.estimator is None) or (self.estimator is None) != (self.features is None):
            raise ValueError("a method entry is either a registered method (name) or an inline pipeline "
                             "(features and estimator)")
        return self


class FeatureCombination(BaseModel):
    """An expanded feature combination: concatenation of (name, params) sets."""

    label: str
    sets: list[tuple[str, dict[str, Any]]]

    @property
    def names(self) -> list[str]:
        return [n for n, _ in self.sets]


class ClassifierEntry(BaseModel):
    """An expanded classifier entry (one value of every grid)."""

    label: str
    name: str
    params: dict[str, Any]
    #: the leaky variants of a ``methods:`` entry (see :class:`MethodRef`)
    subject_id_feature: bool = False
    #: the entry whose grid is chosen on test accuracy (its label without the grid), "" otherwise
    tuned_on_test: str = ""


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

    @field_validator("subjects", "methods", mode="before")
    @classmethod
    def _strs(cls, v: Any) -> Any:
        return _coerce_str_list(v)

    _lists = field_validator("rows", mode="before")(_coerce_str_lists)

    @model_validator(mode="after")
    def _some_rows(self) -> "DesignSpec":
        if not self.subjects and not self.rows:
            raise ValueError("design needs subjects (or rows): the data the methods were designed on")
        return self

    def filters(self) -> dict[str, list[str]]:
        """The design data as metadata filters (a capture is design data when it matches all)."""
        return {**({"subject": list(self.subjects)} if self.subjects else {}), **self.rows}


class EvaluationSpec(_Model):
    """One (dataset, scheme) pair a protocol's methods are evaluated under; results in
    ``<results>/<protocol>/<name>/``. Fields not given are the protocol's."""

    name: str
    dataset: DatasetSpec | None = None
    scheme: SchemeSpec
    target: str | None = None
    repetitions: int | None = Field(default=None, ge=1)
    design: DesignSpec | None = None

    @model_validator(mode="before")
    @classmethod
    def _shorthands(cls, d: Any) -> Any:
        if isinstance(d, dict):
            d = dict(d)
            for k in ("dataset", "scheme"):
                if isinstance(d.get(k), str):
                    d[k] = {"name": d[k]}
        return d

    @field_validator("name")
    @classmethod
    def _name_ok(cls, v: str) -> str:
        if not _NAME_RE.match(v):
            raise ValueError(f"name {v!r} must be letters, digits, '.', '_' or '-' (it names the results folder)")
        return v


class AuditSpec(_Model):
    """How ``touchbench audit`` and ``papers reproduce --audit`` audit this protocol: the leaky
    variants to run, the folds of the k-fold ones, the window of window-kfold, the grid tuned on test."""

    variants: list[Literal["honest", "capture-kfold", "window-kfold", "subject-id", "tuned-on-test"]] = Field(
        default_factory=lambda: ["honest", "capture-kfold", "window-kfold", "subject-id", "tuned-on-test"])
    k: int = Field(default=10, ge=2)
    window_seconds: float = Field(default=2.0, gt=0)
    tune: dict[str, list[Any]] = Field(default_factory=dict)


#: fields an evaluation may set for itself (the protocol's are the default)
EVALUATION_FIELDS = ("dataset", "scheme", "target", "repetitions", "design")


class Protocol(_Model):
    """A validated protocol. Build with :func:`load_protocol` / :func:`parse_protocol`."""

    name: str
    description: str = ""
    dataset: DatasetSpec
    target: str = Field(default="gesture", min_length=1)
    scheme: SchemeSpec
    #: several (dataset, scheme) pairs for the same methods (each its own results folder)
    evaluations: list[EvaluationSpec] = Field(default_factory=list)
    #: the evaluation this protocol is (set on the protocols :meth:`evaluation_protocols` gives)
    evaluation: str = ""
    design: DesignSpec | None = None
    #: the leakage audit of this protocol's methods (see :mod:`touchbench.engine.audit`)
    audit: AuditSpec | None = None
    features: list[list[FeatureRef]] | None = Field(default=None, min_length=1)
    classifiers: list[ClassifierSpec] | None = Field(default=None, min_length=1)
    methods: list[MethodRef] = Field(default_factory=list)
    seed: int = 0
    repetitions: int = Field(default=1, ge=1)
    expected: Expected | None = None
    #: scikit-learn scorer names computed for every task besides the three fixed metrics
    metrics: list[str] = Field(default_factory=list)

    _path: Path | None = PrivateAttr(default=None)
    _text: str = PrivateAttr(default="")
    _lines: dict[tuple, int] = PrivateAttr(default_factory=dict)
    _booleans: dict[tuple, str] = PrivateAttr(default_factory=dict)  # what YAML read as booleans, as written
    _subs: list["Protocol"] | None = PrivateAttr(default=None)

    @field_validator("metrics")
    @classmethod
    def _known_scorers(cls, v: list[str]) -> list[str]:
        from sklearn.metrics import get_scorer_names

        names = sorted(get_scorer_names())
        for name in v:
            if name not in names:
                raise ValueError(f"unknown metric {name!r}{did_you_mean(name, names)}: a scikit-learn scorer name "
                                 f"(sklearn.metrics.get_scorer_names(), e.g. f1_weighted, matthews_corrcoef, "
                                 f"neg_log_loss)")
        if len(set(v)) != len(v):
            raise ValueError("a metric is named twice")
        return v

    @field_validator("target")
    @classmethod
    def _target_name(cls, v: str) -> str:
        if v != v.strip() or not v:
            raise ValueError(f"target {v!r}: the name of a metadata column of the dataset (gesture, subject, cover...)")
        return v

    @field_validator("repetitions")
    @classmethod
    def _few_repetitions(cls, v: int) -> int:
        if v > MAX_REPETITIONS:
            raise ValueError(f"{v} repetitions: at most {MAX_REPETITIONS} (each repeats the whole evaluation)")
        return v

    @field_validator("name")
    @classmethod
    def _name_ok(cls, v: str) -> str:
        if not _NAME_RE.match(v):
            raise ValueError(f"name {v!r} must be letters, digits, '.', '_' or '-' (it names the results folder)")
        return v

    @model_validator(mode="before")
    @classmethod
    def _shorthands(cls, d: Any) -> Any:
        if not isinstance(d, dict):
            return d
        d = dict(d)
        evs = d.get("evaluations")
        if isinstance(evs, list) and evs and isinstance(evs[0], dict):  # the first evaluation's by default
            for k in ("dataset", "scheme"):
                if k not in d and k in evs[0]:
                    d[k] = evs[0][k]
        if isinstance(d.get("dataset"), str):
            d["dataset"] = {"name": d["dataset"]}
        if isinstance(d.get("scheme"), str):
            d["scheme"] = {"name": d["scheme"]}
        feats = d.get("features")
        if isinstance(feats, list):
            out = []
            for combo in feats:
                if isinstance(combo, (str, dict)):
                    combo = [combo]
                if isinstance(combo, list):
                    combo = [{"name": f} if isinstance(f, str) else f for f in combo]
                out.append(combo)
            d["features"] = out
        clfs = d.get("classifiers")
        if isinstance(clfs, list):
            d["classifiers"] = [{"name": c} if isinstance(c, str) else c for c in clfs]
        return d

    @model_validator(mode="after")
    def _methods_or_cross_product(self) -> "Protocol":
        if (self.features is None) != (self.classifiers is None):
            missing = "classifiers" if self.classifiers is None else "features"
            raise _ErrorAt((missing,), "features and classifiers go together (their cross product), "
                                       "or list methods: alone")
        if self.features is None and not self.methods:
            raise _ErrorAt(("methods",), "a protocol needs methods:, or features and classifiers")
        if self.features is None:
            self.features, self.classifiers = [], []
        return self

    # ----------------------------------------------------------- accessors
    @property
    def path(self) -> Path | None:
        return self._path

    @property
    def text(self) -> str:
        return self._text

    @property
    def text_hash(self) -> str:
        """SHA-256 of the protocol file's text."""
        return hashlib.sha256(self._text.encode()).hexdigest()

    def content(self) -> dict[str, Any]:
        """The validated protocol as plain data (what determines results)."""
        skip = {"description", "expected", "design", "audit"}
        if not self.evaluations:
            skip.add("evaluations")
        if not self.evaluation:
            skip.add("evaluation")
        return self.model_dump(mode="json", exclude=skip)

    def evaluation_protocols(self) -> list["Protocol"]:
        """One protocol per evaluation (the methods, seed and metrics shared; the evaluation's
        dataset, scheme, target, repetitions and design), or ``[self]`` without evaluations."""
        if not self.evaluations:
            return [self]
        if self._subs is None:
            base = self.model_dump(mode="python", exclude={"evaluations", "evaluation"})
            if not base.get("features"):  # methods: alone
                base.pop("features", None)
                base.pop("classifiers", None)
            subs = []
            for i, ev in enumerate(self.evaluations):
                data = dict(base, evaluation=ev.name)
                for k in EVALUATION_FIELDS:
                    v = getattr(ev, k)
                    if v is not None:
                        data[k] = v.model_dump(mode="python") if isinstance(v, BaseModel) else v
                sub = Protocol.model_validate(data)
                sub._path, sub._text = self._path, self._text
                at = ("evaluations", i)
                sub._lines, sub._booleans = ({**m, **{k[2:]: v for k, v in m.items()
                                                      if k[:2] == at and k[2:3] and k[2] in EVALUATION_FIELDS}}
                                             for m in (self._lines, self._booleans))
                subs.append(sub)
            self._subs = subs
        return self._subs

    def evaluations_named(self, names: "typing.Sequence[str]") -> list["Protocol"]:
        """The evaluations ``names`` (every one when empty), in the protocol's order; a name the
        protocol does not have is an :class:`UnknownEvaluation` naming the ones it has."""
        subs = self.evaluation_protocols()
        known = [s.evaluation for s in subs if s.evaluation]
        for name in names:
            if name not in known:
                where = f"(evaluations: {', '.join(known)})" if known else "(it has none: leave out --evaluation)"
                raise UnknownEvaluation(f"{name!r} is not an evaluation of protocol {self.name!r}"
                                        f"{did_you_mean(name, known)} {where}")
        return [s for s in subs if not names or s.evaluation in names]

    @property
    def content_hash(self) -> str:
        return hashlib.sha256(canonical_json(self.content()).encode()).hexdigest()

    def error_at(self, loc: tuple, message: str) -> ProtocolError:
        """A :class:`ProtocolError` at field ``loc`` (for checks that need the data)."""
        return _make_error(self._path, self._lines, [(loc, message)], self._booleans)

    def combinations(self) -> list[FeatureCombination]:
        """Feature combinations with parameter grids expanded."""
        out = []
        for combo in self.features:
            per_set = []
            for ref in combo:
                grid_keys = [k for k, v in ref.params.items() if _is_grid(v)]
                per_set.append([(ref.name, p, grid_keys) for p in expand_grid(ref.params)])
            for choice in itertools.product(*per_set):
                sets = [(n, p) for n, p, _ in choice]
                label = "+".join(_label(n, p, sorted(g)) if g else n for n, p, g in choice)
                out.append(FeatureCombination(label=label, sets=sets))
        # Entries that differ only in non-grid parameters get labels with all parameters.
        labels = [c.label for c in out]
        for c in out:
            if labels.count(c.label) > 1:
                c.label = "+".join(_label(n, p) for n, p in c.sets)
        return out

    def classifier_entries(self) -> list[ClassifierEntry]:
        """Classifier entries with parameter grids expanded."""
        out = []
        for spec in self.classifiers:
            grid_keys = sorted(k for k, v in spec.params.items() if _is_grid(v))
            for p in expand_grid(spec.params):
                base = spec.label or spec.name
                label = _label(base, p, grid_keys) if grid_keys else base
                out.append(ClassifierEntry(label=label, name=spec.name, params=p, tuned_on_test=(
                    f"{base} ({', '.join(grid_keys)} chosen on test)" if spec.tuned_on_test else "")))
        labels = [c.label for c in out]
        for c in out:
            if labels.count(c.label) > 1:
                c.label = _label(c.label, c.params)
        return out

    def _method_entries(self) -> list[tuple[int, FeatureCombination, ClassifierEntry]]:
        """The ``methods:`` entries (index, combination, classifier entry), grids expanded.

        A registered method, or an estimator on captures, stands beside the
        ``[raw-window]`` combination (the captures as recorded), exactly as
        ``features: [[raw-window]]`` with ``classifiers: [touch-et]`` reads;
        an inline pipeline has its own feature sets.
        """
        out = []
        for i, m in enumerate(self.methods):
            if m.name is not None:
                combo = FeatureCombination(label=CAPTURES, sets=[(CAPTURES, {})])
                name = m.name
            else:
                sets = [(f.name, f.params) for f in (m.features or [])]
                combo = FeatureCombination(label="+".join(_label(n, p) for n, p in sets), sets=sets)
                name = m.estimator or ""
            grid_keys = sorted(k for k, v in m.params.items() if _is_grid(v))
            base = (m.label or name) + ("+subject-id" if m.subject_id_feature else "")
            for p in expand_grid(m.params):
                out.append((i, combo, ClassifierEntry(label=_label(base, p, grid_keys) if grid_keys else base,
                                                      name=name, params=p, subject_id_feature=m.subject_id_feature,
                                                      tuned_on_test=f"{base} ({', '.join(grid_keys)} chosen on test)"
                                                      if m.tuned_on_test else "")))
        return out

    def _entry_pairs(self) -> list[tuple[FeatureCombination, ClassifierEntry, tuple]]:
        """Every (combination, classifier entry) pair as the protocol spells it, with its field:
        the ``features`` x ``classifiers`` cross product, then ``methods:`` (grids expanded)."""
        out = [(c, k, ("classifiers", self._classifier_index(k.name)))
               for c in self.combinations() for k in self.classifier_entries()]
        return out + [(c, k, ("methods", i)) for i, c, k in self._method_entries()]

    def evaluated_methods(self) -> list[Method]:
        """Every method the protocol evaluates, each spelling read into a :class:`Method`."""
        return [self._method(c, k, loc) for c, k, loc in self._entry_pairs()]

    def _classifier_index(self, name: str) -> int:
        """The index in ``classifiers:`` of the first entry named ``name`` (for error locations)."""
        return next((i for i, s in enumerate(self.classifiers) if s.name == name), 0)

    def _method(self, combo: FeatureCombination, clf: ClassifierEntry, loc: tuple) -> Method:
        """The method of one (combination, classifier entry) pair; a pairing that means nothing
        (a registered method beside feature sets of its own) is refused at ``loc``."""
        try:
            spec = resolve_entry(combo.sets, clf.name, clf.params)
        except TouchbenchError as e:
            raise self.error_at(loc, str(e)) from None
        frames = dict(combo.sets[0][1]).get("frames") if clf.name in METHODS else None
        return Method(label=clf.label, spec=spec, name=clf.name, params=dict(clf.params),
                      features_label=features_label(spec, combo.label), subject_id_feature=clf.subject_id_feature,
                      tuned_on_test=clf.tuned_on_test, input_frames=None if frames is None else int(frames))

    def features_label_of(self, names: list[str]) -> str:
        """The features label reports give the methods of the combination ``names`` (an
        ``expected`` reference names the combination as the protocol wrote it)."""
        key = "+".join(names)
        labels = {self._method(c, k, loc).features_label for c, k, loc in self._entry_pairs()
                  if c.names == list(names) or c.label == key}
        return labels.pop() if len(labels) == 1 else key

    def best_label(self, best: ExpectedBest) -> str:
        """The label of the classifier entry that ``best`` (an entry of
        ``expected.best_parameters``) says is the best, e.g. ``cnn(L=30)``."""
        for c in self.classifier_entries():
            if c.name == best.classifier and c.params.get(best.parameter) == best.value:
                return c.label
        raise self.error_at(("expected", "best_parameters"), f"no {best.classifier} entry with "
                                                             f"{best.parameter} = {best.value!r}")

    def splitter(self, repetition: int = 0) -> Splitter:
        """The scheme, seeded for ``repetition``."""

        params = self.scheme.params
        return make_splitter(self.scheme.name, target=self.target,
                             random_state=derive_seed(self.seed, "split", repetition), **params)


# ----------------------------------------------------------------- error mapping
def _best_line(lines: dict[tuple, int], loc: tuple) -> int | None:
    best = lines.get((), None)
    prefix: tuple = ()
    for part in loc:
        cand = prefix + (part if isinstance(part, int) else str(part),)
        if cand in lines:
            prefix = cand
            best = lines[cand]
        else:
            break
    return best


def _make_error(path: Path | None, lines: dict[tuple, int], issues: list[tuple[tuple, str]],
                booleans: dict[tuple, str] | None = None) -> ProtocolError:
    where = str(path) if path is not None else "<protocol>"
    rows, out = [], []
    for loc, msg in issues:
        msg += _boolean_hint(loc, booleans or {})
        line = _best_line(lines, loc) if loc else None
        loc_s = _loc_str(loc)
        rows.append((where, line, loc_s, msg))
        out.append(f"{where}{':' + str(line) if line else ''}: {loc_s}: {msg}")
    return ProtocolError("\n".join(out), rows)


def _model_fields_at(model: type[BaseModel], loc: tuple) -> list[str] | None:
    """Field names of the model reached by walking ``loc`` through annotations."""
    tp: Any = model
    for part in loc:
        tp = _unwrap(tp, part)
        if tp is None:
            return None
    if isinstance(tp, type) and issubclass(tp, BaseModel):
        return list(tp.model_fields)
    return None


def _unwrap(tp: Any, part: Any) -> Any:
    origin = typing.get_origin(tp)
    if origin in (typing.Union, getattr(__import__("types"), "UnionType", None)):
        args = [a for a in typing.get_args(tp) if a is not type(None)]
        return _unwrap(args[0], part) if len(args) == 1 else None
    if isinstance(tp, type) and issubclass(tp, BaseModel):
        f = tp.model_fields.get(str(part))
        return None if f is None else f.annotation
    if origin in (list, tuple) and isinstance(part, int):
        return typing.get_args(tp)[0]
    if origin is dict:
        return typing.get_args(tp)[1]
    return None


def _pydantic_issues(err: ValidationError, model: type[BaseModel], prefix: tuple = ()) -> list[tuple[tuple, str]]:
    issues = []
    for e in err.errors():
        loc = tuple(e["loc"])
        kind = e["type"]
        msg = e["msg"]
        if msg.startswith("Value error, "):
            msg = msg[len("Value error, "):]
        at = (e.get("ctx") or {}).get("error")
        if isinstance(at, _ErrorAt):
            loc += at.loc
        if kind == "missing":
            msg = "missing required field"
        elif kind == "extra_forbidden":
            fields = _model_fields_at(model, loc[:-1]) or []
            msg = f"unknown field{did_you_mean(str(loc[-1]), fields)}"
            if fields:
                msg += f" (allowed: {', '.join(fields)})"
        elif kind not in ("value_error", "assertion_error"):
            value = e.get("input")
            if isinstance(value, (str, int, float, bool)) or value is None:
                msg = f"{msg}, got {value!r}"
        issues.append((prefix + loc, msg))
    return issues


# ----------------------------------------------------------------- deeper passes
def _scheme_issues(spec: dict[str, Any], target: str, prefix: tuple) -> list[tuple[tuple, str]]:
    name = spec.get("name")
    if not isinstance(name, str) or name not in SPLITTERS:
        return [(prefix + ("name",), SPLITTERS.suggest(str(name)))]
    cls = SPLITTERS.get(name)
    params = {k: v for k, v in spec.items() if k != "name"}
    try:
        validated = cls.Params.model_validate(params)
    except ValidationError as e:
        return _pydantic_issues(e, cls.Params, prefix)
    key = cls.base_param  # a scheme that wraps another: that one is checked too
    if key is not None:
        base = dict(getattr(validated, key))
        if not isinstance(base.get("name"), str):
            return [(prefix + (key,), f"{key} must name a scheme: {key}: {{name: loso}}")]
        issues = _scheme_issues(base, target, prefix + (key,))
        if issues:
            return issues
    return []


def _accepted_params(obj: Any) -> tuple[list[str], bool]:
    """Parameter names a constructor / factory accepts, and whether it takes **kwargs."""
    names: list[str] = []
    var_kw = False
    try:
        sig = inspect.signature(obj)
    except (TypeError, ValueError):
        return names, True
    for p in sig.parameters.values():
        if p.kind is inspect.Parameter.VAR_KEYWORD:
            var_kw = True
        elif p.kind in (inspect.Parameter.POSITIONAL_OR_KEYWORD, inspect.Parameter.KEYWORD_ONLY):
            names.append(p.name)
    return names, var_kw


def _grid_size(params: dict[str, Any]) -> int:
    """How many entries ``params`` expands to (a grid that is not a list counts once: refused elsewhere)."""
    return math.prod(len(v["grid"]) if isinstance(v["grid"], list) else 1 for v in params.values() if _is_grid(v))


def _size_issues(protocol: Protocol) -> list[tuple[tuple, str]]:
    """The number of entries the protocol expands to, counted without expanding anything.

    Feature combinations x classifier entries + method entries, every grid
    expanded; more than :data:`MAX_ENTRIES` is refused at the largest grid.
    """
    sizes: list[tuple[int, tuple]] = []
    n_combos = 0
    for i, combo in enumerate(protocol.features):
        n = 1
        for j, ref in enumerate(combo):
            sizes.append((_grid_size(ref.params), ("features", i, j, "params")))
            n *= sizes[-1][0]
        n_combos += n
    n_clf = 0
    for i, spec in enumerate(protocol.classifiers):
        sizes.append((_grid_size(spec.params), ("classifiers", i, "params")))
        n_clf += sizes[-1][0]
    n_methods = 0
    for i, m in enumerate(protocol.methods):
        sizes.append((_grid_size(m.params), ("methods", i, "params")))
        n_methods += sizes[-1][0]
    total = n_combos * n_clf + n_methods
    if total <= MAX_ENTRIES:
        return []
    largest, loc = max(sizes, key=lambda x: x[0])
    shape = f"{n_combos} feature combination(s) x {n_clf} classifier entries" + (
        f" + {n_methods} method entries" if protocol.methods else "")
    return [(loc if largest > 1 else ("features",),
             f"the protocol expands to {total} entries ({shape}, grids expanded): at most {MAX_ENTRIES}"
             + (f"; this grid gives {largest}" if largest > 1 else "") + ": make the grids smaller or split the protocol")]


def _shape_issues(protocol: Protocol) -> list[tuple[tuple, str]]:
    """Empty filters and empty feature combinations (named by their key / index)."""
    issues = []
    for col, values in protocol.dataset.filters.items():
        if not values:
            issues.append((("dataset", "filters", col),
                           f"the {col} filter is empty: it would leave no captures; "
                           "list the values to keep, or remove the filter"))
    for i, combo in enumerate(protocol.features):
        if not combo:
            issues.append((("features", i), "this feature combination is empty: list at least one feature set"))
    combos = [(("features", i), combo) for i, combo in enumerate(protocol.features)]
    combos += [(("methods", i, "features"), m.features) for i, m in enumerate(protocol.methods) if m.features]
    for at, refs in combos:
        issues += _repeated_set_issues(at, refs)
    return issues


def _repeated_set_issues(at: tuple, refs: list[FeatureRef]) -> list[tuple[tuple, str]]:
    """A feature set listed twice with the same parameters in one combination, at its second place."""
    issues = []
    seen: dict[str, int] = {}
    for j, ref in enumerate(refs):
        key = canonical_json([ref.name, ref.params])
        if key in seen:
            issues.append((at + (j,), f"feature set {ref.name!r} is listed twice in this combination (also at "
                                      f"{_loc_str(at + (seen[key],))}): list each feature set once"))
        seen.setdefault(key, j)
    return issues


def _feature_value_issue(name: str, params: dict[str, Any]) -> str | None:
    """The feature set's own parameter checks (``_check_params``) for every grid value, without a sensor.

    A set that leaves a value to the sensor (``SensorNeededError``) is
    asked again by the plan, with the dataset's sensor."""
    for p in expand_grid(params):
        try:
            make_feature_set(name, p, None)._check_params()
        except SensorNeededError:
            continue
        except FeatureInputError as e:
            return str(e)
        except Exception as e:  # a value of the wrong type that the check did not foresee
            return f"feature set {name!r} rejects {p}: {type(e).__name__}: {e}"
    return None


def _feature_issues(protocol: Protocol) -> list[tuple[tuple, str]]:

    issues = []
    refs = [(("features", i, j), ref) for i, combo in enumerate(protocol.features) for j, ref in enumerate(combo)]
    refs += [(("methods", i, "features", j), ref) for i, m in enumerate(protocol.methods)
             for j, ref in enumerate(m.features or [])]
    for at, ref in refs:
        cls = FEATURES.get(ref.name)
        names, var_kw = _accepted_params(cls)
        names = [n for n in names if n not in ("self",)]
        n_before = len(issues)
        for k, v in ref.params.items():
            loc = at + ("params", k)
            if k == "sensor":
                issues.append((loc, "the engine passes the dataset's sensor; do not set 'sensor'"))
            elif not var_kw and k not in names:
                issues.append((loc, f"unknown parameter {k!r} for feature set {ref.name!r}"
                                    f"{did_you_mean(k, names)} (accepted: {', '.join(n for n in names if n != 'sensor') or 'none'})"))
            elif _is_grid(v) and not (isinstance(v["grid"], list) and v["grid"]):
                issues.append((loc + ("grid",), "a grid must be a non-empty list of values"))
        if len(issues) == n_before:
            problem = _feature_value_issue(ref.name, ref.params)
            if problem:
                issues.append((_param_loc(at + ("params",), ref.params, problem), problem))
    return issues


def _estimator_issues(name: str, params: dict[str, Any], loc: tuple, what: str) -> list[tuple[tuple, str]]:
    """Parameters of the classifier or named method ``name`` (a method's go to its estimator), at ``loc``."""
    est_name, base = _estimator_and_defaults(name)
    factory = CLASSIFIERS.get(est_name)
    extra = CLASSIFIERS.entry(est_name).tags.get("extra")
    missing = missing_extra(extra) if extra else []
    if missing:
        return [(loc, f"{what} {name!r} needs the optional {extra!r} extra, not installed here "
                      f"({', '.join(missing)} missing): pip install 'touchbench[{extra}]'")]
    issues = _reserved_param_issues(params, loc)
    issues += _unknown_param_issues(name, params, _estimator_param_names(factory), loc, what)
    if issues:
        return issues
    return _construction_issues(factory, base, name, params, loc, what)


def _estimator_and_defaults(name: str) -> tuple[str, dict[str, Any]]:
    """The classifier ``name`` builds and the parameters it sets: a named method's estimator and
    defaults, else ``name`` itself and none."""
    if name in METHODS:  # a named method's parameters go to its estimator
        tags = METHODS.entry(name).tags
        return tags["estimator"], dict(tags.get("defaults") or {})
    return name, {}


def _reserved_param_issues(params: dict[str, Any], loc: tuple) -> list[tuple[tuple, str]]:
    """The parameters a protocol may not set (``random_state``, ``sensor``) and empty grids."""
    issues: list[tuple[tuple, str]] = []
    for k, v in params.items():
        at = loc + ("params", k)
        if k == "random_state":
            issues.append((at, "random_state is derived from the protocol's seed; set 'seed' instead"))
        elif k == "sensor":
            issues.append((at, "the engine passes the dataset's sensor; do not set 'sensor'"))
        elif _is_grid(v) and not (isinstance(v["grid"], list) and v["grid"]):
            issues.append((at + ("grid",), "a grid must be a non-empty list of values"))
    return issues


def _estimator_param_names(factory: Any) -> list[str]:
    """The parameters ``factory`` accepts: its own, and, when it forwards ``**params`` to an
    estimator, the names that estimator's ``get_params()`` gives."""
    names, var_kw = _accepted_params(factory)
    if var_kw:
        try:
            est = factory(random_state=0)
            names = sorted(set(names) | set(getattr(est, "get_params", lambda: {})()))
        except Exception:  # pragma: no cover - a broken factory is reported at construction below
            pass
    return names


def _unknown_param_issues(name: str, params: dict[str, Any], names: list[str], loc: tuple,
                          what: str) -> list[tuple[tuple, str]]:
    """The parameters of ``params`` that are not among ``names`` (none when ``names`` is empty)."""
    known = [n for n in names if n not in ("random_state",)]
    return [(loc + ("params", k), f"unknown parameter {k!r} for {what} {name!r}{did_you_mean(k, known)}")
            for k in params if k != "random_state" and known and k not in names]


def _construction_issues(factory: Any, base: dict[str, Any], name: str, params: dict[str, Any], loc: tuple,
                         what: str) -> list[tuple[tuple, str]]:
    """The first point of the grid ``params`` that the estimator refuses to be built with, or whose
    values its own parameter validation refuses (beyond what its defaults already break)."""
    try:  # what the estimator's own defaults break is the estimator's business (a subclass widening a domain)
        own = set(_constraint_failures(factory(random_state=0, **base)))
    except Exception:
        own = set()
    for p in expand_grid(params):
        try:
            est = factory(random_state=0, **{**base, **p})
        except Exception as e:  # any construction error is a protocol error
            return [(_param_loc(loc + ("params",), p, str(e)), f"{what} {name!r} rejects {p}: {type(e).__name__}: {e}")]
        problem = next((m for k, m in _constraint_failures(est).items() if k not in own), None)
        if problem:
            return [(_param_loc(loc + ("params",), p, problem), f"{what} {name!r} rejects {p}: {problem}")]
    return []


def _constraint_failures(est: Any) -> dict[tuple[str, str], str]:
    """scikit-learn's own parameter validation of ``est`` and of the estimators among its
    parameters, without fitting: ``(path, parameter) -> message`` for each parameter that
    ``_validate_params`` refuses against its ``_parameter_constraints`` (asked one parameter
    at a time, so that one refusal does not hide the next)."""
    parts: dict[str, Any] = {"": est}
    try:
        parts.update({k: v for k, v in est.get_params(deep=True).items() if hasattr(v, "_parameter_constraints")})
    except Exception:  # an estimator without scikit-learn's get_params: nothing more to ask
        pass
    out: dict[tuple[str, str], str] = {}
    for path, part in parts.items():
        constraints = getattr(part, "_parameter_constraints", None)
        if not callable(getattr(part, "_validate_params", None)) or not isinstance(constraints, dict):
            continue
        for k, c in constraints.items():
            probe = copy.copy(part)
            probe._parameter_constraints = {k: c}
            try:
                probe._validate_params()
            except (ValueError, TypeError) as e:
                out[(path, k)] = str(e)
    return out


def _param_loc(at: tuple, params: dict[str, Any], message: str) -> tuple:
    """``at`` + the parameter ``message`` names, when it names exactly one of ``params``."""
    named = [k for k in params if re.search(r"(?<![\w])" + re.escape(str(k)) + r"(?![\w])", message)]
    return at + (named[0],) if len(named) == 1 else at


def _classifier_issues(protocol: Protocol) -> list[tuple[tuple, str]]:
    issues = []
    for i, spec in enumerate(protocol.classifiers):
        issues += _estimator_issues(spec.name, spec.params, ("classifiers", i), "classifier")
    for i, m in enumerate(protocol.methods):
        if m.name is not None:
            issues += _estimator_issues(m.name, m.params, ("methods", i), "method")
        else:
            issues += _estimator_issues(m.estimator or "", m.params, ("methods", i), "classifier")
    return issues


def _expected_issues(protocol: Protocol) -> list[tuple[tuple, str]]:
    if protocol.expected is None:
        return []
    entries = protocol._entry_pairs()
    combos = [c for c, _, _ in entries]
    by_names = {"+".join(c.names) for c in combos} | {c.label for c in combos}
    clfs = [k for _, k, _ in entries]
    clf_names = ({c.label for c in clfs} | {c.name for c in clfs} | {s.label for s in protocol.classifiers if s.label}
                 | {m.label for m in protocol.methods if m.label})
    labels = sorted(c.label for c in clfs)
    issues = []
    for i, r in enumerate(protocol.expected.results):
        key = "+".join(r.features)
        if key not in by_names:
            issues.append((("expected", "results", i, "features"),
                           f"no feature combination {r.features} in this protocol{did_you_mean(key, sorted(by_names))}"))
        if r.classifier not in clf_names:
            issues.append((("expected", "results", i, "classifier"),
                           f"no classifier {r.classifier!r} in this protocol{did_you_mean(r.classifier, sorted(clf_names))}"))
    for field in ("standard_deviations", "confusions"):
        for i, c in enumerate(getattr(protocol.expected, field)):
            if c.classifier not in labels:
                issues.append((("expected", field, i, "classifier"),
                               f"no classifier entry labelled {c.classifier!r} in this protocol"
                               f"{did_you_mean(c.classifier, labels)} (labels: {', '.join(labels)})"))
    for i, b in enumerate(protocol.expected.best_parameters):
        issues += [(("expected", "best_parameters", i) + loc, msg) for loc, msg in _best_issues(protocol, b)]
    return issues


def _best_issues(protocol: Protocol, best: ExpectedBest) -> list[tuple[tuple, str]]:
    """Whether ``best`` names a grid of one of the protocol's classifiers and one of its values."""
    specs = [s for s in protocol.classifiers if s.name == best.classifier]
    if not specs:
        names = sorted({s.name for s in protocol.classifiers})
        return [(("classifier",), f"no classifier {best.classifier!r} in this protocol{did_you_mean(best.classifier, names)}")]
    grids = {k: v["grid"] for s in specs for k, v in s.params.items() if _is_grid(v)}
    if best.parameter not in grids:
        return [(("parameter",), f"{best.classifier} has no grid of {best.parameter!r} to take the best of"
                                 f"{did_you_mean(best.parameter, sorted(grids))}")]
    if best.value not in grids[best.parameter]:
        return [(("value",), f"{best.value!r} is not in the grid of {best.parameter}: "
                             f"{', '.join(map(_fmt_value, grids[best.parameter]))}")]
    return []


def _target_issues(protocol: Protocol) -> list[tuple[tuple, str]]:
    try:
        protocol.splitter(0).check_target()
    except SplitError as e:
        return [(("target",), str(e))]
    except Exception as e:
        return [(("scheme",), f"{type(e).__name__}: {e}")]
    return []


def _dataset_issues(protocol: Protocol) -> list[tuple[tuple, str]]:
    ref = protocol_dataset_ref(protocol)
    if protocol.dataset.format is not None:
        problem = format_ref_problem(ref.value, protocol.dataset.format)
        return [] if problem is None else [(("dataset", "format" if protocol.dataset.format not in FORMATS
                                             else "name"), problem)]
    problem = dataset_ref_problem(ref)
    return [] if problem is None else [(("dataset", "name"), problem)]


def protocol_dataset_ref(protocol: Protocol) -> DatasetRef:
    """The protocol's dataset reference, relative paths taken from the protocol's folder."""
    return parse_dataset_ref(protocol.dataset.name, None if protocol.path is None else protocol.path.parent)


def resolve_dataset_ref(protocol: Protocol) -> str:
    """The dataset reference as a string, relative paths resolved against the protocol's folder."""
    return str(protocol_dataset_ref(protocol))


# ----------------------------------------------------------------- entry points
def parse_protocol(text: str, path: str | Path | None = None, *, deep: bool = True) -> Protocol:
    """Validate protocol ``text``; ``path`` names it in errors.

    ``deep=False`` skips the checks that build classifiers (for listing).
    """
    p = Path(path) if path is not None else None
    data, root = _load_mapping(text, str(p) if p is not None else "<protocol>")
    lines, booleans = _line_map(root), _boolean_map(root)
    data = copy.deepcopy(data)
    if "name" not in data and p is not None:
        data["name"] = p.stem.replace(".yaml", "")
    try:
        proto = Protocol.model_validate(data)
    except ValidationError as e:
        raise _make_error(p, lines, _pydantic_issues(e, Protocol), booleans) from None
    proto._path = p
    proto._text = text
    proto._lines, proto._booleans = lines, booleans
    issues = _size_issues(proto)  # before anything expands the grids
    if issues:
        raise _make_error(p, lines, issues, booleans)
    names = [ev.name for ev in proto.evaluations]
    issues = [(("evaluations", i, "name"), f"evaluation {n!r} is named twice") for i, n in enumerate(names)
              if n in names[:i]]
    try:
        subs = proto.evaluation_protocols()
    except ValidationError as e:
        raise _make_error(p, lines, _pydantic_issues(e, Protocol), booleans) from None
    issues += _shape_issues(proto)
    issues += _feature_issues(proto)
    if deep:
        issues += _classifier_issues(proto)
    issues += _evaluation_issues(proto, subs, clean_so_far=not issues)
    if not issues:
        issues += _expected_issues(proto)
    if issues:
        raise _make_error(p, lines, list(dict.fromkeys(issues)), booleans)
    return proto


def _load_mapping(text: str, where: str) -> tuple[dict, Any]:
    """The YAML mapping of protocol ``text`` and its node tree; anything else is a :class:`ProtocolError`."""
    try:
        data, root = load_bounded(text)
    except yaml.YAMLError as e:
        line, problem = yaml_problem(e)
        raise ProtocolError(f"{where}{'' if line is None else f':{line}'}: {problem}") from None
    if data is None:
        raise ProtocolError(f"{where}: the protocol is empty")
    if not isinstance(data, dict):
        raise ProtocolError(f"{where}:1: a protocol is a mapping of fields (name, dataset, scheme, ...), got {type(data).__name__}")
    return data, root


def _evaluation_issues(proto: Protocol, subs: list[Protocol], *, clean_so_far: bool) -> list[tuple[tuple, str]]:
    """Each evaluation's scheme and dataset, and (while nothing else is wrong: ``clean_so_far``
    and its own are clean) its target; located in the evaluation that sets the field."""
    issues: list[tuple[tuple, str]] = []
    for i, sub in enumerate(subs):
        at = ("evaluations", i) if proto.evaluations else ()
        own = _scheme_issues({"name": sub.scheme.name, **sub.scheme.params}, sub.target, ("scheme",))
        own += _dataset_issues(sub)
        if not own and clean_so_far and not issues:
            own += _target_issues(sub)
        issues += [((at + loc) if at and loc[:1] and loc[0] in EVALUATION_FIELDS and _given(proto, i, loc[0])
                    else loc, msg) for loc, msg in own]
    return issues


def _given(proto: Protocol, i: int, key: str) -> bool:
    """Whether evaluation ``i`` sets ``key`` itself (else the protocol's is used)."""
    return getattr(proto.evaluations[i], key, None) is not None


def load_protocol(path: str | Path, *, deep: bool = True) -> Protocol:
    """Read and validate a protocol file (see the module docstring)."""
    p = Path(path)
    if not p.is_file():
        raise ProtocolError(f"{p}: no such protocol file")
    size = p.stat().st_size
    if size > MAX_BYTES:  # refused before reading it
        raise ProtocolError(f"{p}: the file has {size} bytes: a protocol has at most {MAX_BYTES}")
    try:
        text = p.read_text(encoding="utf-8")
    except UnicodeDecodeError:
        raise ProtocolError(f"{p}: not a UTF-8 text file") from None
    return parse_protocol(text, p, deep=deep)
