"""What every evaluation scheme shares: the splitter base class, its folds, the registry.

A splitter turns the metadata table of a dataset (one row per capture) into
named folds of positional ``train`` / ``test`` indices (:meth:`Splitter.folds`);
:meth:`Splitter.split` and :meth:`Splitter.get_n_splits` are the same folds
as a scikit-learn cross-validator. A scheme that changes the data it is
evaluated on (windows cut from the captures, a second dataset stacked
under the first) does so in :meth:`Splitter.prepare`, which the run engine
calls before splitting, with a :class:`DataContext`.

Every splitter is built as ``SPLITTERS.create(name, target=..., random_state=...,
**params)`` (or :func:`make_splitter`); its parameters are validated by a
pydantic model (``Params``) so a protocol file gets an error naming the
field. Situations the scheme cannot evaluate raise :class:`SplitError`
before any work; situations it handles are described in
``splitter.notes_`` (dataset-wide) and ``Fold.notes`` (one fold), which the
run engine copies into the report.

Randomness (fold assignment, party assignment) comes only from
``random_state`` through :func:`touchbench.protocols.seeding.derive_seed`,
so the same protocol seed gives the same folds.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field, replace
from functools import cached_property
from typing import TYPE_CHECKING, Annotated, Any, Callable, ClassVar, Iterator, TypeVar

import numpy as np
import pandas as pd
from pydantic import BaseModel, BeforeValidator, ConfigDict, Field, model_validator

from ...core.errors import TouchbenchError, UnknownNameError
from ...core.folds import FoldExtra
from ...core.paramdoc import of_model
from ...core.registry import Registry
from ..seeding import derive_seed

if TYPE_CHECKING:
    from ...datasets.model import TouchDataset


#: the repetitions (seeds of every method) of an evaluation whose scheme has a single test set
#: (:attr:`Splitter.single_test_set`) when its protocol does not say: one seed's accuracy on one test
#: set is one draw of the methods' randomness, which the captures' interval does not cover
DEFAULT_SEEDS = 5


class SplitError(TouchbenchError):
    """A scheme that cannot be evaluated on this metadata (refused before any work); ``field``, the
    scheme's parameter at fault (``("hop_s",)``), where one is."""

    def __init__(self, message: str, field: tuple = ()):
        super().__init__(message)
        self.field = tuple(field)


class MissingColumnError(SplitError):
    """The metadata has no column the scheme reads."""


@dataclass(frozen=True)
class Crop(FoldExtra):
    """Cut captures to their first ``frames`` frames or first ``seconds`` seconds (the ``early``
    scheme's fold extra).

    ``train=False`` (the default) cuts only the test captures: the model is
    trained on whole gestures and asked to recognise one from its beginning.
    """

    frames: int | None = None
    seconds: float | None = None
    train: bool = False

    def n_frames(self, frame_rate: float) -> int:
        """The number of frames kept (at least one)."""
        if self.frames is not None:
            return int(self.frames)
        assert self.seconds is not None
        return max(1, int(round(self.seconds * frame_rate)))

    @property
    def label(self) -> str:
        return f"{self.frames}f" if self.frames is not None else f"{self.seconds:g}s"


@dataclass(frozen=True)
class CurvePoint(FoldExtra):
    """Where a fold sits on a data curve: ``axis`` ``"subjects"`` (trained on ``size`` of the base
    fold's training subjects, a number, or a fraction when below 1) or ``"calibration"`` (``size``
    labelled captures per class of the test side joined the training data); ``draw`` numbers the
    random draws of those subjects or captures (0 when there is one). On a calibration curve
    ``added`` and ``added_min`` are the labelled captures per class that really joined the training
    data: the mean and the least over the test side's (unit, class) pools (a pool short of ``size``
    captures gives fewer); NaN where not recorded."""

    axis: str
    size: float
    draw: int = 0
    added: float = field(default=float("nan"), compare=False)
    added_min: float = field(default=float("nan"), compare=False)



def curve_columns(point: CurvePoint | None) -> dict[str, Any]:
    """The scores columns of a task at ``point`` (``curve`` "" and ``curve_size`` NaN off a curve;
    ``curve_added`` / ``curve_added_min`` NaN but on a calibration curve)."""
    if point is None:
        return {"curve": "", "curve_size": np.nan, "curve_draw": 0, "curve_added": np.nan, "curve_added_min": np.nan}
    return {"curve": point.axis, "curve_size": np.float64(point.size), "curve_draw": int(point.draw),
            "curve_added": np.float64(point.added), "curve_added_min": np.float64(point.added_min)}


#: a kind of fold extra
E = TypeVar("E", bound=FoldExtra)


@dataclass(frozen=True)
class Fold:
    """One train/test split over positional indices of the metadata table.

    ``group`` is the scope the fold's scores are reported under (the subject
    of a within-subject fold, the direction of a transfer fold, the party of
    a person-independent fold, the repeat of a k-fold); ``notes`` says how the
    splitter handled an extreme case; ``extras`` are what schemes attach
    (:class:`touchbench.core.folds.FoldExtra`, at most one of each type): the
    ``early`` scheme's :class:`Crop`, a data curve's :class:`CurvePoint`, the
    ``stream`` scheme's :class:`touchbench.streams.replay.LiveSpec`. The engine
    reads them through the fold's methods below, never by a scheme's field.
    """

    name: str
    train: np.ndarray
    test: np.ndarray
    group: str = ""
    notes: tuple[str, ...] = field(default=())
    extras: tuple[FoldExtra, ...] = ()

    def __post_init__(self) -> None:
        object.__setattr__(self, "train", np.asarray(self.train, dtype=np.int64))
        object.__setattr__(self, "test", np.asarray(self.test, dtype=np.int64))

    def with_extra(self, extra: FoldExtra, **changes: Any) -> "Fold":
        """This fold with ``extra`` (replacing one of its type) and the fields ``changes``."""
        kept = tuple(e for e in self.extras if type(e) is not type(extra))
        return replace(self, extras=kept + (extra,), **changes)

    def extra(self, kind: type[E]) -> E | None:
        """The fold's extra of type ``kind``, or None."""
        return next((e for e in self.extras if isinstance(e, kind)), None)

    def crop_frames(self, frame_rate: float) -> int | None:
        """The frames the captures are cut to (None: whole captures)."""
        crop = self.extra(Crop)
        return crop.n_frames(frame_rate) if crop is not None else None

    def crops_training(self) -> bool:
        """Whether the training captures are cut too."""
        crop = self.extra(Crop)
        return crop is not None and crop.train

    def identity(self) -> dict[str, Any]:
        """The extras' entries of the fold's task identities."""
        return {k: v for e in self.extras for k, v in e.identity().items()}

    def columns(self) -> dict[str, Any]:
        """The scores columns the fold sets (:func:`curve_columns`: empty off a data curve)."""
        return curve_columns(self.extra(CurvePoint))


@dataclass(frozen=True)
class DataContext:
    """What the run engine gives :meth:`Splitter.prepare`: the protocol's services a scheme that
    changes the data may use (the schemes' layer cannot import the engine's).

    ``dataset_name`` is the protocol's dataset entry as written; ``notes`` the run's notes, which
    ``prepare`` appends what it did to; ``load(entry, loc)`` loads a dataset entry given as a
    mapping (``name``, ``format``, ``filters``, ``exclude``, ``options``) at the protocol location
    ``loc`` and applies its filters; ``error_at(loc, message)`` is the error pointing at ``loc``.
    """

    dataset_name: str
    notes: list[str]
    load: Callable[[Any, tuple], "TouchDataset"]
    error_at: Callable[[tuple, str], Exception]


# ----------------------------------------------------------------- helpers the schemes share
def natural_key(v: object) -> tuple:
    """Sort "r2" before "r10", numbers numerically."""
    parts = re.split(r"(\d+)", str(v))
    return tuple((0, int(p)) if p.isdigit() else (1, p) for p in parts if p != "")


def sorted_values(values) -> list[str]:
    return sorted({str(v) for v in values}, key=natural_key)


def require_columns(meta: pd.DataFrame, scheme: str, *cols: str) -> None:
    for c in cols:
        if c not in meta.columns:
            raise MissingColumnError(
                f"scheme {scheme!r} needs the metadata column {c!r}; "
                f"the dataset has: {', '.join(map(str, meta.columns))}"
            )


def str_col(meta: pd.DataFrame, col: str) -> np.ndarray:
    s = meta[col]
    return np.array([None if pd.isna(v) else str(v) for v in s.tolist()], dtype=object)


def deal(y: np.ndarray | None, n: int, k: int, rng: np.random.Generator) -> np.ndarray:
    """Assign ``n`` items to ``k`` folds, stratified by ``y`` when given.

    Items of each class are shuffled and laid end to end (classes in sorted
    order), then dealt round-robin into the folds: fold sizes differ by at
    most one and each class is spread over the folds as evenly as its size
    allows (a class with fewer than ``k`` members is in fewer than ``k`` test
    folds). The fold labels are then permuted. This is what scikit-learn's
    ``StratifiedKFold`` approximates, without its refusal when every class is
    smaller than ``k``.
    """
    if y is None:
        order = rng.permutation(n)
    else:
        parts = []
        for c in sorted_values(y):
            idx = np.flatnonzero(y == c)
            parts.append(rng.permutation(idx))
        order = np.concatenate(parts) if parts else np.zeros(0, dtype=np.int64)
    assign = np.empty(n, dtype=np.int64)
    assign[order] = np.arange(n) % k
    relabel = rng.permutation(k)
    return relabel[assign]


def folds_from_assignment(assign: np.ndarray, k: int, base: np.ndarray | None = None) -> list[tuple[np.ndarray, np.ndarray]]:
    idx = np.arange(len(assign)) if base is None else base
    out = []
    for f in range(k):
        test = idx[assign == f]
        train = idx[assign != f]
        out.append((np.sort(train), np.sort(test)))
    return out


def small_class_notes(y: np.ndarray, k: int, where: str = "") -> list[str]:
    """Notes on the classes with fewer than ``k`` captures (absent from some of ``k`` test folds)."""
    notes = []
    vals, counts = np.unique(y.astype(str), return_counts=True)
    for v, c in zip(vals.tolist(), counts.tolist()):
        if c < k:
            notes.append(
                f"{where}class {v!r} has {c} capture(s), fewer than k={k}: it is in only {c} of the "
                f"{k} test folds, and a fold that tests all of them trains without it"
                if c == 1 else
                f"{where}class {v!r} has {c} captures, fewer than k={k}: it is in only {c} of the {k} test folds"
            )
    return notes


class SchemeParams(BaseModel):
    """The base of every scheme's parameter model: unknown parameters are refused."""

    model_config = ConfigDict(extra="forbid")


def _strings(v: Any) -> Any:
    return [str(x) for x in v] if isinstance(v, list) else v


#: a parameter that lists values of a metadata column: strings, as the column is read (YAML reads ``1`` as a number)
StrList = Annotated[list[str], BeforeValidator(_strings)]


def named(d: Any, key: str) -> Any:
    """Parameters where ``key: NAME`` is short for ``key: {name: NAME}``."""
    if isinstance(d, dict) and isinstance(d.get(key), str):
        return {**d, key: {"name": d[key]}}
    return d


class WrappingParams(SchemeParams):
    """The parameters of a scheme that wraps another: ``base``, the wrapped scheme's entry
    (``base: loso`` is short for ``base: {name: loso}``)."""

    base: dict[str, Any]

    @model_validator(mode="before")
    @classmethod
    def _base(cls, d: Any) -> Any:
        return named(d, "base")

    @cached_property
    def base_params(self) -> BaseModel:
        """The wrapped scheme's parameters validated by its own model, once (a ``ValidationError``
        at its fields; an unknown name: ``UnknownNameError``): the protocol's checks ask it first,
        and the wrapped scheme is built from it."""
        return SPLITTERS.get(self.base["name"]).Params.model_validate(
            {k: v for k, v in self.base.items() if k != "name"})


class CurveParams(WrappingParams):
    """A data-curve scheme's parameters: its base and the number of random ``draws`` per point."""

    draws: int = Field(default=5, ge=1, le=1000)


#: the schemes that place their folds on a data curve (a :class:`CurvePoint` extra): a fold sits on one curve, so
#: neither wraps the other
CURVE_SCHEMES = ("learning-curve", "calibration")


def check_base(base: dict[str, Any], scheme: str, refused: tuple[str, ...] = ()) -> None:
    """Refuse a wrapping scheme's ``base`` entry that names no scheme, or names ``scheme`` itself or
    one of ``refused`` (ValueError: the parameter model reports it at the field)."""
    name = base.get("name")
    if not isinstance(name, str):
        raise ValueError("base must name a scheme: base: {name: loso}")
    if name == scheme or name in refused:
        raise ValueError(f"the base of {scheme!r} cannot be {name!r}")


# ----------------------------------------------------------------- base
S = TypeVar("S", bound="Splitter")


class Splitter:
    """Base class: subclasses set ``Params`` and implement ``_split``.

    ``target`` is the metadata column the classifier predicts (``gesture``
    or ``subject``); stratified schemes stratify on it.
    """

    name: ClassVar[str] = ""
    Params: ClassVar[type[BaseModel]] = SchemeParams
    #: the parameter that is another scheme's entry (``{name: ..., ...}``), which this one wraps:
    #: validated as a scheme, labelled as one
    base_param: ClassVar[str | None] = None
    #: the parameters swept over, each value evaluated as result rows of its own (the ``early``
    #: scheme's lengths): not part of the scheme's label, so runs with different lists combine
    swept_params: ClassVar[tuple[str, ...]] = ()
    #: each fold tests one fixed set of captures whatever the seed (a challenge split, a transfer to
    #: another group or dataset): the folds are the same in every repetition, which re-draws only the
    #: methods' seeds, and such an evaluation runs :data:`DEFAULT_SEEDS` repetitions unless its
    #: protocol or evaluation sets ``repetitions``
    single_test_set: ClassVar[bool] = False

    @classmethod
    def heading(cls, params: dict[str, Any], dataset: str) -> str | None:
        """How a report's title names this scheme with ``params`` (as the protocol wrote them) on the
        protocol's ``dataset``, as a person would; None: ``name(param=value,...)``."""
        return None

    def __init__(self, target: str = "gesture", random_state: int | None = None, **params: Any):
        self.params = self.Params.model_validate(params)
        self._setup(target, random_state)

    @classmethod
    def from_params(cls: type[S], params: BaseModel, target: str = "gesture", random_state: int | None = None) -> S:
        """The scheme with ``params`` already validated by its ``Params`` model (not validated again:
        a protocol validates its scheme's parameters once, when it is read)."""
        if not isinstance(params, cls.Params):
            raise TypeError(f"scheme {cls.name!r} takes a {cls.Params.__name__}, got {type(params).__name__}")
        self = cls.__new__(cls)
        self.params = params
        self._setup(target, random_state)
        return self

    def _setup(self, target: str, random_state: int | None) -> None:
        """What building sets besides the validated ``self.params``."""
        self.target = target
        self.random_state = 0 if random_state is None else int(random_state)
        self.notes_: list[str] = []

    # properties the engine and the tests rely on
    def keeps_subjects_apart(self) -> bool:
        """True if no subject can be on both sides of a fold."""
        return False

    def tests_each_capture_once(self) -> bool:
        """True if every kept capture is in exactly one test fold (per repeat)."""
        return False

    def apart_column(self) -> str | None:
        """The metadata column whose values are never on both sides of a fold (the one held out)."""
        return "subject" if self.keeps_subjects_apart() else None

    def leakage(self) -> str:
        """Why this scheme's accuracy overstates what a new user's captures would give ("" when it
        does not): the leaky schemes are named so every result row and report can say so."""
        return ""

    def sample_windows(self) -> tuple[int | None, float | None, int | None] | None:
        """``(frames, seconds, hop frames)`` when the scheme's samples are windows cut from the
        captures (:meth:`prepare` cuts them), else None."""
        return None

    def prepare(self, ds: "TouchDataset", context: DataContext) -> "TouchDataset":
        """The dataset the scheme is evaluated on, from the protocol's (filtered) dataset ``ds``:
        ``ds`` itself unless the scheme changes the data (then it says what it did in
        ``context.notes``)."""
        return ds

    def check_target(self) -> None:
        """Refuse a target the scheme cannot evaluate: the column it holds out (every test class
        would be missing from the training data)."""
        if self.target == "subject" and self.keeps_subjects_apart():
            raise SplitError(
                f"target 'subject' (person identification) needs each test subject in the training "
                f"data, but scheme {self.name!r} keeps subjects apart; use kfold or leave-recording-out"
            )
        if self.target == self.apart_column():
            raise SplitError(
                f"target {self.target!r}: scheme {self.name!r} holds out the values of {self.target!r}, so no "
                f"test capture's class would be in the training data; predict another column or hold out another"
            )

    def folds(self, meta: pd.DataFrame) -> list[Fold]:
        """The scheme's folds over ``meta`` (one row per capture, positional indices)."""
        self.notes_ = []
        self.check_target()
        require_columns(meta, self.name, self.target)
        if len(meta) == 0:
            raise SplitError(f"scheme {self.name!r}: the dataset has no captures (after filters)")
        folds = self._split(meta.reset_index(drop=True))
        if not folds:
            raise SplitError(f"scheme {self.name!r} produced no folds on this dataset")
        for f in folds:
            if len(f.test) == 0:
                raise SplitError(f"scheme {self.name!r}: fold {f.name!r} has no test captures")
            if len(f.train) == 0:
                raise SplitError(f"scheme {self.name!r}: fold {f.name!r} has no training captures")
        return folds

    # scikit-learn's cross-validator interface (BaseCrossValidator), built on folds()
    def split(self, X: Any, y: Any = None, groups: Any = None) -> Iterator[tuple[np.ndarray, np.ndarray]]:
        """``(train, test)`` positional indices of each fold, as a scikit-learn cross-validator.

        ``X`` may be the metadata table (a DataFrame with the columns the
        scheme reads); otherwise the table is built from ``y`` (the target
        column) and ``groups`` (the subject of each row), and a scheme that
        reads another column is refused. ``y`` and ``groups``, when given,
        are those columns. A scheme whose folds cut captures is refused.
        """
        for f in self._sklearn_folds(X, y, groups):
            yield f.train, f.test

    def get_n_splits(self, X: Any = None, y: Any = None, groups: Any = None) -> int:
        """The number of folds :meth:`split` yields; without data, only a scheme whose number of
        folds does not depend on it (k-fold) can say."""
        if X is None and y is None and groups is None:
            n = self._n_splits()
            if n is None:
                raise SplitError(f"scheme {self.name!r}: the number of folds depends on the data; pass X (the "
                                 "metadata table) or y and groups")
            return n
        return len(self._sklearn_folds(X, y, groups))

    def _n_splits(self) -> int | None:
        """The number of folds when it does not depend on the data, else None."""
        return None

    def _sklearn_folds(self, X: Any, y: Any, groups: Any) -> list[Fold]:
        built = not isinstance(X, pd.DataFrame)
        meta = _sklearn_table(X, y, groups, self.target)
        try:
            folds = self.folds(meta)
        except MissingColumnError as e:
            if not built:
                raise
            raise SplitError(f"{e}: split(X, y, groups) knows only y (the column {self.target!r}) and groups "
                             "(the column 'subject'); pass the metadata table as X") from None
        cut = [f.name for f in folds if f.extra(Crop) is not None]
        if cut:
            raise SplitError(f"scheme {self.name!r} cuts captures (fold {cut[0]!r}), which index splits cannot "
                             "express; use folds(meta) and cut the captures")
        return folds

    def _split(self, meta: pd.DataFrame) -> list[Fold]:
        raise NotImplementedError

    def _y(self, meta: pd.DataFrame) -> np.ndarray:
        return str_col(meta, self.target)

    def _rng(self, *identity: object) -> np.random.Generator:
        return np.random.default_rng(derive_seed(self.random_state, self.name, *identity))


def _sklearn_table(X: Any, y: Any, groups: Any, target: str) -> pd.DataFrame:
    """The metadata table of :meth:`Splitter.split`: ``X`` when it is one, else a table of as many
    rows as ``X``; ``y`` as the ``target`` column and ``groups`` as ``subject`` when given."""
    if isinstance(X, pd.DataFrame):
        meta = X.reset_index(drop=True)
    else:
        rows = next(v for v in (X, y, groups) if v is not None)
        meta = pd.DataFrame(index=pd.RangeIndex(rows.shape[0] if hasattr(rows, "shape") else len(rows)))
    columns = {c: np.asarray(v) for c, v in ((target, y), ("subject", groups)) if v is not None}
    return meta.assign(**columns) if columns else meta


SPLITTERS: Registry = Registry("evaluation scheme", package="touchbench.protocols.schemes", params_of=of_model)


def make_splitter(name: str, target: str = "gesture", random_state: int | None = None, **params: Any) -> Splitter:
    """Build the registered scheme ``name``."""
    return SPLITTERS.create(name, target=target, random_state=random_state, **params)


def scheme_class(name: str) -> type[Splitter] | None:
    """The class of the registered scheme ``name``; None when no scheme has that name."""
    try:
        return SPLITTERS.get(name)
    except UnknownNameError:
        return None


# ----------------------------------------------------------------- fold checks
def fold_notes(fold: Fold, y: np.ndarray) -> list[str]:
    """How the engine handles a fold's classes, as notes for the report.

    - test classes absent from training: the classifier cannot predict them;
      their test captures count as errors;
    - a training fold with a single class: no classifier is fitted, every
      test capture is predicted as that class;
    - a test fold with a single class: balanced accuracy and macro F1 are
      computed over the classes present in truth or prediction.
    """
    y = np.asarray(y).astype(str)
    tr = {str(v) for v in y[fold.train].tolist()}
    te_vals, te_counts = np.unique(y[fold.test], return_counts=True)
    notes = []
    te_vals = [str(v) for v in te_vals.tolist()]
    missing = [(v, int(c)) for v, c in zip(te_vals, te_counts.tolist()) if v not in tr]
    if missing:
        desc = ", ".join(f"{v!r} ({c} test captures)" for v, c in missing)
        notes.append(f"classes absent from training: {desc}; counted as errors")
    if len(tr) == 1:
        notes.append(f"training fold has a single class {next(iter(tr))!r}: no model fitted, constant prediction")
    if len(te_vals) == 1:
        notes.append(f"test fold has a single class {te_vals[0]!r}")
    return notes


class WrappingSplitter(Splitter):
    """A scheme that wraps another (its ``base`` parameter, ``{name: loso}``): the base's folds, data,
    subjects kept apart and leakage, unless the subclass says otherwise."""

    base_param = "base"

    def _setup(self, target: str, random_state: int | None) -> None:
        super()._setup(target, random_state)
        params = self.params.base_params  # type: ignore[attr-defined]
        self.base = SPLITTERS.get(self.params.base["name"]).from_params(  # type: ignore[attr-defined]
            params, target=target, random_state=random_state)

    def keeps_subjects_apart(self) -> bool:
        return self.base.keeps_subjects_apart()

    def check_target(self) -> None:
        self.base.check_target()

    def leakage(self) -> str:
        return self.base.leakage()

    def sample_windows(self):
        return self.base.sample_windows()

    def prepare(self, ds: "TouchDataset", context: DataContext) -> "TouchDataset":
        return self.base.prepare(ds, context)

