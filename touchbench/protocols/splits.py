"""Evaluation schemes: splitters over the metadata table.

A splitter turns the metadata table of a dataset (one row per capture) into
named folds of positional ``train`` / ``test`` indices. Each scheme of the
four papers is one registered splitter (``SPLITTERS``):

==========================  ====================================================
``challenge``               fixed train/test from a split column or subject
                            lists (Gaus et al. 2015, Sec. 4: the Social Touch
                            Gesture Challenge split).
``loso``                    leave one subject out (Al-mashhadani et al. 2021,
                            Sec. 3, Table 2; optionally only some subjects are
                            held out, as for their Fig. 5).
``kfold``                   (stratified) k-fold with repeats, optionally
                            grouped so no subject is on both sides (Gaus Sec. 4:
                            10-fold; Flagg 2012 Sec. 4.4: 100-fold; Zhou et al.
                            2017 Sec. 5: 5-fold "random cross-validation").
``within-subject``          k-fold inside each subject, one model per subject,
                            scores per subject (Flagg Sec. 4.4, Fig. 4.5).
``leave-recording-out``     train on one recording of every person, test on the
                            other, then swap (Zhou Sec. 5.4, Fig. 9b).
``person-independent``      subjects dealt into k disjoint parties, each tested
                            once (Zhou Sec. 5.4: 4 parties of 6, Fig. 9c).
``transfer``                train on one group, test on another, both
                            directions (Zhou Sec. 5.4, Fig. 11: A->B, B->A).
``window-kfold``            k-fold over windows cut from the captures, the
                            windows the samples (leaky unless grouped by
                            subject: windows of one capture on both sides).
``cross-dataset``           train on one dataset, test on another (adapted to
                            the training sensor when declared).
``early``                   any scheme above, with test captures (optionally
                            training captures too) cut to their first N frames
                            or S seconds, N swept over a list (Al-mashhadani
                            Sec. 2.3: recognition after the first frames).
==========================  ====================================================

A scheme that lets the test data inform training says why in
``leakage()`` (k-fold ignoring subjects when the target is not the subject,
window-level k-fold): the engine writes it into every result row and the
reports flag it; no such scheme is a default.

Every splitter is built as ``SPLITTERS.create(name, target=..., random_state=...,
**params)``; its parameters are validated by a pydantic model (``Params``) so
a protocol file gets an error naming the field. ``split(meta)`` returns a list
of :class:`Fold`; situations the scheme cannot evaluate raise
:class:`SplitError` before any work, situations it handles are described in
``splitter.notes_`` (dataset-wide) and ``Fold.notes`` (one fold), which the run
engine copies into the report.

Randomness (fold assignment, party assignment) comes only from
``random_state`` through :func:`touchbench.protocols.seeding.derive_seed`,
so the same protocol seed gives the same folds.
"""

from __future__ import annotations

import re
import warnings
from dataclasses import dataclass, field, replace
from typing import Any, ClassVar, Literal

import numpy as np
import pandas as pd
from pydantic import BaseModel, ConfigDict, Field, model_validator
from sklearn.model_selection import GroupKFold, StratifiedGroupKFold

from ..core.errors import TouchbenchError
from ..core.registry import Registry
from .seeding import derive_seed

__all__ = [
    "SPLITTERS",
    "Crop",
    "Fold",
    "SplitError",
    "Splitter",
    "fold_notes",
    "make_splitter",
]

class SplitError(TouchbenchError):
    """A scheme that cannot be evaluated on this metadata (refused before any work)."""


@dataclass(frozen=True)
class Crop:
    """Cut captures to their first ``frames`` frames or first ``seconds`` seconds.

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
class Fold:
    """One train/test split over positional indices of the metadata table.

    ``group`` is the scope the fold's scores are reported under (the subject
    of a within-subject fold, the direction of a transfer fold, the party of
    a person-independent fold, the repeat of a k-fold); ``crop`` is set by the
    ``early`` scheme; ``notes`` says how the splitter handled an extreme case.
    """

    name: str
    train: np.ndarray
    test: np.ndarray
    group: str = ""
    crop: Crop | None = None
    notes: tuple[str, ...] = field(default=())

    def __post_init__(self) -> None:
        object.__setattr__(self, "train", np.asarray(self.train, dtype=np.int64))
        object.__setattr__(self, "test", np.asarray(self.test, dtype=np.int64))


# ----------------------------------------------------------------- helpers
def _natural_key(v: object) -> tuple:
    """Sort "r2" before "r10", numbers numerically."""
    parts = re.split(r"(\d+)", str(v))
    return tuple((0, int(p)) if p.isdigit() else (1, p) for p in parts if p != "")


def _sorted_values(values) -> list[str]:
    return sorted({str(v) for v in values}, key=_natural_key)


def _require_columns(meta: pd.DataFrame, scheme: str, *cols: str) -> None:
    for c in cols:
        if c not in meta.columns:
            raise SplitError(
                f"scheme {scheme!r} needs the metadata column {c!r}; "
                f"the dataset has: {', '.join(map(str, meta.columns))}"
            )


def _str_col(meta: pd.DataFrame, col: str) -> np.ndarray:
    s = meta[col]
    return np.array([None if pd.isna(v) else str(v) for v in s.tolist()], dtype=object)


def _deal(y: np.ndarray | None, n: int, k: int, rng: np.random.Generator) -> np.ndarray:
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
        for c in _sorted_values(y):
            idx = np.flatnonzero(y == c)
            parts.append(rng.permutation(idx))
        order = np.concatenate(parts) if parts else np.zeros(0, dtype=np.int64)
    assign = np.empty(n, dtype=np.int64)
    assign[order] = np.arange(n) % k
    relabel = rng.permutation(k)
    return relabel[assign]


def _folds_from_assignment(assign: np.ndarray, k: int, base: np.ndarray | None = None) -> list[tuple[np.ndarray, np.ndarray]]:
    idx = np.arange(len(assign)) if base is None else base
    out = []
    for f in range(k):
        test = idx[assign == f]
        train = idx[assign != f]
        out.append((np.sort(train), np.sort(test)))
    return out


class _Params(BaseModel):
    model_config = ConfigDict(extra="forbid")


def _named(d: Any, key: str) -> Any:
    """Parameters where ``key: NAME`` is short for ``key: {name: NAME}``."""
    if isinstance(d, dict) and isinstance(d.get(key), str):
        return {**d, key: {"name": d[key]}}
    return d


# ----------------------------------------------------------------- base
class Splitter:
    """Base class: subclasses set ``Params`` and implement ``_split``.

    ``target`` is the metadata column the classifier predicts (``gesture``
    or ``subject``); stratified schemes stratify on it.
    """

    name: ClassVar[str] = ""
    Params: ClassVar[type[BaseModel]] = _Params

    def __init__(self, target: str = "gesture", random_state: int | None = None, **params: Any):
        self.target = target
        self.random_state = 0 if random_state is None else int(random_state)
        self.params = self.Params.model_validate(params)
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
        captures (the engine cuts them before splitting), else None."""
        return None

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

    def split(self, meta: pd.DataFrame) -> list[Fold]:
        self.notes_ = []
        self.check_target()
        _require_columns(meta, self.name, self.target)
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

    def _split(self, meta: pd.DataFrame) -> list[Fold]:
        raise NotImplementedError

    def _y(self, meta: pd.DataFrame) -> np.ndarray:
        return _str_col(meta, self.target)

    def _rng(self, *identity: object) -> np.random.Generator:
        return np.random.default_rng(derive_seed(self.random_state, self.name, *identity))


SPLITTERS: Registry = Registry("evaluation scheme", plugins=True)


def make_splitter(name: str, target: str = "gesture", random_state: int | None = None, **params: Any) -> Splitter:
    """Build the registered scheme ``name``."""
    return SPLITTERS.create(name, target=target, random_state=random_state, **params)


# ----------------------------------------------------------------- challenge
class _ChallengeParams(_Params):
    column: str = "split"
    train: list[str] = Field(default_factory=lambda: ["train"])
    test: list[str] = Field(default_factory=lambda: ["test"])
    train_subjects: list[str] | None = None
    test_subjects: list[str] | None = None

    @model_validator(mode="before")
    @classmethod
    def _listify(cls, d: Any) -> Any:
        if isinstance(d, dict):
            d = dict(d)
            for k in ("train", "test", "train_subjects", "test_subjects"):
                v = d.get(k)
                if isinstance(v, (str, int)):
                    d[k] = [str(v)]
                elif isinstance(v, list):
                    d[k] = [str(x) for x in v]
        return d

    @model_validator(mode="after")
    def _check(self) -> "_ChallengeParams":
        if self.train_subjects is not None and self.test_subjects is None:
            raise ValueError("train_subjects needs test_subjects (or give test_subjects alone)")
        if self.train_subjects and self.test_subjects:
            both = sorted(set(self.train_subjects) & set(self.test_subjects))
            if both:
                raise ValueError(f"subjects on both sides: {both}")
        return self


@SPLITTERS.register(
    "challenge",
    description="fixed train/test split from a split column or subject lists (Gaus 2015, Sec. 4)",
    paper="Gaus et al. 2015, Sec. 4",
)
class ChallengeSplit(Splitter):
    """One fold: the Social Touch Gesture Challenge 2015 train/test split.

    With ``test_subjects`` the split is by subject (``train_subjects``
    defaults to every other subject); otherwise the ``column`` (``split``)
    decides: values in ``train`` are trained on, values in ``test`` tested.
    Captures in neither are left out, and the report says how many.
    """

    name = "challenge"
    Params = _ChallengeParams

    def keeps_subjects_apart(self) -> bool:
        return self.params.test_subjects is not None

    def apart_column(self) -> str | None:
        return "subject" if self.params.test_subjects is not None else self.params.column

    def _split(self, meta: pd.DataFrame) -> list[Fold]:
        p = self.params
        if p.test_subjects is not None:
            subj = _str_col(meta, "subject")
            known = set(subj)
            unknown = [s for s in (p.test_subjects + (p.train_subjects or [])) if s not in known]
            if unknown:
                raise SplitError(f"scheme 'challenge': unknown subject(s) {unknown}; the dataset has {_sorted_values(known)}")
            is_test = np.isin(subj, p.test_subjects)
            is_train = np.isin(subj, p.train_subjects) if p.train_subjects is not None else ~is_test
        else:
            _require_columns(meta, self.name, p.column)
            col = _str_col(meta, p.column)
            is_train = np.isin(col, p.train)
            is_test = np.isin(col, p.test)
            both = sorted(set(p.train) & set(p.test))
            if both:
                raise SplitError(f"scheme 'challenge': value(s) {both} of column {p.column!r} are both train and test")
            subj = _str_col(meta, "subject")
            shared = sorted(set(subj[is_train]) & set(subj[is_test]))
            if shared:
                self.notes_.append(f"subjects on both sides of the {p.column!r} split: {shared}")
        unused = int((~is_train & ~is_test).sum())
        if unused:
            self.notes_.append(f"{unused} captures are in neither train nor test and are not used")
        return [Fold("challenge", np.flatnonzero(is_train), np.flatnonzero(is_test), group="challenge")]


# ----------------------------------------------------------------- loso
class _LosoParams(_Params):
    column: str = "subject"
    subjects: list[str] | None = Field(default=None, min_length=1)

    @model_validator(mode="before")
    @classmethod
    def _listify(cls, d: Any) -> Any:
        if isinstance(d, dict) and isinstance(d.get("subjects"), list):
            d = {**d, "subjects": [str(x) for x in d["subjects"]]}
        return d


@SPLITTERS.register(
    "loso",
    description="leave one subject out (Al-mashhadani 2021, Table 2)",
    paper="Al-mashhadani et al. 2021, Sec. 3",
)
class LeaveOneSubjectOut(Splitter):
    """One fold per subject: test on that subject, train on all the others.

    ``subjects`` restricts which subjects are held out (each fold still
    trains on every other subject): Al-mashhadani et al. select the frame
    length on subjects 1, 3, 5, 7 only (Fig. 5). ``column`` may name another
    grouping column (a leave-one-group-out).
    """

    name = "loso"
    Params = _LosoParams

    def keeps_subjects_apart(self) -> bool:
        return self.params.column == "subject"

    def apart_column(self) -> str | None:
        return self.params.column

    def tests_each_capture_once(self) -> bool:
        return self.params.subjects is None

    def _split(self, meta: pd.DataFrame) -> list[Fold]:
        col = self.params.column
        _require_columns(meta, self.name, col)
        g = _str_col(meta, col)
        values = _sorted_values(g)
        if len(values) < 2:
            raise SplitError(f"scheme 'loso' needs at least 2 values of {col!r}; the dataset has {values}")
        held = values
        if self.params.subjects is not None:
            unknown = [s for s in self.params.subjects if s not in values]
            if unknown:
                raise SplitError(f"scheme 'loso': unknown {col} {unknown}; the dataset has {values}")
            held = [v for v in values if v in set(self.params.subjects)]
        folds = []
        for v in held:
            test = g == v
            folds.append(Fold(f"{col}={v}", np.flatnonzero(~test), np.flatnonzero(test), group=v))
        small = [v for v in held if (g == v).sum() == 1]
        if small:
            self.notes_.append(f"{col} {small} have a single capture: their fold tests one capture")
        return folds


# ----------------------------------------------------------------- kfold
class _KFoldParams(_Params):
    k: int = Field(default=10, ge=2)
    repeats: int = Field(default=1, ge=1)
    stratified: bool = True
    grouped: bool = False
    group_column: str = "subject"
    shuffle: bool = True

    @model_validator(mode="after")
    def _check(self) -> "_KFoldParams":
        if self.repeats > 1 and not self.shuffle:
            raise ValueError("repeats > 1 needs shuffle: true (unshuffled repeats are identical)")
        return self


#: the leak of every scheme that lets one subject's captures be on both sides of a fold
SUBJECTS_SHARED = "captures of one subject on both sides of a fold (k-fold ignoring subjects)"
WINDOWS_SHARED = "windows of one capture on both sides of a fold"


def _kfold_notes_small_classes(y: np.ndarray, k: int, where: str = "") -> list[str]:
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


@SPLITTERS.register(
    "kfold",
    description="stratified k-fold cross-validation with repeats, optionally grouped by subject",
    paper="Gaus 2015 Sec. 4 (10-fold); Flagg 2012 Sec. 4.4 (100-fold); Zhou 2017 Sec. 5 (5-fold)",
)
class KFold(Splitter):
    """k folds (stratified on the target by default), ``repeats`` times.

    Not grouped, folds are dealt at random per class (see ``_deal``): each
    capture is tested exactly once per repeat. ``grouped: true`` keeps every
    value of ``group_column`` (the subject) on one side of each fold, using
    scikit-learn's ``StratifiedGroupKFold`` (``GroupKFold`` if not stratified).
    ``k`` larger than the number of captures (or groups) is refused; a class
    with fewer than ``k`` captures is handled (it is absent from some test
    folds) and noted in the report.
    """

    name = "kfold"
    Params = _KFoldParams

    def keeps_subjects_apart(self) -> bool:
        return self.params.grouped and self.params.group_column == "subject"

    def apart_column(self) -> str | None:
        return self.params.group_column if self.params.grouped else None

    def tests_each_capture_once(self) -> bool:
        return True

    def leakage(self) -> str:
        if self.target == "subject" or self.keeps_subjects_apart():
            return ""
        return SUBJECTS_SHARED

    def _grouping(self) -> str | None:
        """The column no value of which is on both sides of a fold (None: not grouped)."""
        return self.params.group_column if self.params.grouped else None

    def _split(self, meta: pd.DataFrame) -> list[Fold]:
        p = self.params
        n = len(meta)
        y = self._y(meta)
        group_column = self._grouping()
        if n < p.k:
            raise SplitError(f"scheme {self.name!r}: k={p.k} folds but only {n} "
                             f"{'windows' if self.sample_windows() else 'captures'}; lower k")
        folds: list[Fold] = []
        if group_column is not None:
            _require_columns(meta, self.name, group_column)
            groups = _str_col(meta, group_column)
            n_groups = len(set(groups))
            if n_groups < p.k:
                raise SplitError(
                    f"scheme {self.name!r} (grouped by {group_column!r}): k={p.k} folds but only {n_groups} groups; lower k"
                )
        elif p.stratified:
            self.notes_.extend(_kfold_notes_small_classes(y, p.k))
        for r in range(p.repeats):
            seed = derive_seed(self.random_state, "kfold", r)
            if group_column is not None:

                if p.stratified:
                    cv = StratifiedGroupKFold(n_splits=p.k, shuffle=p.shuffle, random_state=seed if p.shuffle else None)
                else:
                    cv = GroupKFold(n_splits=p.k, shuffle=p.shuffle, random_state=seed if p.shuffle else None)
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    pairs = [(np.sort(a), np.sort(b)) for a, b in cv.split(np.zeros(n), y, groups)]
            else:
                if p.shuffle:
                    assign = _deal(y if p.stratified else None, n, p.k, np.random.default_rng(seed))
                else:
                    assign = np.arange(n) * p.k // n  # contiguous blocks, in table order
                pairs = _folds_from_assignment(assign, p.k)
            for i, (tr, te) in enumerate(pairs):
                name = f"r{r}/f{i}" if p.repeats > 1 else f"f{i}"
                folds.append(Fold(name, tr, te, group=f"r{r}"))
        return folds


# ----------------------------------------------------------------- within-subject
class _WithinParams(_Params):
    k: int = Field(default=10, ge=2)
    repeats: int = Field(default=1, ge=1)
    stratified: bool = True
    column: str = "subject"


@SPLITTERS.register(
    "within-subject",
    description="k-fold inside each subject, one model per subject, scores per subject (Flagg 2012)",
    paper="Flagg 2012, Sec. 4.4, Fig. 4.5",
)
class WithinSubject(Splitter):
    """k-fold cross-validation inside each subject separately.

    Every fold trains and tests on one subject's captures only (Flagg's
    per-person models); ``Fold.group`` is the subject, so scores are reported
    per subject. A subject with fewer captures than ``k`` gets one fold per
    capture (leave-one-out for that subject); a subject with a single capture
    cannot be cross-validated and is left out. Both are noted in the report.
    The target ``subject`` is refused (one class per model).
    """

    name = "within-subject"
    Params = _WithinParams

    def tests_each_capture_once(self) -> bool:
        return True

    def check_target(self) -> None:
        if self.target == self.params.column or self.target == "subject":
            raise SplitError(
                "scheme 'within-subject' trains one model per subject: the target cannot be the subject "
                "(every model would see one class)"
            )

    def _split(self, meta: pd.DataFrame) -> list[Fold]:
        p = self.params
        _require_columns(meta, self.name, p.column)
        subj = _str_col(meta, p.column)
        y = self._y(meta)
        folds: list[Fold] = []
        skipped = []
        for s in _sorted_values(subj):
            idx = np.flatnonzero(subj == s)
            n = len(idx)
            if n < 2:
                skipped.append(s)
                continue
            k = min(p.k, n)
            notes: list[str] = []
            if k < p.k:
                notes.append(f"subject {s!r} has {n} captures < k={p.k}: {k} folds (leave-one-out)")
            if p.stratified:
                notes.extend(_kfold_notes_small_classes(y[idx], k, where=f"subject {s!r}: "))
            self.notes_.extend(notes)
            for r in range(p.repeats):
                rng = np.random.default_rng(derive_seed(self.random_state, self.name, s, r))
                assign = _deal(y[idx] if p.stratified else None, n, k, rng)
                for i, (tr, te) in enumerate(_folds_from_assignment(assign, k, base=idx)):
                    name = f"{s}/r{r}/f{i}" if p.repeats > 1 else f"{s}/f{i}"
                    folds.append(Fold(name, tr, te, group=s, notes=tuple(notes)))
        if skipped:
            self.notes_.append(f"subject(s) {skipped} have a single capture and are left out (cannot cross-validate)")
        if not folds:
            raise SplitError("scheme 'within-subject': no subject has 2 or more captures")
        return folds


# ----------------------------------------------------------------- leave-recording-out
class _RecordingParams(_Params):
    column: str = "session"
    subject_column: str = "subject"


@SPLITTERS.register(
    "leave-recording-out",
    description="train on one recording of every person, test on the other, then swap (Zhou 2017)",
    paper="Zhou et al. 2017, Sec. 5.4, Fig. 9b",
)
class LeaveRecordingOut(Splitter):
    """Train on one recording session of every person, test on another.

    Within each subject the recordings (values of ``column``) are ordered
    (natural sort: ``r2`` before ``r10``); fold ``i`` tests every subject's
    ``i``-th recording and trains on their other recordings. With two
    recordings per person this is Zhou's scheme: train on one session, test
    on the other, then swap. A subject with fewer recordings than the others
    is left out (it could not be on both sides of every fold), with a note.
    """

    name = "leave-recording-out"
    Params = _RecordingParams

    def tests_each_capture_once(self) -> bool:
        return True

    def _split(self, meta: pd.DataFrame) -> list[Fold]:
        p = self.params
        _require_columns(meta, self.name, p.column, p.subject_column)
        subj = _str_col(meta, p.subject_column)
        rec = _str_col(meta, p.column)
        rank = np.full(len(meta), -1, dtype=np.int64)
        n_rec: dict[str, int] = {}
        for s in _sorted_values(subj):
            idx = np.flatnonzero(subj == s)
            recs = _sorted_values(rec[idx])
            n_rec[s] = len(recs)
            pos = {r: i for i, r in enumerate(recs)}
            rank[idx] = [pos[str(v)] for v in rec[idx]]
        most = max(n_rec.values())
        if most < 2:
            raise SplitError(f"scheme 'leave-recording-out': every subject has a single {p.column!r}; nothing to leave out")
        short = sorted((s for s, c in n_rec.items() if c < most), key=_natural_key)
        keep = ~np.isin(subj, short)
        if short:
            self.notes_.append(
                f"subject(s) {short} have fewer than {most} recordings ({p.column!r}) and are left out"
            )
        folds = []
        for i in range(most):
            test = keep & (rank == i)
            train = keep & (rank != i)
            name = f"test=recording{i + 1}"
            folds.append(Fold(name, np.flatnonzero(train), np.flatnonzero(test), group=name))
        return folds


# ----------------------------------------------------------------- person-independent
class _PartyParams(_Params):
    k: int = Field(default=4, ge=2)
    column: str = "subject"


@SPLITTERS.register(
    "person-independent",
    description="subjects dealt into k disjoint parties, each party tested once (Zhou 2017: 4 of 6)",
    paper="Zhou et al. 2017, Sec. 5.4, Fig. 9c",
)
class PersonIndependent(Splitter):
    """Subjects shuffled (seeded) and dealt into ``k`` disjoint parties.

    Fold ``i`` tests party ``i`` and trains on the other parties, so each
    subject is tested exactly once and never trained on in its own fold. Zhou
    et al. deal 24 people into 4 parties of 6; parties differ in size by at
    most one subject when ``k`` does not divide the number of subjects.
    """

    name = "person-independent"
    Params = _PartyParams

    def keeps_subjects_apart(self) -> bool:
        return self.params.column == "subject"

    def apart_column(self) -> str | None:
        return self.params.column

    def tests_each_capture_once(self) -> bool:
        return True

    def _split(self, meta: pd.DataFrame) -> list[Fold]:
        p = self.params
        _require_columns(meta, self.name, p.column)
        subj = _str_col(meta, p.column)
        values = _sorted_values(subj)
        if len(values) < p.k:
            raise SplitError(
                f"scheme 'person-independent': k={p.k} parties but only {len(values)} values of {p.column!r}; lower k"
            )
        rng = self._rng()
        order = [values[i] for i in rng.permutation(len(values))]
        parties = [sorted(order[i::p.k], key=_natural_key) for i in range(p.k)]
        if len(values) % p.k:
            self.notes_.append(f"{len(values)} subjects do not divide into {p.k} equal parties: sizes differ by one")
        folds = []
        for i, party in enumerate(parties):
            test = np.isin(subj, party)
            folds.append(
                Fold(f"party{i + 1}", np.flatnonzero(~test), np.flatnonzero(test), group=f"party{i + 1}",
                     notes=(f"party{i + 1} = {party}",))
            )
        return folds


# ----------------------------------------------------------------- transfer
class _TransferParams(_Params):
    column: str = "group"
    groups: list[str] | None = Field(default=None, min_length=2)
    both_directions: bool = True

    @model_validator(mode="before")
    @classmethod
    def _listify(cls, d: Any) -> Any:
        if isinstance(d, dict) and isinstance(d.get("groups"), list):
            d = {**d, "groups": [str(x) for x in d["groups"]]}
        return d


@SPLITTERS.register(
    "transfer",
    description="train on one group, test on another, both directions (Zhou 2017: A->B, B->A)",
    paper="Zhou et al. 2017, Sec. 5.4, Fig. 11",
)
class Transfer(Splitter):
    """Train on all captures of one group, test on all captures of another.

    ``groups`` (default: every value of ``column``, sorted) lists the groups;
    every ordered pair is a fold named ``A->B`` (train A, test B), or only the
    pairs in list order with ``both_directions: false``. Captures of other
    groups are not used. A subject found in two groups is noted (the groups
    are then not independent).
    """

    name = "transfer"
    Params = _TransferParams

    def keeps_subjects_apart(self) -> bool:
        return True

    def apart_column(self) -> str | None:
        return self.params.column

    def _split(self, meta: pd.DataFrame) -> list[Fold]:
        p = self.params
        _require_columns(meta, self.name, p.column)
        g = _str_col(meta, p.column)
        present = _sorted_values(v for v in g if v is not None)
        groups = p.groups if p.groups is not None else present
        unknown = [x for x in groups if x not in present]
        if unknown:
            raise SplitError(f"scheme 'transfer': unknown {p.column} value(s) {unknown}; the dataset has {present}")
        if len(groups) < 2:
            raise SplitError(f"scheme 'transfer' needs at least 2 values of {p.column!r}; the dataset has {present}")
        subj = _str_col(meta, "subject")
        for i, a in enumerate(groups):
            for b in groups[i + 1:]:
                shared = sorted(set(subj[g == a]) & set(subj[g == b]), key=_natural_key)
                if shared:
                    self.notes_.append(f"subject(s) {shared} are in both groups {a!r} and {b!r}")
        folds = []
        for i, a in enumerate(groups):
            for j, b in enumerate(groups):
                if a == b or (not p.both_directions and j < i):
                    continue
                name = f"{a}->{b}"
                folds.append(Fold(name, np.flatnonzero(g == a), np.flatnonzero(g == b), group=name))
        return folds


# ----------------------------------------------------------------- window-kfold
class _WindowKFoldParams(_KFoldParams):
    frames: int | None = Field(default=None, ge=1)
    seconds: float | None = Field(default=None, gt=0)
    hop: int | None = Field(default=None, ge=1)
    group_by: Literal["none", "capture", "subject"] = "none"

    @model_validator(mode="after")
    def _one_length(self) -> "_WindowKFoldParams":
        if (self.frames is None) == (self.seconds is None):
            raise ValueError("give exactly one of 'frames' or 'seconds' (the window length)")
        if self.grouped:
            raise ValueError("window-kfold groups with group_by: none, capture or subject (not grouped)")
        return self


@SPLITTERS.register(
    "window-kfold",
    description="k-fold over windows cut from the captures (leaky unless group_by: subject)",
    paper="Al-mashhadani et al. 2021, Sec. 2.3 and Table 3 (252 windows); Cang et al. 2015 (2-s windows)",
)
class WindowKFold(KFold):
    """Captures cut into windows of ``frames`` (or ``seconds``) every ``hop``
    frames (default: the window length, no overlap), each window a sample
    with its capture's labels; then k-fold over the windows.

    ``group_by: none`` (the default, as published evaluations did it) deals
    windows to folds at random, so windows of one capture, a few frames
    apart, are trained on and tested: **leaky**. ``capture`` keeps a
    capture's windows on one side but still shares subjects (leaky when the
    target is not the subject); ``subject`` keeps subjects apart (honest).
    The engine cuts the windows (:meth:`sample_windows`); the metadata then
    has ``source_capture`` and ``window`` columns. Accuracy is per window.
    """

    name = "window-kfold"
    Params = _WindowKFoldParams

    def _grouping(self) -> str | None:
        return {"none": None, "capture": "source_capture", "subject": "subject"}[self.params.group_by]

    def keeps_subjects_apart(self) -> bool:
        return self.params.group_by == "subject"

    def apart_column(self) -> str | None:
        return "subject" if self.params.group_by == "subject" else None

    def leakage(self) -> str:
        if self.params.group_by == "none":
            return WINDOWS_SHARED + ("" if self.target == "subject" else ", and captures of one subject")
        return "" if self.target == "subject" or self.params.group_by == "subject" else SUBJECTS_SHARED

    def sample_windows(self):
        p = self.params
        return (p.frames, p.seconds, p.hop)

    def _split(self, meta: pd.DataFrame) -> list[Fold]:
        _require_columns(meta, self.name, "source_capture")
        return super()._split(meta)


# ----------------------------------------------------------------- cross-dataset
#: the metadata column the engine adds to a cross-dataset evaluation's combined table
ORIGIN = "origin"
#: the column holding each capture's frame checksum (the engine adds it)
FRAMES_SHA = "frames_sha256"


class _CrossParams(_Params):
    test: dict[str, Any]
    adapters: list[dict[str, Any]] = Field(default_factory=list)

    @model_validator(mode="before")
    @classmethod
    def _test_ref(cls, d: Any) -> Any:
        return _named(d, "test")

    @model_validator(mode="after")
    def _check(self) -> "_CrossParams":
        if not isinstance(self.test.get("name"), str) or not self.test["name"]:
            raise ValueError("test must name the test dataset: test: {name: DATASET}")
        unknown = sorted(set(self.test) - {"name", "format", "filters", "exclude", "options"})
        if unknown:
            raise ValueError(f"test: unknown key(s) {unknown} (name, format, filters, exclude, options)")
        return self


@SPLITTERS.register(
    "cross-dataset",
    description="train on the protocol's dataset, test on another (same sensor, or declared adapters)",
    paper="",
)
class CrossDataset(Splitter):
    """One fold: train on every capture of the protocol's dataset (after its
    filters), test on every capture of ``test`` (a dataset reference with
    its own ``format``, ``filters``, ``exclude``, ``options``).

    The engine loads the test data, adapts it to the training sensor with
    the declared ``adapters`` (each recorded in the run's notes), refuses
    a sensor mismatch left after them, and stacks both with an ``origin``
    column (``train`` / ``test``) and each capture's frame checksum. A test
    capture whose frames are those of a training capture is refused: the
    same recording read twice would be tested on what was trained on.
    """

    name = "cross-dataset"
    Params = _CrossParams

    def keeps_subjects_apart(self) -> bool:
        return True

    def apart_column(self) -> str | None:
        return ORIGIN

    def tests_each_capture_once(self) -> bool:
        return True

    def _split(self, meta: pd.DataFrame) -> list[Fold]:
        _require_columns(meta, self.name, ORIGIN, FRAMES_SHA)
        origin = _str_col(meta, ORIGIN)
        train, test = np.flatnonzero(origin == "train"), np.flatnonzero(origin == "test")
        sha = _str_col(meta, FRAMES_SHA)
        seen = set(sha[train].tolist())
        again = [i for i in test.tolist() if sha[i] in seen]
        if again:
            ids = meta["capture_id"].astype(str).to_numpy()[again]
            raise SplitError(f"scheme 'cross-dataset': {len(again)} test capture(s) have the frames of a training "
                             f"capture ({', '.join(ids[:5].tolist())}{'...' if len(again) > 5 else ''}): the same "
                             f"recordings are in both datasets; filter them out of one")
        subj = _str_col(meta, "subject")
        shared = sorted(set(subj[train]) & set(subj[test]), key=_natural_key)
        if shared:
            self.notes_.append(f"subject name(s) {shared} are in both datasets (the same people, or a clash of names)")
        name = "train->test"
        return [Fold(name, train, test, group=name)]


# ----------------------------------------------------------------- early
class _EarlyParams(_Params):
    base: dict[str, Any]
    frames: list[int] | None = Field(default=None, min_length=1)
    seconds: list[float] | None = Field(default=None, min_length=1)
    crop_train: bool = False

    @model_validator(mode="before")
    @classmethod
    def _base(cls, d: Any) -> Any:
        return _named(d, "base")

    @model_validator(mode="after")
    def _check(self) -> "_EarlyParams":
        if (self.frames is None) == (self.seconds is None):
            raise ValueError("give exactly one of 'frames' (a list of frame counts) or 'seconds' (a list of durations)")
        if self.frames is not None and min(self.frames) < 1:
            raise ValueError("frames must be at least 1")
        if self.seconds is not None and min(self.seconds) <= 0:
            raise ValueError("seconds must be positive")
        name = self.base.get("name")
        if not isinstance(name, str):
            raise ValueError("base must name a scheme: base: {name: loso}")
        if name == "early":
            raise ValueError("the base of 'early' cannot be 'early'")
        return self


@SPLITTERS.register(
    "early",
    description="any scheme, test captures cut to their first N frames / S seconds, N swept (CNN real-time claim)",
    paper="Al-mashhadani et al. 2021, Sec. 2.3 and 4",
)
class Early(Splitter):
    """Recognition from the beginning of a gesture.

    ``base`` is another scheme (``{name: loso}`` or ``{name: kfold, k: 5}``);
    its folds are repeated once per value of ``frames`` (or ``seconds``,
    converted with the sensor's frame rate), with ``Fold.crop`` telling the
    engine to cut the test captures (and, with ``crop_train: true``, the
    training captures) to their first N frames. A capture shorter than N is
    used whole. Accuracy as a function of N measures how recognition grows
    with what has been seen.
    """

    name = "early"
    Params = _EarlyParams

    def __init__(self, target: str = "gesture", random_state: int | None = None, **params: Any):
        super().__init__(target=target, random_state=random_state, **params)
        base = dict(self.params.base)
        self.base = make_splitter(base.pop("name"), target=target, random_state=random_state, **base)

    def keeps_subjects_apart(self) -> bool:
        return self.base.keeps_subjects_apart()

    def tests_each_capture_once(self) -> bool:
        return False  # once per crop length

    def check_target(self) -> None:
        self.base.check_target()

    def leakage(self) -> str:
        return self.base.leakage()

    def sample_windows(self):
        return self.base.sample_windows()

    def _split(self, meta: pd.DataFrame) -> list[Fold]:
        base_folds = self.base.split(meta)
        self.notes_.extend(self.base.notes_)
        p = self.params
        crops = (
            [Crop(frames=int(n), train=p.crop_train) for n in p.frames]
            if p.frames is not None
            else [Crop(seconds=float(s), train=p.crop_train) for s in p.seconds]
        )
        return [replace(f, name=f"first{c.label}/{f.name}", crop=c) for c in crops for f in base_folds]


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

